// roscpp side of tests/benchmarks/bench_transport.py; same contract as wire_bench_rospy.py.
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <cstdio>
#include <string>
#include <sys/time.h>
#include <vector>

static std::vector<double> lat_ms, arrivals;

static double wall() {
  struct timeval tv;
  gettimeofday(&tv, nullptr);
  return tv.tv_sec + tv.tv_usec * 1e-6;
}

static void cb(const sensor_msgs::Image::ConstPtr& m) {
  double now = wall();
  if (m->header.frame_id == "lat") lat_ms.push_back((now - m->header.stamp.toSec()) * 1000.0);
  else arrivals.push_back(now);
}

int main(int argc, char** argv) {
  if (argc < 5) return 2;
  std::string mode = argv[1], topic = argv[2];
  int nlat = atoi(argv[3]), nthr = atoi(argv[4]);
  ros::init(argc, argv, "wire_bench_roscpp_" + mode, ros::init_options::NoSigintHandler);
  ros::NodeHandle nh;
  double deadline = wall() + 120;
  if (mode == "sub") {
    ros::Subscriber sub = nh.subscribe<sensor_msgs::Image>(topic, 1000, cb);
    printf("READY\n");
    fflush(stdout);
    while (ros::ok() && ((int)lat_ms.size() < nlat || (int)arrivals.size() < nthr) && wall() < deadline) {
      ros::spinOnce();
      ros::WallDuration(0.0005).sleep();
    }
    double span = arrivals.size() > 1 ? arrivals.back() - arrivals.front() : -1;
    printf("{\"lat_ms\": [");
    for (size_t i = 0; i < lat_ms.size(); ++i) printf("%s%f", i ? ", " : "", lat_ms[i]);
    printf("], \"thr_frames\": %zu, \"thr_seconds\": %f}\n", arrivals.size(), span);
    fflush(stdout);
  } else {
    ros::Publisher pub = nh.advertise<sensor_msgs::Image>(topic, nthr + 10);
    printf("READY\n");
    fflush(stdout);
    while (ros::ok() && pub.getNumSubscribers() == 0 && wall() < deadline) ros::WallDuration(0.01).sleep();
    ros::WallDuration(0.5).sleep();
    sensor_msgs::Image img;
    img.height = 480;
    img.width = 640;
    img.encoding = "rgba8";
    img.step = 2560;
    img.data.resize(640 * 480 * 4);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = (uint8_t)(i & 0xFF);
    const char* phases[2] = {"lat", "thr"};
    int counts[2] = {nlat, nthr};
    for (int p = 0; p < 2; ++p) {
      img.header.frame_id = phases[p];
      for (int k = 0; k < counts[p]; ++k) {
        img.header.stamp = ros::Time(wall());
        pub.publish(img);
        if (p == 0) ros::WallDuration(0.1).sleep();
      }
    }
    ros::WallDuration(5.0).sleep();
  }
  ros::shutdown();
  return 0;
}
