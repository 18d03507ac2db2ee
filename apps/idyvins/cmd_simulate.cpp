// `idyvins simulate`: the synthetic dynamic-scene benchmark generator.

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "commands.h"
#include "core/error.h"
#include "io/bag_writer.h"
#include "io/euroc_dataset.h"
#include "io/output_folder.h"
#include "progress.h"
#include "sim/simulator.h"
#include "sim/vins_rigs.h"

namespace idyvins::app {
namespace {

struct SimulateArgs {
  std::string scene = "city", level = "none", out;
  std::uint64_t seed = 1, traffic_seed = 0;
  int parked = 0;
  std::string route = "default";
  double duration = 60.0, noise = 1.0, image_noise = 2.0, td_ms = 0.0;
  int threads = 2;
  bool opening_vehicle = false, standard_set = false, depth = false, force = false;
  std::string format = "euroc", compression = "none", viode_tables = IDYVINS_VIODE_TABLES;
  std::string realism = "none", realism_without;
  std::string family = "standard";
  std::string lens = "pinhole";
  std::string rig;
};

/// VIODE's file name for a traffic level (0_none .. 3_high).
std::string viodeBagName(const std::string& level) {
  const char* names[] = {"none", "low", "mid", "high"};
  for (int i = 0; i < 4; ++i)
    if (level == names[i]) return std::to_string(i) + "_" + level + ".bag";
  return level + ".bag";
}

/// OUT/<k>_<level>.bag with VIODE's topics, the colour tables copied into OUT/config and
/// the config naming the bag's ground-truth and segmentation topics.
void writeBag(const SimulateArgs& a, const std::string& scene, const std::string& level, const std::string& out,
              const std::string& final_dir) {
  namespace fs = std::filesystem;
  const std::string vehicles = scene == "parking_lot" ? "vehicle_ids_parking_lot.txt" : "vehicle_ids_city_day.txt";
  const fs::path tables(a.viode_tables), config_dir = fs::path(out) / "config";
  for (const std::string& f : {std::string("rgb_ids.txt"), vehicles}) {
    if (!fs::exists(tables / f))
      throw InputError((tables / f).string(), "VIODE's segmentation table is missing (set --viode-tables)");
    fs::copy_file(tables / f, config_dir / f, fs::copy_options::overwrite_existing);
  }
  io::BagWriteOptions w;
  w.format = a.format == "mcap" ? "mcap" : "ros1";
  w.compression = a.compression;
  w.rgb_ids = (config_dir / "rgb_ids.txt").string();
  w.vehicle_ids = (config_dir / vehicles).string();
  const std::string bag_name = a.format == "mcap" ? fs::path(viodeBagName(level)).stem().string() : viodeBagName(level);
  const std::string bag = (fs::path(out) / bag_name).string();
  io::writeViodeBag(io::readEurocDataset(out), bag, w);
  // The config names VIODE's topics and the colour tables.
  const std::string config_path =
      (config_dir / (a.rig.empty() ? "sim_stereo_imu_config.yaml" : sim::findVinsRig(a.rig)->config_file)).string();
  Config cfg = loadConfig(config_path);
  cfg.imu_topic = "/imu0";
  cfg.image0_topic = "/cam0/image_raw";
  cfg.image1_topic = "/cam1/image_raw";
  cfg.groundtruth_topic = "/odometry";
  cfg.segmentation_topic = "/cam0/segmentation";
  cfg.segmentation_rgb_ids = "rgb_ids.txt";
  cfg.segmentation_vehicle_ids = vehicles;
  saveConfig(cfg, config_path);
  if (a.format == "bag" || a.format == "mcap") fs::remove_all(fs::path(out) / "mav0");  // the staging folder's
  std::printf("%s: %s, VIODE topics /imu0 /cam0/image_raw /cam1/image_raw /odometry /cam0/segmentation\n",
              (fs::path(final_dir) / bag_name).string().c_str(),
              a.format == "mcap" ? "ROS 2 bag (rosbag2 folder, MCAP)" : "ROS1 bag");
}

/// OUT, staged and never replacing what simulate did not write (an earlier render is replaced).
io::OutputFolderOptions simulateFolderOptions(const SimulateArgs& a) {
  io::OutputFolderOptions o;
  o.tool = "simulate";
  o.inputs = {a.viode_tables};
  o.force = a.force;
  o.legacy_names = {"mav0",       "config", "meta.json", "0_none.bag", "1_low.bag", "2_mid.bag",
                    "3_high.bag", "0_none", "1_low",     "2_mid",      "3_high"};
  o.legacy_required = {"meta.json"};
  return o;
}

/// --realism and --realism-without.
sim::RealismOptions realismOf(const SimulateArgs& a) {
  sim::RealismOptions r = sim::realismPreset(a.realism);
  if (!a.realism_without.empty() && !r.enabled)
    throw CLI::ValidationError("--realism-without", "removes effects of a realism preset: give --realism euroc");
  try {
    sim::removeRealismEffects(r, a.realism_without);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--realism-without", e.what());
  }
  return r;
}

int simulateOne(const SimulateArgs& a, const std::string& scene, const std::string& level, const std::string& dir) {
  io::OutputFolder folder(dir, simulateFolderOptions(a));
  const std::string& out = folder.path();
  sim::SimOptions o;
  if (!sim::parseFamily(a.family, o.family))
    throw CLI::ValidationError("--family", "expected standard|validation, got '" + a.family + "'");
  if (!sim::parseLens(a.lens, o.lens))
    throw CLI::ValidationError("--lens", "expected pinhole|kb|mei|kb185, got '" + a.lens + "'");
  if (!a.rig.empty()) {
    const sim::VinsRig* rig = sim::findVinsRig(a.rig);
    if (!rig) throw CLI::ValidationError("--rig", "expected one of " + sim::vinsRigNames() + ", got '" + a.rig + "'");
    if (o.lens != sim::Lens::kPinhole)
      throw CLI::ValidationError("--rig", "a rig brings its own lenses: leave --lens at pinhole");
    o.vins_rig = a.rig;
    o.camera_rate_hz = rig->camera_rate_hz;
    o.imu_rate_hz = rig->imu_rate_hz;
  }
  o.scene.scene = scene;
  if (!sim::parseLevel(level, o.scene.level))
    throw CLI::ValidationError("--level", "expected none|low|mid|high, got '" + level + "'");
  o.scene.seed = a.seed;
  o.scene.traffic_seed = a.traffic_seed;
  o.scene.parked = a.parked;
  if (!sim::parseRoute(a.route, o.scene.route))
    throw CLI::ValidationError("--route", "expected default|block, got '" + a.route + "'");
  if (o.scene.route == sim::Route::kBlock && (scene != "city" || o.family != sim::Family::kStandard))
    throw CLI::ValidationError("--route", "block is a drone's lap of a city block: --scene city, --family standard");
  o.scene.opening_vehicle = a.opening_vehicle;
  o.duration_s = a.duration;
  o.td_s = 1e-3 * a.td_ms;
  o.imu.scale = a.noise;
  o.image_noise_sigma = a.image_noise;
  o.realism = realismOf(a);
  o.threads = a.threads;
  o.write_depth = a.depth;
  ProgressBar bar("simulate " + scene + " " + level, 0, "frames");
  std::size_t total = 0;
  const sim::SimResult r = sim::simulate(o, out, [&](std::size_t done, std::size_t n) {
    if (total == 0) {
      total = n;
      bar = ProgressBar("simulate " + scene + " " + level, n, "frames");
    }
    bar.update(done);
  });
  bar.finish();
  std::printf(
      "%s: %s %s seed %llu, %.1f s, %zu stereo frames, %zu IMU samples, path %.1f m, "
      "moving objects cover %.1f%% of cam0 on average (max %.1f%%, >=30%% in %.1f%% of frames), "
      "written in %.1f s\n",
      dir.c_str(), scene.c_str(), level.c_str(), static_cast<unsigned long long>(a.seed), a.duration, r.frames,
      r.imu_samples, r.path_length_m, 100 * r.coverage.mean, 100 * r.coverage.max, 100 * r.coverage.frames_over_30pct,
      r.seconds);
  if (a.format != "euroc") writeBag(a, scene, level, out, dir);
  for (const std::string& w : folder.publish()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  return kOk;
}

int runSimulate(const SimulateArgs& a) {
  if (!(a.duration > 0)) throw CLI::ValidationError("--duration", "must be positive");
  if (a.depth && (a.format == "bag" || a.format == "mcap"))
    throw CLI::ValidationError("--depth", "depth images go into the EuRoC folder: --format euroc or both");
  if (a.format == "mcap" && a.compression == "bz2")
    throw CLI::ValidationError("--compression", "MCAP chunks are none, zstd or lz4 (bz2 is ROS1's)");
  if (a.format != "mcap" && a.compression == "zstd")
    throw CLI::ValidationError("--compression", "ROS1 bag chunks are none, bz2 or lz4 (zstd is MCAP's: --format mcap)");
  if (a.noise < 0) throw CLI::ValidationError("--noise", "must be >= 0");
  if (!a.standard_set) return simulateOne(a, a.scene, a.level, a.out);
  for (const char* scene : {"city", "parking_lot"})
    for (const char* level : {"none", "low", "mid", "high"}) {
      const std::string dir =
          (std::filesystem::path(a.out) / (std::string(scene) + "_" + level + "_s" + std::to_string(a.seed))).string();
      if (std::filesystem::exists(std::filesystem::path(dir) / "meta.json")) {
        std::printf("%s: exists, kept\n", dir.c_str());
        continue;
      }
      simulateOne(a, scene, level, dir);
    }
  return kOk;
}

/// --traffic-seed, --parked, --route: the run through a place (loop closure, map reuse).
void addRunThroughPlaceOptions(CLI::App* cmd, SimulateArgs& args) {
  SimulateArgs* a = &args;
  cmd->add_option("--traffic-seed", a->traffic_seed,
                  "random seed of the run through the place: traffic, temporarily parked cars, the\n"
                  "trajectory's start and phases, sensor noise (default: --seed). Same --seed, other\n"
                  "--traffic-seed: the same place revisited with other vehicles");
  cmd->add_option("--parked", a->parked,
                  "temporarily parked cars placed from the traffic seed (garage centre, back street of\n"
                  "the city block; static within the run, moved or gone in another run)")
      ->check(CLI::Range(0, 24));
  cmd->add_option("--route", a->route,
                  "default: the scene's path (city: along the street; parking_lot: laps of the\n"
                  "ellipse, 33 s each); block: laps around a city block (about 95 s each, 4 m up)")
      ->check(CLI::IsMember({"default", "block"}));
}

}  // namespace

/// --format and --compression: the EuRoC folder, a ROS1 bag or a ROS 2 bag.
void addFormatOptions(CLI::App* cmd, SimulateArgs& args) {
  SimulateArgs* a = &args;
  cmd->add_option("--format", a->format,
                  "euroc (default): the EuRoC folder; bag: OUT/<k>_<level>.bag (VIODE's names) with VIODE's topics\n"
                  "and message types (/imu0, /cam0/image_raw and /cam1/image_raw mono8, /odometry, /cam0/segmentation\n"
                  "coloured with VIODE's tables) and the config naming them; both: the folder and the bag;\n"
                  "mcap: a ROS 2 bag, the rosbag2 folder OUT/<k>_<level>/ (metadata.yaml, one .mcap, CDR) with the\n"
                  "same topics in ROS 2's types (sensor_msgs/msg/Image, ...)")
      ->check(CLI::IsMember({"euroc", "bag", "both", "mcap"}));
  cmd->add_option("--compression", a->compression,
                  "bag chunks: none (default), bz2, lz4 (ROS1); none, zstd, lz4 (MCAP)")
      ->check(CLI::IsMember({"none", "bz2", "lz4", "zstd"}));
}

/// --realism and --realism-without.
void addRealismOptions(CLI::App* cmd, SimulateArgs& args) {
  SimulateArgs* a = &args;
  cmd->add_option("--realism", a->realism,
                  "camera realism: none (default: today's images) | euroc (vignetting, right camera 10 %\n"
                  "darker, auto-exposure, 6 ms motion blur along the true trajectory, defocus, shot and read\n"
                  "noise; statistics matched to the real EuRoC excerpt, see README). Ground truth, masks\n"
                  "and IMU are the same as without.")
      ->check(CLI::IsMember({"none", "euroc"}));
  cmd->add_option("--realism-without", a->realism_without,
                  "the preset without some effects (which one does a result depend on?): comma-separated\n"
                  "vignetting, gain, blur, defocus, exposure, noise, plain; meta.json names them");
}

/// --rig: one of VINS-Fusion's rigs in place of the family's.
void addRigOption(CLI::App* cmd, SimulateArgs& args) {
  SimulateArgs* a = &args;
  cmd->add_option(
      "--rig", a->rig,
      "a rig of VINS-Fusion's config folder in place of the family's, from its published numbers:\n" +
          sim::vinsRigNames() +
          ".\nCameras (PINHOLE or MEI), mounts, image size, num_of_cam, imu and keys as the config states;\n"
          "rates the sensor's usual ones (EuRoC, vi_car, simulation 20 / 200 Hz, A3 20 / 400 Hz, MYNT EYE\n"
          "and RealSense 30 / 200 Hz, KITTI 10 / 100 Hz). cam0 flies the family's path; the written\n"
          "config is VINS-Fusion's file name under DIR/config/. A one-camera config's folder has cam1 too");
}

void registerSimulate(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<SimulateArgs>();
  CLI::App* cmd =
      app.add_subcommand("simulate",
                         "Render a synthetic stereo-inertial dataset of a dynamic scene (VIODE-like) in EuRoC\n"
                         "layout: cam0/cam1 PNGs (752x480, 20 Hz) with per-pixel object-id masks, IMU at 200 Hz\n"
                         "(ADIS16448-like noise and bias random walk), ground truth with velocity and biases,\n"
                         "a VINS-Fusion config under DIR/config/, and DIR/meta.json. Deterministic.");
  cmd->add_option("--scene", a->scene, "city | parking_lot")->check(CLI::IsMember({"city", "parking_lot"}));
  cmd->add_option("--level", a->level, "moving objects: none | low | mid | high")
      ->check(CLI::IsMember({"none", "low", "mid", "high"}));
  cmd->add_option("--seed", a->seed,
                  "random seed of the place (layout, textures) and, unless --traffic-seed, of the run");
  addRunThroughPlaceOptions(cmd, *a);
  cmd->add_option("--duration", a->duration, "seconds of data");
  cmd->add_option("-o,--out", a->out,
                  "output folder (with --standard-set: the parent folder): new, empty or an earlier render's\n"
                  "(replaced); a folder holding other files is refused")
      ->required();
  cmd->add_flag("--force", a->force, "write into an --out holding files simulate did not write (none is removed)");
  cmd->add_option("--noise", a->noise, "IMU noise scale (0 = perfect IMU, 1 = ADIS16448-like)");
  cmd->add_option("--image-noise", a->image_noise, "pixel noise sigma, gray levels (with --realism none)");
  addRealismOptions(cmd, *a);
  cmd->add_option("--family", a->family,
                  "standard (default): the sequences the defaults are tuned on; validation: the family no\n"
                  "default is tuned on: EuRoC's intrinsics without distortion, a 0.11 m stereo pair with small\n"
                  "mount errors, VINS-Fusion's EuRoC IMU noise keys in the config, other materials (bricks,\n"
                  "fractal asphalt and concrete, plainer vehicles) and a handheld (walking) trajectory")
      ->check(CLI::IsMember({"standard", "validation"}));
  cmd->add_option("--lens", a->lens,
                  "pinhole (default): the family's lens; kb, mei: a full-frame fisheye of 150 deg across the\n"
                  "diagonal in both cameras (Kannala-Brandt, or MEI with xi 1.2), the same scene, trajectory\n"
                  "and mounts, so a run compares with the pinhole render of the same seed; kb185: a circular\n"
                  "Kannala-Brandt fisheye of 185 deg across its lens circle (inside the image, dark outside)")
      ->check(CLI::IsMember({"pinhole", "kb", "mei", "kb185"}));
  addRigOption(cmd, *a);
  cmd->add_option("--td-ms", a->td_ms,
                  "camera-IMU time offset of the written data (ms): image stamps are the capture times on the\n"
                  "IMU clock minus this, so a config's td of this value is right (VINS-Fusion's convention: image\n"
                  "clock + td = IMU clock). The written config keeps td: 0; meta.json records the truth")
      ->check(CLI::Range(-100.0, 100.0));
  cmd->add_option("--threads", a->threads, "rendering threads")->check(CLI::Range(1, 64));
  addFormatOptions(cmd, *a);
  cmd->add_option("--viode-tables", a->viode_tables,
                  "folder with VIODE's rgb_ids.txt and vehicle_ids_*.txt (default: the source tree's config/viode)");
  cmd->add_flag("--opening-vehicle", a->opening_vehicle,
                "a vehicle crosses close in front of the drone during the first seconds");
  cmd->add_flag("--depth", a->depth,
                "also write mav0/cam{0,1}/depth/<stamp>.tiff: float32 depth (z, m) per pixel, 0 = sky; for checking\n"
                "tracks against the scene (scripts/analysis/track_accuracy.py); 1.4 MB per image");
  cmd->add_flag("--standard-set", a->standard_set,
                "write city and parking_lot x none/low/mid/high into OUT/<scene>_<level>_s<seed>, "
                "keeping folders that already hold a meta.json");
  cmd->callback([a, &exit_code] { exit_code = runSimulate(*a); });
}

}  // namespace idyvins::app
