// door_state_latency: end-to-end latency of the door-state nodelet, from a
// PointCloud2 published to the DoorStateArray answering it.
//
// Loads the sensor_msgs/PointCloud2 messages (and /tf_static) of one or more
// rosbags, then publishes them in turn at a fixed rate, each stamped with the
// time it is published, and subscribes to `doors`. An answer is matched to
// its cloud by stamp; its latency is the receipt time minus that stamp.
// Prints clouds published, answered and dropped, latency percentiles, the
// resident memory of a process (the nodelet manager) at start and end, and
// the nodelet's own counters from /diagnostics.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "door_state_recognition/DoorStateArray.h"

namespace {

const char* kUsage =
    "usage: door_state_latency --bag FILE.bag [--bag FILE2.bag ...] [options]\n"
    "\n"
    "Publishes the PointCloud2 messages of the bags in turn on `points` at\n"
    "--rate Hz for --seconds s, each stamped with the time it is published\n"
    "(wall clock: do not run under use_sim_time), and measures the time until\n"
    "the nodelet's DoorStateArray for that stamp arrives on `doors`.\n"
    "\n"
    "options:\n"
    "  --bag FILE       bag with sensor_msgs/PointCloud2 (any topic) and, with\n"
    "                   --tf, /tf_static (repeatable; clouds are played in turn)\n"
    "  --rate HZ        publishing rate (default 30)\n"
    "  --seconds S      how long to publish (default 30)\n"
    "  --drain S        after the last cloud, wait this long without an answer\n"
    "                   before counting (default 10)\n"
    "  --pid PID        process whose resident memory (VmRSS) is reported: the\n"
    "                   nodelet manager (default: none)\n"
    "  --tf             republish the bags' /tf_static (latched), for a nodelet\n"
    "                   with ~fixed_frame\n"
    "  --json FILE      also write the figures as JSON\n"
    "  --label TEXT     name of the case in the output\n"
    "  -h, --help       this text\n"
    "\n"
    "The nodelet subscribes to `points` only once `doors` has a subscriber; this\n"
    "tool waits for that, sends one warm-up cloud and waits for its answer\n"
    "(its memory is reported as 'warm'), then measures.\n"
    "Exit status: 0 when the measurement ran, 1 when the nodelet never answered,\n"
    "2 on bad arguments or unreadable bags.\n";

struct Options {
  std::vector<std::string> bags;
  double rate = 30, seconds = 30, drain = 10;
  long pid = 0;
  bool tf = false;
  std::string json, label;
};

Options parse(int argc, char** argv) {
  using dsr::tools::UsageError;
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "--bag") o.bags.push_back(dsr::tools::nextValue(argc, argv, i));
    else if (a == "--rate") o.rate = dsr::tools::toDouble(a, dsr::tools::nextValue(argc, argv, i));
    else if (a == "--seconds") o.seconds = dsr::tools::toDouble(a, dsr::tools::nextValue(argc, argv, i));
    else if (a == "--drain") o.drain = dsr::tools::toDouble(a, dsr::tools::nextValue(argc, argv, i));
    else if (a == "--pid") o.pid = static_cast<long>(dsr::tools::toInt(a, dsr::tools::nextValue(argc, argv, i)));
    else if (a == "--tf") o.tf = true;
    else if (a == "--json") o.json = dsr::tools::nextValue(argc, argv, i);
    else if (a == "--label") o.label = dsr::tools::nextValue(argc, argv, i);
    else throw UsageError("unknown argument '" + a + "'");
  }
  if (o.bags.empty()) throw UsageError("--bag is required");
  if (!(o.rate > 0 && o.rate <= 1000)) throw UsageError("--rate must be in (0, 1000]");
  if (!(o.seconds > 0)) throw UsageError("--seconds must be > 0");
  if (!(o.drain >= 0)) throw UsageError("--drain must be >= 0");
  if (o.pid < 0) throw UsageError("--pid must be a process id");
  return o;
}

// Resident memory of a process in MiB (VmRSS), or -1 when it cannot be read.
double rssMiB(long pid) {
  if (pid <= 0) return -1;
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5));
  return v[k];
}

struct Answers {
  std::mutex m;
  std::map<ros::Time, double> latency_ms;  // stamp -> receipt minus stamp
  std::map<ros::Time, std::size_t> doors;  // stamp -> doors in the answer
  ros::WallTime last_receipt;
  std::map<std::string, std::string> diag;  // the nodelet's last diagnostics
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "door_state_latency", ros::init_options::AnonymousName);
  std::vector<std::string> args;
  ros::removeROSArgs(argc, argv, args);
  std::vector<char*> cargs;
  for (auto& a : args) cargs.push_back(&a[0]);
  Options o;
  try {
    o = parse(static_cast<int>(cargs.size()), cargs.data());
  } catch (const dsr::tools::UsageError& e) {
    std::cerr << "door_state_latency: " << e.what() << "\n\n" << kUsage;
    return 2;
  }

  std::vector<sensor_msgs::PointCloud2> clouds;
  tf2_msgs::TFMessage statics;
  try {
    for (const auto& path : o.bags) {
      rosbag::Bag bag(path, rosbag::bagmode::Read);
      for (const rosbag::MessageInstance& mi : rosbag::View(bag)) {
        if (auto c = mi.instantiate<sensor_msgs::PointCloud2>()) clouds.push_back(*c);
        else if (mi.getTopic() == "/tf_static")
          if (auto t = mi.instantiate<tf2_msgs::TFMessage>())
            for (const auto& tr : t->transforms) statics.transforms.push_back(tr);
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "door_state_latency: cannot read bag: " << e.what() << "\n";
    return 2;
  }
  if (clouds.empty()) {
    std::cerr << "door_state_latency: no sensor_msgs/PointCloud2 in the bags\n";
    return 2;
  }

  ros::NodeHandle nh;
  Answers rx;
  ros::Subscriber sub = nh.subscribe<door_state_recognition::DoorStateArray>(
      "doors", 100, [&](const door_state_recognition::DoorStateArrayConstPtr& m) {
        const ros::Time now = ros::Time::now();
        std::lock_guard<std::mutex> l(rx.m);
        rx.latency_ms[m->header.stamp] = (now - m->header.stamp).toSec() * 1e3;
        rx.doors[m->header.stamp] = m->doors.size();
        rx.last_receipt = ros::WallTime::now();
      });
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& a) {
        std::lock_guard<std::mutex> l(rx.m);
        for (const auto& st : a->status)
          if (st.name.find("door_state") != std::string::npos)
            for (const auto& kv : st.values) rx.diag[kv.key] = kv.value;
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points", 2);
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, true);
  if (o.tf) tf_pub.publish(statics);
  ros::AsyncSpinner spinner(2);
  spinner.start();

  const std::string name = o.label.empty() ? o.bags.front() : o.label;
  auto waitFor = [](const std::function<bool()>& cond, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < end) {
      if (cond()) return true;
      ros::WallDuration(0.01).sleep();
    }
    return cond();
  };
  const double rss_start = rssMiB(o.pid);
  if (!waitFor([&] { return pub.getNumSubscribers() > 0; }, 30.0)) {
    std::cerr << "door_state_latency: nobody subscribed to " << pub.getTopic() << " within 30 s\n";
    return 1;
  }
  ros::WallDuration(0.5).sleep();  // the tf listener may connect a moment later
  // Warm-up: one cloud, answered, before measuring.
  {
    sensor_msgs::PointCloud2& c = clouds.front();
    c.header.stamp = ros::Time::now();
    const ros::Time stamp = c.header.stamp;
    pub.publish(c);  // by reference: serialized now, the message may be reused
    if (!waitFor([&] { std::lock_guard<std::mutex> l(rx.m); return rx.latency_ms.count(stamp) > 0; }, 120.0)) {
      std::cerr << "door_state_latency: the warm-up cloud was never answered\n";
      return 1;
    }
    std::lock_guard<std::mutex> l(rx.m);
    rx.latency_ms.clear();
  }
  const double rss_warm = rssMiB(o.pid);
  double rss_max = rss_warm;

  std::set<ros::Time> published;
  ros::WallRate rate(o.rate);
  const ros::WallTime start = ros::WallTime::now();
  const ros::WallTime end = start + ros::WallDuration(o.seconds);
  ros::WallTime next_rss = start;
  std::vector<double> rss_samples;  // one a second
  std::size_t k = 0;
  while (ros::ok() && ros::WallTime::now() < end) {
    sensor_msgs::PointCloud2& c = clouds[k++ % clouds.size()];
    c.header.stamp = ros::Time::now();
    c.header.seq = static_cast<std::uint32_t>(k);
    published.insert(c.header.stamp);
    pub.publish(c);
    if (ros::WallTime::now() >= next_rss) {
      const double r = rssMiB(o.pid);
      rss_max = std::max(rss_max, r);
      rss_samples.push_back(r);
      next_rss += ros::WallDuration(1.0);
    }
    rate.sleep();
  }
  const double elapsed = (ros::WallTime::now() - start).toSec();
  // Drain: until no answer came for --drain seconds.
  {
    std::lock_guard<std::mutex> l(rx.m);
    rx.last_receipt = ros::WallTime::now();
  }
  waitFor([&] { std::lock_guard<std::mutex> l(rx.m); return (ros::WallTime::now() - rx.last_receipt).toSec() > o.drain; },
          o.drain + 600.0);
  ros::WallDuration(1.5).sleep();  // one more diagnostics message
  const double rss_end = rssMiB(o.pid);
  rss_max = std::max(rss_max, rss_end);

  std::vector<double> lat;
  std::size_t answered = 0;
  std::size_t doors_min = 0, doors_max = 0;  // doors per answer
  std::map<std::string, std::string> diag;
  {
    std::lock_guard<std::mutex> l(rx.m);
    for (const auto& [stamp, ms] : rx.latency_ms)
      if (published.count(stamp)) {
        const std::size_t nd = rx.doors[stamp];
        doors_min = answered ? std::min(doors_min, nd) : nd;
        doors_max = answered ? std::max(doors_max, nd) : nd;
        ++answered;
        lat.push_back(ms);
      }
    diag = rx.diag;
  }
  const std::size_t n = published.size();
  const std::size_t points = static_cast<std::size_t>(clouds.front().width) * clouds.front().height;
  char buf[2048];
  std::snprintf(buf, sizeof buf,
                "%s: %zu clouds (%zu points%s) published at %.1f Hz for %.1f s: %zu answered, %zu dropped "
                "(%.0f %%), answers at %.2f Hz\n"
                "  latency stamp->DoorStateArray ms: p50 %.0f  p90 %.0f  p99 %.0f  max %.0f;  doors per answer %zu-%zu\n"
                "  manager RSS MiB: start %.1f  warm %.1f  end %.1f  max %.1f  (end - warm %+.1f)\n",
                name.c_str(), n, points, clouds.size() > 1 ? ", first bag cloud" : "", n / elapsed, elapsed, answered,
                n - answered, n ? 100.0 * (n - answered) / n : 0.0, answered / elapsed, quantile(lat, 0.5),
                quantile(lat, 0.9), quantile(lat, 0.99), quantile(lat, 1.0), doors_min, doors_max, rss_start, rss_warm, rss_end, rss_max,
                rss_end - rss_warm);
  std::cout << buf;
  if (o.pid > 0 && rss_samples.size() >= 10) {
    std::cout << "  manager RSS MiB at each tenth of the run:";
    for (int t = 0; t <= 10; ++t)
      std::printf(" %.0f", rss_samples[std::min(rss_samples.size() - 1, t * (rss_samples.size() - 1) / 10)]);
    std::cout << std::endl;
  }
  auto d = [&](const char* key) { return diag.count(key) ? diag.at(key) : std::string("?"); };
  std::cout << "  nodelet diagnostics: received " << d("clouds received") << ", processed " << d("clouds processed")
            << ", dropped stale " << d("clouds dropped (stale)") << ", no tf " << d("clouds dropped (no tf)")
            << ", processing p50 " << d("processing time p50 (ms)") << " ms, max " << d("processing time max (ms)")
            << " ms" << std::endl;
  if (!o.json.empty()) {
    std::ofstream js(o.json);
    js.precision(6);
    js << "{\"label\": \"" << name << "\", \"points\": " << points << ", \"rate_hz\": " << o.rate
       << ", \"seconds\": " << elapsed << ", \"published\": " << n << ", \"answered\": " << answered
       << ", \"dropped\": " << (n - answered) << ", \"latency_ms\": {\"p50\": " << quantile(lat, 0.5)
       << ", \"p90\": " << quantile(lat, 0.9) << ", \"p99\": " << quantile(lat, 0.99) << ", \"max\": "
       << quantile(lat, 1.0) << "}, \"doors_per_answer\": {\"min\": " << doors_min << ", \"max\": " << doors_max
       << "}, \"rss_mib\": {\"start\": " << rss_start << ", \"warm\": " << rss_warm
       << ", \"end\": " << rss_end << ", \"max\": " << rss_max << ", \"per_second\": [";
    for (std::size_t i = 0; i < rss_samples.size(); ++i) js << (i ? ", " : "") << rss_samples[i];
    js << "]}, \"latency_ms_in_stamp_order\": [";
    for (std::size_t i = 0; i < lat.size(); ++i) js << (i ? ", " : "") << lat[i];
    js << "], \"nodelet\": {\"received\": \""
       << d("clouds received") << "\", \"processed\": \"" << d("clouds processed") << "\", \"dropped_stale\": \""
       << d("clouds dropped (stale)") << "\"}}\n";
  }
  spinner.stop();
  sub.shutdown();
  diag_sub.shutdown();
  return answered > 0 ? 0 : 1;
}
