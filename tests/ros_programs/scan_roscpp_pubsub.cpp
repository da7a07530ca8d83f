// roscpp publisher and subscriber of sensor_msgs/LaserScan for the any-type component's tests.
//   scan_roscpp_pubsub IN_TOPIC OUT_TOPIC INFILE EXPECT OUTFILE [TIMEOUT]
// Reads scans from INFILE (each: uint32 beam count + that many float32 ranges), waits until
// the component subscribes to IN_TOPIC and publishes OUT_TOPIC, publishes each scan with the
// real sensor_msgs::LaserScan class (header.stamp = 100 + k s and k ns, frame_id "laser",
// angle_min -1.5, angle_increment 0.01, range_max 30, intensities {k, 0.5}), then writes every
// message received on OUT_TOPIC, re-serialized by roscpp (uint32 length + bytes), to OUTFILE;
// exits after EXPECT messages or TIMEOUT seconds. Prints DONE at the end.
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

static FILE* out = nullptr;
static int received = 0;

static void on_scan(const sensor_msgs::LaserScan::ConstPtr& m) {
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
  if (argc < 6) {
    fprintf(stderr, "usage: scan_roscpp_pubsub IN_TOPIC OUT_TOPIC INFILE EXPECT OUTFILE [TIMEOUT]\n");
    return 2;
  }
  ros::init(argc, argv, "scan_roscpp_pubsub", ros::init_options::NoSigintHandler);
  std::vector<std::vector<float>> scans;
  FILE* in = fopen(argv[3], "rb");
  if (!in) {
    fprintf(stderr, "cannot open %s\n", argv[3]);
    return 2;
  }
  uint32_t n = 0;
  while (fread(&n, 4, 1, in) == 1 && n <= 100000) {
    std::vector<float> ranges(n);
    if (fread(ranges.data(), 4, n, in) != n) break;
    scans.push_back(ranges);
  }
  fclose(in);
  int expect = atoi(argv[4]);
  out = fopen(argv[5], "wb");
  double timeout = argc > 6 ? atof(argv[6]) : 30.0;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe(argv[2], 100, on_scan);
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>(argv[1], 100);
  ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && (pub.getNumSubscribers() < 1 || sub.getNumPublishers() < 1) &&
         ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  for (size_t k = 0; k < scans.size(); ++k) {
    sensor_msgs::LaserScan m;
    m.header.stamp = ros::Time(100 + k, k);
    m.header.frame_id = "laser";
    m.angle_min = -1.5f;
    m.angle_max = 1.5f;
    m.angle_increment = 0.01f;
    m.range_min = 0.05f;
    m.range_max = 30.0f;
    m.ranges = scans[k];
    m.intensities = {static_cast<float>(k), 0.5f};
    pub.publish(m);
  }
  while (ros::ok() && received < expect && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  fclose(out);
  printf("DONE %d\n", received);
  fflush(stdout);
  return 0;
}
