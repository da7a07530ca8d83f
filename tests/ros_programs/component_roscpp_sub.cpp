// roscpp subscriber of the FPGA component's real-ROS tests.
//   component_roscpp_sub TOPIC COUNT OUTFILE [TIMEOUT]
// Subscribes with the real sensor_msgs::Image class, writes every message received,
// re-serialized by roscpp (uint32 length + bytes), to OUTFILE; exits after COUNT messages or
// TIMEOUT seconds. Prints READY once subscribed, DONE at the end.
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

static FILE* out = nullptr;
static int received = 0;

static void on_image(const sensor_msgs::Image::ConstPtr& m) {
  uint32_t n = ros::serialization::serializationLength(*m);
  std::vector<uint8_t> buf(n);
  ros::serialization::OStream s(buf.data(), n);
  ros::serialization::serialize(s, *m);
  fwrite(&n, 4, 1, out);
  fwrite(buf.data(), 1, n, out);
  fflush(out);
  ++received;
}

int main(int argc, char** argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: component_roscpp_sub TOPIC COUNT OUTFILE [TIMEOUT]\n");
    return 2;
  }
  ros::init(argc, argv, "component_roscpp_sub", ros::init_options::NoSigintHandler);
  const char* topic = argv[1];
  int count = atoi(argv[2]);
  out = fopen(argv[3], "wb");
  double timeout = argc > 4 ? atof(argv[4]) : 60.0;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe(topic, 100, on_image);
  printf("READY\n");
  fflush(stdout);
  ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && received < count && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  fclose(out);
  printf("DONE\n");
  fflush(stdout);
  return 0;
}
