// roscpp side of the lab's TCPROS interop tests.
//   wire_roscpp_node sub TYPE TOPIC COUNT OUTFILE [TIMEOUT]
//   wire_roscpp_node pub TYPE TOPIC COUNT OUTFILE [TIMEOUT [WIDTH HEIGHT]]
// Same contract as wire_rospy_node.py: the subscriber writes each received message
// re-serialized by roscpp (uint32 length + bytes); the publisher writes what it sent.
// Image frames are rgba8, 640x480 unless WIDTH HEIGHT are given.
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Int32.h>
#include <std_msgs/String.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

static FILE* out = nullptr;
static int received = 0;
static uint32_t image_width = 640, image_height = 480;

template <class M>
static void write_msg(const M& m) {
  uint32_t n = ros::serialization::serializationLength(m);
  std::vector<uint8_t> buf(n);
  ros::serialization::OStream s(buf.data(), n);
  ros::serialization::serialize(s, m);
  fwrite(&n, 4, 1, out);
  fwrite(buf.data(), 1, n, out);
  fflush(out);
}

template <class M>
static void on_msg(const typename M::ConstPtr& m) {
  write_msg(*m);
  ++received;
}

static std_msgs::String make_string(int k) {
  std_msgs::String m;
  m.data = "msg " + std::to_string(k) + " \xc3\xa9";
  return m;
}

static std_msgs::Int32 make_int(int k) {
  std_msgs::Int32 m;
  m.data = k;
  return m;
}

static sensor_msgs::Image make_image(int k) {
  sensor_msgs::Image m;
  m.header.seq = k;
  m.header.frame_id = "roscpp";
  m.header.stamp = ros::Time(1000 + k, 17);
  m.height = image_height;
  m.width = image_width;
  m.encoding = "rgba8";
  m.is_bigendian = 0;
  m.step = image_width * 4;
  m.data.resize((size_t)image_width * image_height * 4);
  for (size_t i = 0; i < m.data.size(); ++i) m.data[i] = (uint8_t)((i * 7 + k * 13) & 0xFF);
  return m;
}

template <class M, class Make>
static int run(ros::NodeHandle& nh, const std::string& mode, const std::string& topic, int count,
               double timeout, Make make) {
  ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  if (mode == "sub") {
    ros::Subscriber sub = nh.subscribe<M>(topic, 100, &on_msg<M>);
    printf("READY\n");
    fflush(stdout);
    while (ros::ok() && received < count && ros::WallTime::now() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.005).sleep();
    }
  } else {
    ros::Publisher pub = nh.advertise<M>(topic, 100);
    printf("READY\n");
    fflush(stdout);
    while (ros::ok() && pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline)
      ros::WallDuration(0.01).sleep();
    ros::WallDuration(0.2).sleep();
    for (int k = 0; ros::ok() && (count == 0 || k < count) && ros::WallTime::now() < deadline; ++k) {
      M m = make(k);
      pub.publish(m);
      write_msg(m);
      ros::spinOnce();
      ros::WallDuration(0.05).sleep();
    }
    ros::WallDuration(1.0).sleep();
  }
  printf("DONE\n");
  fflush(stdout);
  return 0;
}

int main(int argc, char** argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: %s sub|pub String|Int32|Image TOPIC COUNT OUTFILE [TIMEOUT [WIDTH HEIGHT]]\n", argv[0]);
    return 2;
  }
  std::string mode = argv[1], kind = argv[2], topic = argv[3];
  int count = atoi(argv[4]);
  double timeout = argc > 6 ? atof(argv[6]) : 30.0;
  if (argc > 8) {
    image_width = (uint32_t)atoi(argv[7]);
    image_height = (uint32_t)atoi(argv[8]);
  }
  ros::init(argc, argv, "wire_roscpp_" + mode, ros::init_options::NoSigintHandler);
  ros::NodeHandle nh;
  out = fopen(argv[5], "wb");
  if (!out) return 3;
  ros::AsyncSpinner spinner(1);
  int rc;
  if (kind == "String") rc = run<std_msgs::String>(nh, mode, topic, count, timeout, make_string);
  else if (kind == "Int32") rc = run<std_msgs::Int32>(nh, mode, topic, count, timeout, make_int);
  else rc = run<sensor_msgs::Image>(nh, mode, topic, count, timeout, make_image);
  fclose(out);
  ros::shutdown();
  return rc;
}
