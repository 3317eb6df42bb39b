// door_scene_sim: simulates a scan of a room with doors and writes the cloud
// (PCD/PLY), its ground truth (JSON) and optionally a rosbag; or, with
// --drive, a robot's drive through the room as a rosbag and its truth.
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <string>

#include "bag_writer.hpp"
#include "cli_args.hpp"
#include "door_state_recognition/sim/drive.hpp"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/registered.hpp"
#include "door_state_recognition/sim/lidar.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

namespace {

const char* kUsage = R"(usage: door_scene_sim --out PREFIX [options]

Simulates a scan of a room with doors, deterministically for a seed, and
writes PREFIX.pcd (binary), PREFIX.ply (binary), PREFIX.json (ground truth,
coordinates in the cloud's own frame) and PREFIX.bag (sensor_msgs/PointCloud2
on /points plus /tf_static from the fixed frame to the cloud frame).

options:
  --out PREFIX           output path without extension (required)
  --formats LIST         comma list of pcd,ply,json,bag (default pcd,json)
  --scene NAME           random (default), paper_livingroom, paper_house, paper_multidoor
  --seed N               random seed (default 1)
  --sensor NAME          tls: terrestrial laser scanner (default); rgbd: one 640x480
                         RGB-D frame; lidar16|lidar32|lidar64|lidar128: one sweep of a
                         rotating LiDAR on a mast 0.4-1.2 m high (organized cloud,
                         rows = beams from the top, NaN where no return; frame
                         "lidar", x forward, z up)
  --points N             TLS rays over all viewpoints (default 400000)
  --viewpoints K         TLS scan positions inside the room (default 1); with more
                         than one position in all (K > 1 or --beyond-doors) and
                         pcd, each position's scan is also written to
                         PREFIX.stationI.pcd (same frame, VIEWPOINT = the position)
  --no-handles           leaves without their lever handles
  --beyond-doors         TLS: one more scan position in the room behind each
                         door, 1.2-2 m beyond it (as a surveyor walks through;
                         the rays still total --points)
  --noise M              TLS/LiDAR range noise sigma in metres (default TLS 0.005,
                         LiDAR 0.02 (16, 32 beams) or 0.015 (64, 128));
                         RGB-D: 0 switches the depth noise model off
  --dropout P            probability of a lost return (default TLS 0, RGB-D 0.02, LiDAR 0.01)
  --zeros                LiDAR: (0, 0, 0) instead of NaN where no return
  --mount-height M       LiDAR head (0.4-1.2 m) or, with --drive, camera (0.3-1.5 m)
                         height above the floor (default: drawn by the seed)
  --depth-model M        RGB-D depth error of a camera family (src/sim/depth_models.cpp):
                         default (Kinect-like axial noise, as before), structured
                         (Kinect v1-like: 1/8 px disparity steps, projector shadows,
                         holes on dark surfaces), tof (flying pixels, multipath in
                         corners, range to 10 m), stereo (D435-like: RMS ~ z^2,
                         speckle, holes on dark/glossy leaves)
  --resolution WxH       RGB-D image 640x480 (default) or 320x240 (intrinsics scaled)
  --camera-height M      RGB-D camera height above the floor, 0.1-3 m (default: drawn 0.9-1.5)
  --pitch DEG            RGB-D optical axis above the horizontal, -60..60 (default: at the
                         door and below the ceiling); with it the ceiling may be in view
  --roll DEG             RGB-D roll, -30..30 (default: drawn within 3 deg)
  --door-distance M      RGB-D camera this far in front of the door (default: drawn 1.6-3.5)
  --robot-camera         RGB-D pose as robots carry cameras, drawn by the seed: height
                         0.3-1.6 m, pitch -20..+10 deg, roll within 5 deg, 1-6 m from the
                         door; the options above win
  --doors MIN:MAX        number of doors of a random room (default 1:3)
  --angle DEG            opening angle of every door, 0..180 (default: random)
  --max-angle DEG        largest random opening angle (default 130)
  --decoys MIN:MAX       tall cupboards/wardrobes of a random room (default 1:2)
  --merge                TLS: PREFIX.pcd is every station's points in ONE cloud in
                         the --frame frame, VIEWPOINT 0 0 0 as registered exports
                         write it, overlaps as the stations give them; truth and
                         station files in that frame
  --frame map|station0   frame of --merge/--mesh-like (default map: z up, floor at
                         z = 0, origin on the floor 0.5-2 m beyond the outer corner
                         of walls 3 and 0, yaw by the seed: no scanner stood at
                         0 0 0); station0: the first station's frame
  --frame-offset X,Y,Z   the written cloud (and its VIEWPOINT, the truth, the
                         station files) moved by this offset (metres) in its own
                         frame: the same scan in a frame not at the sensor, whose
                         voxel grid cuts it elsewhere (not with --zeros or bag)
  --mesh-like N          TLS: the merged cloud resampled as about N vertices of a
                         reconstructed mesh (Poisson-disk spacing, holes, rounded
                         corners, 2 mm noise); implies --merge; no station files
  --voxel-map RES        TLS: the merged cloud as an occupancy map exports it (OctoMap,
                         a voxel SLAM map): the centre of every occupied RES-metre
                         voxel; implies --merge; no station files
  --clutter              random room: desks with chairs, bookcases, shelves and
                         cupboards against the walls beside doors (0-30 cm from
                         the casing) and between them, a window-like gap with a
                         low cabinet under it, a chair; never in a leaf's swing
  --partition            random room: a bathroom in a corner (two interior walls,
                         walls 4 and 5; its door is in the truth)
  --corridor             random room: a corridor 6-12 m x 1.5-2.2 m, its doors
                         (2 to MAX+2 of --doors) along the two long walls
  --varied-doors         random room: door joinery varied per room: a third with
                         no casing (plain openings), the rest casing 4-10 cm wide
                         and 0.8-3 cm deep; leaves 3-5.5 cm thick
  --bag-count N          clouds in the bag (default 3), --bag-rate HZ (default 1)
  --fixed-frame NAME     parent frame of the tf in the bag (default map)

drive (--drive; --sensor lidar16|lidar32|lidar64|lidar128|rgbd, default lidar64;
--formats bag,json,pcd, default bag,json):
  --drive                a robot drives through the room past every door (1-3 m
                         from it) and, when one is open (>= 75 deg) and passable,
                         ends 1.8 m beyond it in the room behind. PREFIX.bag holds
                         /points (sensor_msgs/PointCloud2, sensor frame "lidar" or
                         "camera_depth_optical_frame"), /tf (map -> base_link at
                         each cloud's stamp), /tf_static (base_link -> sensor frame,
                         latched), /clock (every 10 ms; play without --clock);
                         stamps from 1000 s. PREFIX.json: the truth in map, doors
                         in their final state, changes, path (see sim/drive.hpp);
                         pcd: every cloud as PREFIX.frameNNNNN.pcd (sensor frame)
                         with its truth in that frame in PREFIX.frameNNNNN.json
  --drive-seconds S      duration (default: the path at 0.5 m/s, turns at 60 deg/s)
  --rate HZ              clouds per second (default 10 LiDAR, 15 RGB-D)
  --toggle-door K:ANGLE@T  door K is at ANGLE deg from T s after the start on
                         (repeatable)
  --pass-distance M      pass the doors this far from their wall, 1-3 m (default 1.4)
  --no-through-door      stay in the room
  --lidar-motion         LiDAR: the robot moves during each sweep (1 / rate long,
                         ending at the cloud's stamp); clouds not deskewed
  --camera-pitch DEG     RGB-D pitch, -20..10, negative down (default: drawn)
  --rgbd-size WxH        RGB-D image, 320x240 (default for a drive) or 640x480
  --quiet                no summary on stderr
  -h, --help             this text
)";

using dsr::tools::toDouble;
using dsr::tools::toInt;
using dsr::tools::UsageError;

std::pair<int, int> toRange(const std::string& flag, const std::string& v) {
  const auto colon = v.find(':');
  if (colon == std::string::npos) {
    const int n = static_cast<int>(toInt(flag, v));
    return {n, n};
  }
  const int a = static_cast<int>(toInt(flag, v.substr(0, colon))), b = static_cast<int>(toInt(flag, v.substr(colon + 1)));
  if (a < 0 || b < a || b > 12) throw UsageError(flag + " needs MIN:MAX with 0 <= MIN <= MAX <= 12");
  return {a, b};
}

}  // namespace

int main(int argc, char** argv) {
  using namespace dsr;
  std::string out, scene_name = "random", sensor = "tls", formats = "pcd,json";
  std::uint64_t seed = 1;
  sim::TlsOptions tls;
  sim::RgbdOptions rgbd;
  sim::RandomSceneOptions random_options;
  tools::BagOptions bag;
  double angle = -1;
  bool quiet = false;
  bool handles = true;
  bool merge = false;
  std::string merged_frame;
  Eigen::Vector3d frame_offset = Eigen::Vector3d::Zero();
  long long mesh_vertices = 0;
  double voxel_map = 0;
  bool drive = false, zeros = false, sensor_given = false, formats_given = false;
  std::optional<double> mount_height, lidar_noise, lidar_dropout;
  sim::DriveOptions drive_options;
  std::string rgbd_size;
  std::string drive_flag;  // a drive-only flag given
  bool depth_model_given = false, rgbd_option = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&] { return dsr::tools::nextValue(argc, argv, i); };
      if (a == "--drive-seconds" || a == "--rate" || a == "--toggle-door" || a == "--pass-distance" ||
          a == "--no-through-door" || a == "--camera-pitch" || a == "--rgbd-size" || a == "--lidar-motion")
        drive_flag = a;
      if (a == "-h" || a == "--help") {
        std::cout << kUsage;
        return 0;
      } else if (a == "--out") out = value();
      else if (a == "--formats") {
        formats = value();
        formats_given = true;
      }
      else if (a == "--scene") scene_name = value();
      else if (a == "--seed") {
        const long long s = toInt(a, value());
        if (s < 0) throw UsageError("--seed must be >= 0");
        seed = static_cast<std::uint64_t>(s);
      } else if (a == "--sensor") {
        sensor = value();
        sensor_given = true;
      }
      else if (a == "--points") {
        const long long n = toInt(a, value());
        if (n < 100 || n > 100000000) throw UsageError("--points must lie in [100, 1e8]");
        tls.points = static_cast<std::size_t>(n);
      } else if (a == "--viewpoints") tls.viewpoints = static_cast<int>(toInt(a, value()));
      else if (a == "--beyond-doors") tls.beyond_doors = true;
      else if (a == "--no-handles") handles = false;
      else if (a == "--noise") {
        const double m = toDouble(a, value());
        if (m < 0 || m >= 1) throw UsageError("--noise must lie in [0, 1) m");
        tls.range_sigma = m;
        rgbd.noise = m > 0;
        lidar_noise = m;
      } else if (a == "--dropout") {
        const double p = toDouble(a, value());
        if (p < 0 || p >= 1) throw UsageError("--dropout must lie in [0, 1)");
        tls.dropout = rgbd.dropout = p;
        lidar_dropout = p;
      } else if (a == "--depth-model") {
        const std::string m = value();
        try {
          rgbd.depth_model = sim::parseDepthModel(m);
        } catch (const std::invalid_argument& e) {
          throw UsageError(std::string("--depth-model: ") + e.what());
        }
        depth_model_given = true;
      } else if (a == "--resolution") {
        const std::string r = value();
        if (r != "640x480" && r != "320x240") throw UsageError("--resolution must be 640x480 or 320x240");
        if (r == "320x240") rgbd.resize(320, 240);
        rgbd_option = true;
      } else if (a == "--camera-height") {
        rgbd.camera_height = toDouble(a, value());
        if (*rgbd.camera_height < 0.1 || *rgbd.camera_height > 3) throw UsageError("--camera-height must lie in [0.1, 3] m");
        rgbd_option = true;
      } else if (a == "--pitch") {
        rgbd.pitch_deg = toDouble(a, value());
        if (std::abs(*rgbd.pitch_deg) > 60) throw UsageError("--pitch must lie in [-60, 60] deg");
        rgbd_option = true;
      } else if (a == "--roll") {
        rgbd.roll_deg = toDouble(a, value());
        if (std::abs(*rgbd.roll_deg) > 30) throw UsageError("--roll must lie in [-30, 30] deg");
        rgbd_option = true;
      } else if (a == "--door-distance") {
        rgbd.door_distance = toDouble(a, value());
        if (*rgbd.door_distance < 0.5 || *rgbd.door_distance > 50) throw UsageError("--door-distance must lie in [0.5, 50] m");
        rgbd_option = true;
      } else if (a == "--robot-camera") {
        rgbd.robot_camera = true;
        rgbd_option = true;
      } else if (a == "--doors") std::tie(random_options.min_doors, random_options.max_doors) = toRange(a, value());
      else if (a == "--decoys") std::tie(random_options.min_decoys, random_options.max_decoys) = toRange(a, value());
      else if (a == "--angle") {
        angle = toDouble(a, value());
        if (angle < 0 || angle > 180) throw UsageError("--angle must lie in [0, 180] deg");
      } else if (a == "--max-angle") {
        random_options.max_angle_deg = toDouble(a, value());
        if (random_options.max_angle_deg < 0 || random_options.max_angle_deg > 180) throw UsageError("--max-angle must lie in [0, 180] deg");
      } else if (a == "--bag-count") bag.count = static_cast<int>(toInt(a, value()));
      else if (a == "--bag-rate") bag.rate_hz = toDouble(a, value());
      else if (a == "--fixed-frame") bag.fixed_frame = value();
      else if (a == "--quiet") quiet = true;
      else if (a == "--merge") merge = true;
      else if (a == "--frame") merged_frame = value();
      else if (a == "--frame-offset") {
        const std::string v = value();
        double xyz[3];
        dsr::tools::toXYZ(a, v, "X,Y,Z", xyz);
        frame_offset = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        if (frame_offset.cwiseAbs().maxCoeff() > 1e4)
          throw UsageError("--frame-offset needs X,Y,Z (finite, within 1e4 m), got '" + v + "'");
      }
      else if (a == "--mesh-like") {
        mesh_vertices = toInt(a, value());
        if (mesh_vertices < 100 || mesh_vertices > 10000000) throw UsageError("--mesh-like must lie in [100, 1e7]");
        merge = true;
      } else if (a == "--voxel-map") {
        voxel_map = toDouble(a, value());
        if (!(voxel_map >= 0.01 && voxel_map <= 0.5)) throw UsageError("--voxel-map must lie in [0.01, 0.5] m");
        merge = true;
      } else if (a == "--clutter") random_options.clutter = true;
      else if (a == "--partition") random_options.partition = true;
      else if (a == "--corridor") random_options.corridor = true;
      else if (a == "--varied-doors") random_options.varied_doors = true;
      else if (a == "--zeros") zeros = true;
      else if (a == "--mount-height") mount_height = toDouble(a, value());
      else if (a == "--drive") drive = true;
      else if (a == "--drive-seconds") {
        drive_options.seconds = toDouble(a, value());
        if (!(drive_options.seconds > 0 && drive_options.seconds <= 3600)) throw UsageError("--drive-seconds must lie in (0, 3600]");
      } else if (a == "--rate") {
        drive_options.rate_hz = toDouble(a, value());
        if (!(drive_options.rate_hz > 0 && drive_options.rate_hz <= 100)) throw UsageError("--rate must lie in (0, 100] Hz");
      } else if (a == "--toggle-door") {
        const dsr::tools::Toggle c = dsr::tools::toToggle(a, value());
        drive_options.changes.push_back({c.door, c.angle_deg, c.t});
      } else if (a == "--pass-distance") {
        drive_options.door_distance = toDouble(a, value());
        if (drive_options.door_distance < 1 || drive_options.door_distance > 3) throw UsageError("--pass-distance must lie in [1, 3] m");
      } else if (a == "--no-through-door") drive_options.through_door = false;
      else if (a == "--lidar-motion") drive_options.lidar_motion = true;
      else if (a == "--camera-pitch") {
        drive_options.camera_pitch_deg = toDouble(a, value());
        if (*drive_options.camera_pitch_deg < -20 || *drive_options.camera_pitch_deg > 10) throw UsageError("--camera-pitch must lie in [-20, 10] deg");
      } else if (a == "--rgbd-size") {
        rgbd_size = value();
        if (rgbd_size != "320x240" && rgbd_size != "640x480") throw UsageError("--rgbd-size must be 320x240 or 640x480");
      }
      else throw UsageError("unknown argument '" + a + "'");
    }
    if (out.empty()) throw UsageError("--out PREFIX is required");
    if (drive && !sensor_given) sensor = "lidar64";
    const int beams = sim::lidarBeamsOf(sensor);
    if (sensor != "tls" && sensor != "rgbd" && beams == 0)
      throw UsageError("--sensor must be tls, rgbd, lidar16, lidar32, lidar64 or lidar128");
    if (drive && sensor == "tls") throw UsageError("--drive needs --sensor lidar16|lidar32|lidar64|lidar128|rgbd");
    if (!drive && !drive_flag.empty()) throw UsageError(drive_flag + " is for --drive");
    if (drive && !formats_given) formats = "bag,json";
    if (mount_height) {
      const bool camera = drive && sensor == "rgbd";
      if (!camera && beams == 0) throw UsageError("--mount-height is for a LiDAR or a drive's camera");
      if (camera ? (*mount_height < 0.3 || *mount_height > 1.5) : (*mount_height < 0.4 || *mount_height > 1.2))
        throw UsageError(camera ? "--mount-height must lie in [0.3, 1.5] m for a camera" : "--mount-height must lie in [0.4, 1.2] m for a LiDAR");
    }
    if (sensor != "rgbd" && (depth_model_given || rgbd_option))
      throw UsageError("--depth-model, --resolution and the camera pose options are for --sensor rgbd");
    // Each family's reach: time of flight to 10 m, active stereo to 8 m (its
    // error then ~20 cm), structured light as the default, 4.5 m.
    if (rgbd.depth_model == sim::DepthModel::TimeOfFlight) rgbd.max_range = 10.0;
    if (rgbd.depth_model == sim::DepthModel::ActiveStereo) rgbd.max_range = 8.0;
    if (bag.count < 1 || bag.count > 10000 || !(bag.rate_hz > 0 && bag.rate_hz <= 1000))
      throw UsageError("--bag-count must lie in [1, 10000] and --bag-rate in (0, 1000]");
    if (bag.fixed_frame.empty()) throw UsageError("--fixed-frame must not be empty");
    std::stringstream ss(formats);
    std::string f;
    std::set<std::string> fmt;
    while (std::getline(ss, f, ','))
      if (f == "pcd" || f == "ply" || f == "json" || f == "bag") fmt.insert(f);
      else throw UsageError("--formats: unknown format '" + f + "'");
    if (fmt.empty()) throw UsageError("--formats is empty");
    if (!merged_frame.empty() && !merge) throw UsageError("--frame needs --merge or --mesh-like");
    if (merged_frame.empty()) merged_frame = "map";
    if (merged_frame != "map" && merged_frame != "station0") throw UsageError("--frame must be map or station0");
    if (merge && sensor != "tls") throw UsageError("--merge and --mesh-like are for --sensor tls");
    if (merge && merged_frame == "map" && fmt.count("bag") && bag.fixed_frame == "map")
      throw UsageError("--merge puts the cloud in frame map: give the bag another --fixed-frame (e.g. world)");
    if (drive && fmt.count("ply")) throw UsageError("--drive writes bag, json and pcd only");
    if (!frame_offset.isZero() && (drive || zeros || fmt.count("bag")))
      throw UsageError("--frame-offset is for pcd, ply and json of one scene (not --drive, --zeros or bag)");

    const auto t_start = std::chrono::steady_clock::now();
    sim::RoomSpec spec = scene_name == "random" ? sim::randomRoom(seed, random_options) : sim::paperRoom(scene_name);
    if (angle >= 0)
      for (auto& d : spec.doors) d.angle_deg = angle;
    spec.handles = handles;
    const sim::Scene scene = sim::buildScene(spec);
    tls.seed = rgbd.seed = seed;
    sim::LidarOptions lidar;
    if (beams > 0) {
      lidar = sim::LidarOptions::preset(beams);
      if (lidar_noise) lidar.range_sigma = *lidar_noise;
      if (lidar_dropout) lidar.dropout = *lidar_dropout;
      lidar.zeros_for_no_return = zeros;
      if (mount_height) lidar.mast_height = *mount_height;
      lidar.seed = seed;
    }
    if (drive) {
      drive_options.sensor = sensor;
      drive_options.seed = seed;
      drive_options.mount_height = mount_height;
      if (beams > 0) drive_options.lidar = lidar;
      else {
        if (rgbd_size != "640x480") rgbd.resize(320, 240);
        drive_options.rgbd = rgbd;
      }
      sim::DrivePlan plan = sim::planDrive(spec, drive_options);
      plan.map_frame = bag.fixed_frame;
      if (fmt.count("json")) {
        std::ofstream js(out + ".json");
        js << sim::driveTruthJson(plan, bag.start_time).dump(1) << "\n";
        if (!js) throw std::runtime_error("cannot write " + out + ".json");
      }
      // pcd: every frame's cloud (sensor frame) and its truth in that frame, for per-cloud evaluation.
      auto perFrame = [&](const sim::DriveFrame& f) {
        if (!fmt.count("pcd")) return;
        char name[32];
        std::snprintf(name, sizeof name, ".frame%05zu", f.index);
        const std::string p = out + name;
        if (pcl::io::savePCDFileBinary(p + ".pcd", f.cloud.cloud) != 0) throw std::runtime_error("cannot write " + p + ".pcd");
        std::ofstream js(p + ".json");
        nlohmann::json t = sim::groundTruthJson(plan.scenes[f.scene_index], f.cloud);
        for (std::size_t k = 0; k < t["doors"].size(); ++k)
          t["doors"][k]["in_view"] = sim::sensorSeesDoor(plan.scenes[f.scene_index], f.cloud, static_cast<int>(k));
        t["stamp"] = bag.start_time + f.t;
        js << t.dump(1) << "\n";
        if (!js) throw std::runtime_error("cannot write " + p + ".json");
      };
      if (fmt.count("bag")) tools::writeDriveBag(out + ".bag", plan, bag, perFrame);
      else if (fmt.count("pcd")) sim::simulateDrive(plan, perFrame);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
      if (!quiet) {
        std::cerr << "door_scene_sim: scene " << spec.name << " (" << spec.width << " x " << spec.depth << " x "
                  << spec.height << " m), " << plan.scenes[0].doors.size() << " door(s); drive of " << plan.options.seconds
                  << " s, " << plan.path_length << " m at " << plan.speed << " m/s, " << plan.frame_count << " " << sensor
                  << " clouds at " << plan.options.rate_hz << " Hz, sensor " << *plan.options.mount_height << " m high"
                  << (plan.through_door >= 0 ? ", through door " + std::to_string(plan.through_door) : std::string(", no doorway driven through"))
                  << "; written in " << static_cast<int>(ms) << " ms\n";
        for (std::size_t i = 0; i < plan.scenes[0].doors.size(); ++i) {
          const auto& d = plan.scenes[0].doors[i];
          std::cerr << "  door " << i << ": " << d.state() << " at " << d.angle_deg << " deg"
                    << (plan.door_waypoints[i].z() < 0 ? " (not reachable: not passed)" : "") << "\n";
        }
        for (const auto& c : plan.changes)
          std::cerr << "  door " << c.door << " -> " << c.angle_deg << " deg at " << c.t << " s\n";
      }
      return 0;
    }
    sim::SimulatedCloud cloud = sensor == "tls" ? sim::scanTls(scene, tls)
                                : beams > 0     ? sim::scanLidar(scene, lidar)
                                                : sim::captureRgbd(scene, rgbd);
    if (merge) cloud = sim::mergeStations(scene, cloud, {sim::mergedFrameFromString(merged_frame), seed});
    if (mesh_vertices > 0) {
      sim::MeshLikeOptions mesh;
      mesh.vertices = static_cast<std::size_t>(mesh_vertices);
      mesh.seed = seed;
      cloud = sim::meshLike(cloud, mesh);
    }
    if (voxel_map > 0) cloud = sim::voxelMap(cloud, voxel_map);
    if (!frame_offset.isZero()) {
      // The cloud's frame moved by -offset: its points (NaN stays NaN) and
      // a sensor's VIEWPOINT by +offset, the frame's pose to match (the
      // truth and the station files follow).
      const Eigen::Vector3f o = frame_offset.cast<float>();
      for (auto& q : cloud.cloud.points)
        if (std::isfinite(q.x)) q.getVector3fMap() += o;
      if (!merge) cloud.cloud.sensor_origin_.head<3>() += o;  // a registered export's stays 0 0 0
      cloud.sensor_to_world = cloud.sensor_to_world * Eigen::Translation3d(-frame_offset);
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();

    if (fmt.count("pcd") && pcl::io::savePCDFileBinary(out + ".pcd", cloud.cloud) != 0)
      throw std::runtime_error("cannot write " + out + ".pcd");
    // Several scan positions: each one's scan on its own too, in the same
    // frame, its position in the PCD's VIEWPOINT (as a survey's registered
    // stations come), for door_state_cli's multi-station input.
    if (fmt.count("pcd") && cloud.viewpoints_world.size() > 1 && mesh_vertices == 0 && voxel_map == 0) {
      const Eigen::Isometry3d world_to_cloud = cloud.sensor_to_world.inverse();
      for (std::size_t k = 0; k < cloud.viewpoints_world.size(); ++k) {
        pcl::PointCloud<pcl::PointXYZL> part;
        for (std::size_t i = 0; i < cloud.cloud.size(); ++i)
          if (cloud.station[i] == static_cast<int>(k)) part.push_back(cloud.cloud[i]);
        const Eigen::Vector3d o = world_to_cloud * cloud.viewpoints_world[k];
        part.sensor_origin_ = Eigen::Vector4f(static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z()), 0);
        const std::string path = out + ".station" + std::to_string(k) + ".pcd";
        if (part.empty() || pcl::io::savePCDFileBinary(path, part) != 0) throw std::runtime_error("cannot write " + path);
      }
    }
    if (fmt.count("ply") && pcl::io::savePLYFileBinary(out + ".ply", cloud.cloud) != 0)
      throw std::runtime_error("cannot write " + out + ".ply");
    if (fmt.count("json")) {
      std::ofstream js(out + ".json");
      js << sim::groundTruthJson(scene, cloud).dump(2) << "\n";
      if (!js) throw std::runtime_error("cannot write " + out + ".json");
    }
    if (fmt.count("bag")) tools::writeBag(out + ".bag", cloud, bag);

    if (!quiet) {
      std::cerr << "door_scene_sim: scene " << spec.name << " (" << spec.width << " x " << spec.depth << " x "
                << spec.height << " m), " << scene.doors.size() << " door(s), " << scene.decoys.size()
                << " furniture piece(s); " << sensor << " cloud of " << cloud.cloud.size() << " points in frame "
                << cloud.frame_id << " simulated in " << static_cast<int>(ms) << " ms\n";
      if (mesh_vertices > 0) std::cerr << "  mesh-like: median vertex spacing " << sim::medianSpacing(cloud.cloud) << " m\n";
      if (sensor == "rgbd") {
        const Eigen::Vector3d cam = cloud.sensor_to_world.translation(), f = cloud.sensor_to_world.linear().col(2);
        std::cerr << "  camera: depth model " << sim::toString(rgbd.depth_model) << ", " << rgbd.width << "x"
                  << rgbd.height << ", height " << cam.z() - scene.floor_z << " m, pitch "
                  << std::asin(std::max(-1.0, std::min(1.0, f.z()))) * 180 / M_PI << " deg\n";
      }
      for (std::size_t i = 0; i < scene.doors.size(); ++i) {
        const auto& d = scene.doors[i];
        std::cerr << "  door " << i << ": " << d.state() << " at " << d.angle_deg << " deg, width " << d.width
                  << " m, hinge " << (d.hinge_left ? "left" : "right") << ", swings "
                  << (d.swing_into_room ? "toward" : "away from") << " the viewer\n";
      }
    }
  } catch (const UsageError& e) {
    std::cerr << "door_scene_sim: " << e.what() << "\n\n" << kUsage;
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "door_scene_sim: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "door_scene_sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
