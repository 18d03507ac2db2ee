#include "sim/simulator.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>
#include <thread>

#include "core/error.h"
#include "io/trajectory_io.h"
#include "sim/renderer.h"
#include "sim/textures.h"
#include "sim/vins_rigs.h"

namespace fs = std::filesystem;

namespace idyvins::sim {

using Eigen::Vector3d;

namespace {
/// T_w_b of a trajectory state.
Eigen::Isometry3d bodyPose(const BodyState& b) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = b.q_w_b.toRotationMatrix();
  T.translation() = b.p_w_b;
  return T;
}
}  // namespace

bool parseFamily(const std::string& text, Family& family) {
  if (text == "standard")
    family = Family::kStandard;
  else if (text == "validation")
    family = Family::kValidation;
  else
    return false;
  return true;
}

const char* toString(Family family) { return family == Family::kValidation ? "validation" : "standard"; }

bool parseLens(const std::string& text, Lens& lens) {
  if (text == "pinhole")
    lens = Lens::kPinhole;
  else if (text == "kb")
    lens = Lens::kKannalaBrandt;
  else if (text == "mei")
    lens = Lens::kMei;
  else if (text == "kb185")
    lens = Lens::kKannalaBrandtCircle;
  else
    return false;
  return true;
}

const char* toString(Lens lens) {
  switch (lens) {
    case Lens::kKannalaBrandt:
      return "kb";
    case Lens::kMei:
      return "mei";
    case Lens::kKannalaBrandtCircle:
      return "kb185";
    case Lens::kPinhole:
      break;
  }
  return "pinhole";
}

namespace {

/// The validation family's rig: EuRoC's intrinsics (each camera its own, no distortion),
/// a 0.11 m baseline, both cameras a little rotated from the ideal forward mount.
void validationRig(Config& c) {
  const double intrinsics[2][4] = {{458.654, 457.296, 367.215, 248.375}, {457.587, 456.134, 379.999, 255.238}};
  // Small mount errors (rad): roll, pitch, yaw of each camera about the ideal mount.
  const double mount[2][3] = {{0.004, 0.012, -0.006}, {0.007, 0.0095, -0.0025}};
  for (int i = 0; i < 2; ++i) {
    camera::CameraParams& p = c.cams[i];
    p.fx = intrinsics[i][0];
    p.fy = intrinsics[i][1];
    p.cx = intrinsics[i][2];
    p.cy = intrinsics[i][3];
    p.dist = {0.0, 0.0, 0.0, 0.0};
    const Eigen::Matrix3d R_err =
        (Eigen::AngleAxisd(mount[i][2], Vector3d::UnitY()) * Eigen::AngleAxisd(mount[i][1], Vector3d::UnitX()) *
         Eigen::AngleAxisd(mount[i][0], Vector3d::UnitZ()))
            .toRotationMatrix();  // in the camera frame: y down, x right, z forward
    c.T_b_c[i].linear() = c.T_b_c[i].linear() * R_err;
    c.T_b_c[i].translation() = Vector3d(0.06, i == 0 ? 0.055 : -0.055, 0.01);
  }
  // VINS-Fusion's own EuRoC config values, as a user with an EuRoC-like IMU would write them.
  c.imu.noise.acc_n = 0.1;
  c.imu.noise.gyr_n = 0.01;
  c.imu.noise.acc_w = 0.001;
  c.imu.noise.gyr_w = 0.0001;
}

/// The fisheye lens in place of the pinhole: the same principal point, the focal scale chosen
/// so that the half diagonal images kFisheyeDiagonalFovDeg / 2 off the axis (the circular lens:
/// its lens circle, 2 px inside the image's shorter side, kCircleFovDeg / 2).
void fisheyeLens(camera::CameraParams& p, Lens lens) {
  const bool circle = lens == Lens::kKannalaBrandtCircle;
  const double half_diagonal = circle ? 0.5 * std::min(p.width, p.height) - 2.0 : 0.5 * std::hypot(p.width, p.height);
  const double theta = 0.5 * (circle ? kCircleFovDeg : kFisheyeDiagonalFovDeg) * M_PI / 180.0;
  p.type = lens == Lens::kMei ? camera::ModelType::kMei : camera::ModelType::kKannalaBrandt;
  if (lens == Lens::kMei) {
    p.xi = 1.2;
    p.dist = {-0.02, 0.004, 0.0, 0.0};
  } else {
    p.dist = {0.012, -0.003, 0.0, 0.0};  // k2 k3
  }
  p.fx = p.fy = 1.0;
  const auto unit = camera::makeCamera(p);
  Eigen::Vector2d uv;
  unit->project(Eigen::Vector3d(std::sin(theta), 0.0, std::cos(theta)), uv);
  p.fx = p.fy = half_diagonal / (uv.x() - p.cx);
}

}  // namespace

Config rigConfig(const SimOptions& options) {
  if (!options.vins_rig.empty()) {
    const VinsRig* r = findVinsRig(options.vins_rig);
    if (!r) throw std::invalid_argument("unknown rig '" + options.vins_rig + "' (known: " + vinsRigNames() + ")");
    return vinsRigConfig(*r);
  }
  Config c;
  c.path = "sim_stereo_imu_config.yaml";
  c.num_cam = 2;
  c.image_width = 752;
  c.image_height = 480;
  for (int i = 0; i < 2; ++i) {
    camera::CameraParams p;
    p.type = camera::ModelType::kPinhole;
    p.name = "cam" + std::to_string(i);
    p.width = 752;
    p.height = 480;
    p.fx = p.fy = 380.0;
    p.cx = 376.0;
    p.cy = 240.0;
    p.dist = {-0.05, 0.01, 0.0005, -0.0003};
    c.cams.push_back(p);
    c.cam_paths.push_back("cam" + std::to_string(i) + "_pinhole.yaml");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // camera z = body x (forward), camera x = body -y
    T.translation() = Vector3d(0.05, i == 0 ? 0.055 : -0.055, 0.0);
    c.T_b_c.push_back(T);
  }
  // VINS-Fusion semantics (docs/conventions.md): acc_n = √2 σ_sample, σ_sample = density √rate;
  // acc_w such that acc_w² δt² = random_walk² δt.
  const double rate = options.imu_rate_hz;
  const ImuErrorModel& m = options.imu;
  c.imu.noise.acc_n = std::sqrt(2.0) * m.acc_density * std::sqrt(rate);
  c.imu.noise.gyr_n = std::sqrt(2.0) * m.gyro_density * std::sqrt(rate);
  c.imu.noise.acc_w = m.acc_random_walk * std::sqrt(rate);
  c.imu.noise.gyr_w = m.gyro_random_walk * std::sqrt(rate);
  c.imu.noise.g_norm = options.g_norm;
  if (options.family == Family::kValidation) validationRig(c);
  if (options.lens != Lens::kPinhole)
    for (int i = 0; i < 2; ++i) {
      fisheyeLens(c.cams[i], options.lens);
      c.cam_paths[i] = "cam" + std::to_string(i) + "_" + toString(options.lens) + ".yaml";
    }
  // A real camera's config: right matches refined gain- and bias-invariantly (KLT's
  // disparity is biased by brightness differences a global gain leaves, see TrackerParams).
  c.tracker.stereo_refine = options.realism.enabled ? 1 : 0;
  // A real camera's noise, blur and exposure changes make young static tracks fail the
  // stereo motion test: on such images a repeated failure removes only above chi2 80 or
  // after 3 failures in a row (docs/real-images.md; clean images keep removing at the
  // first repeated failure, which their recall needs).
  if (options.realism.enabled) c.idy.stereo.remove_chi2 = 80.0;
  return c;
}

void synthesizeImu(const Trajectory& traj, const SimOptions& o, std::vector<ImuSample>& imu,
                   std::vector<GroundTruthState>& truth) {
  std::mt19937_64 rng(o.scene.runSeed() * 6364136223846793005ull + 1442695040888963407ull);
  std::normal_distribution<double> g(0.0, 1.0);
  auto gauss3 = [&](double s) -> Vector3d { return s * Vector3d(g(rng), g(rng), g(rng)); };
  const ImuErrorModel& m = o.imu;
  const double dt = 1.0 / o.imu_rate_hz;
  Vector3d bg = gauss3(m.gyro_bias0_sigma * m.scale), ba = gauss3(m.acc_bias0_sigma * m.scale);
  const std::size_t n = static_cast<std::size_t>(std::llround(o.duration_s * o.imu_rate_hz)) + 1;
  const TimeNs dt_ns = static_cast<TimeNs>(std::llround(1e9 / o.imu_rate_hz));
  imu.resize(n);
  truth.resize(n);
  const Vector3d g_w(0, 0, -o.g_norm);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    if (k > 0) {
      bg += gauss3(m.gyro_random_walk * std::sqrt(dt) * m.scale);
      ba += gauss3(m.acc_random_walk * std::sqrt(dt) * m.scale);
    }
    const BodyState s = traj.at(t);
    ImuSample& sample = imu[k];
    sample.t_ns = o.t0_ns + static_cast<TimeNs>(k) * dt_ns;
    sample.gyr_b = s.omega_b + bg + gauss3(m.gyro_density / std::sqrt(dt) * m.scale);
    sample.acc_b = s.q_w_b.conjugate() * (s.a_w - g_w) + ba + gauss3(m.acc_density / std::sqrt(dt) * m.scale);
    GroundTruthState& gt = truth[k];
    gt.t_ns = sample.t_ns;
    gt.p_w_b = s.p_w_b;
    gt.q_w_b = s.q_w_b;
    gt.v_w = s.v_w;
    gt.bg = bg;
    gt.ba = ba;
  }
}

namespace {

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw InputError(path.string(), "cannot write file");
}

std::string matrixYaml(const Eigen::Matrix4d& m, const char* indent) {
  char buf[512];
  std::string s = std::string(indent) + "rows: 4\n" + indent + "cols: 4\n" + indent + "dt: d\n" + indent + "data: [";
  for (int i = 0; i < 16; ++i) {
    std::snprintf(buf, sizeof(buf), "%s%.10g",
                  i ? (i % 4 ? ", " : ",\n" + std::string(indent) + "       ").c_str() : "", m(i / 4, i % 4));
    s += buf;
  }
  return s + "]\n";
}

void writeSensorYamls(const fs::path& mav0, const Config& c, const SimOptions& o) {
  for (int i = 0; i < 2; ++i) {
    const auto& p = c.cams[i];
    char buf[2048];
    std::snprintf(buf, sizeof(buf),
                  "%%YAML:1.0\nsensor_type: camera\ncomment: idyvins simulator cam%d\nT_BS:\n%s"
                  "rate_hz: %g\nresolution: [%d, %d]\ncamera_model: %s\nintrinsics: [%s%g, %g, %g, %g]\n"
                  "distortion_model: %s\ndistortion_coefficients: [%g, %g, %g, %g]\n",
                  i, matrixYaml(c.T_b_c[i].matrix(), "  ").c_str(), o.camera_rate_hz, p.width, p.height,
                  p.type == camera::ModelType::kMei ? "omni" : "pinhole",  // Kalibr's names
                  p.type == camera::ModelType::kMei ? (std::to_string(p.xi) + ", ").c_str() : "", p.fx, p.fy, p.cx,
                  p.cy, p.type == camera::ModelType::kKannalaBrandt ? "equidistant" : "radial-tangential", p.dist[0],
                  p.dist[1], p.dist[2], p.dist[3]);
    writeText(mav0 / ("cam" + std::to_string(i)) / "sensor.yaml", buf);
  }
  char buf[1024];
  const auto& m = o.imu;
  std::snprintf(buf, sizeof(buf),
                "%%YAML:1.0\nsensor_type: imu\ncomment: idyvins simulator IMU (noise scale %g)\nT_BS:\n%s"
                "rate_hz: %g\ngyroscope_noise_density: %g\ngyroscope_random_walk: %g\n"
                "accelerometer_noise_density: %g\naccelerometer_random_walk: %g\n",
                m.scale, matrixYaml(Eigen::Matrix4d::Identity(), "  ").c_str(), o.imu_rate_hz, m.gyro_density * m.scale,
                m.gyro_random_walk * m.scale, m.acc_density * m.scale, m.acc_random_walk * m.scale);
  writeText(mav0 / "imu0" / "sensor.yaml", buf);
  writeText(mav0 / "state_groundtruth_estimate0" / "sensor.yaml",
            "%YAML:1.0\nsensor_type: visual-inertial\ncomment: idyvins simulator ground truth (body = IMU)\n");
  writeText(mav0 / "body.yaml", "%YAML:1.0\ncomment: idyvins simulator drone\n");
}

void writeImuAndTruth(const fs::path& mav0, const std::vector<ImuSample>& imu,
                      const std::vector<GroundTruthState>& truth) {
  std::string s =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
      "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  char buf[512];
  for (const auto& m : imu) {
    std::snprintf(buf, sizeof(buf), "%lld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", static_cast<long long>(m.t_ns),
                  m.gyr_b.x(), m.gyr_b.y(), m.gyr_b.z(), m.acc_b.x(), m.acc_b.y(), m.acc_b.z());
    s += buf;
  }
  writeText(mav0 / "imu0" / "data.csv", s);
  io::writeStateCsv((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), truth);
}

nlohmann::json metaJson(const SimOptions& o, const World& world, const SimResult& r, const Config& rig) {
  nlohmann::json parked = nlohmann::json::array();
  for (const auto& [lo, hi] : world.parked)
    parked.push_back({{"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}});
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& v : world.vehicles) {
    objects.push_back({{"id", v.id},
                       {"type", v.type},
                       {"size_m", {v.size.x(), v.size.y(), v.size.z()}},
                       {"speed_mps", v.speed},
                       {"lane_start", {v.lane_start.x(), v.lane_start.y(), v.lane_start.z()}},
                       {"lane_dir", {v.lane_dir.x(), v.lane_dir.y(), v.lane_dir.z()}},
                       {"lane_length_m", v.lane_length},
                       {"offset_m", v.offset}});
    if (v.ellipse) objects.back()["loop"] = {{"a_m", v.ellipse_a}, {"b_m", v.ellipse_b}, {"direction", v.direction}};
  }
  nlohmann::json markers = nlohmann::json::array();
  for (const auto& m : world.markers)
    for (const auto& c : m.corners_w) markers.push_back({c.x(), c.y(), c.z()});
  return {{"generator", "idyvins simulate"},
          {"scene", o.scene.scene},
          {"level", toString(o.scene.level)},
          {"seed", o.scene.seed},
          {"traffic_seed", o.scene.runSeed()},
          {"route", toString(o.scene.route)},
          {"parked_vehicles", parked},
          {"family", toString(o.family)},
          {"lens", toString(o.lens)},
          {"vins_rig", o.vins_rig},
          {"config", "config/" + (o.vins_rig.empty() ? std::string("sim_stereo_imu_config.yaml") : rig.path)},
          {"opening_vehicle", o.scene.opening_vehicle},
          {"duration_s", o.duration_s},
          {"t0_ns", o.t0_ns},
          {"td_s", o.td_s},
          {"frames", r.frames},
          {"imu_samples", r.imu_samples},
          {"camera_rate_hz", o.camera_rate_hz},
          {"imu_rate_hz", o.imu_rate_hz},
          {"path_length_m", r.path_length_m},
          {"moving_objects", objects},
          {"moving_coverage_cam0",
           {{"mean", r.coverage.mean}, {"max", r.coverage.max}, {"frames_over_30pct", r.coverage.frames_over_30pct}}},
          {"imu_noise_scale", o.imu.scale},
          {"image_noise_sigma", o.image_noise_sigma},
          {"realism", o.realism.preset},
          {"stereo_baseline_m", (rig.T_b_c[0].inverse() * rig.T_b_c[1]).translation().norm()},
          {"marker_corners_w", markers}};
}

}  // namespace

namespace {

/// v to `digits` significant decimal digits.
double significant(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
  return std::strtod(buf, nullptr);
}

}  // namespace

void writeVinsConfig(const Config& c, const std::string& folder, const std::string& name, bool as_published) {
  const fs::path dir(folder);
  fs::create_directories(dir);
  if (as_published) {
    saveConfig(c, (dir / name).string(), SavedKeys::kChanged);
    return;
  }
  // The values the simulator's configs have always carried: IMU keys to 6 significant
  // digits, extrinsics and intrinsics to 10 (so that old and new renders run alike).
  Config w = c;
  for (double* v :
       {&w.imu.noise.acc_n, &w.imu.noise.gyr_n, &w.imu.noise.acc_w, &w.imu.noise.gyr_w, &w.imu.noise.g_norm})
    *v = significant(*v, 6);
  for (auto& T : w.T_b_c) {
    Eigen::Matrix4d m = T.matrix();
    for (int k = 0; k < 16; ++k) m(k / 4, k % 4) = significant(m(k / 4, k % 4), 10);
    T.matrix() = m;
  }
  for (auto& cam : w.cams)
    for (double* v : {&cam.fx, &cam.fy, &cam.cx, &cam.cy, &cam.dist[0], &cam.dist[1], &cam.dist[2], &cam.dist[3]})
      *v = significant(*v, 10);
  saveConfig(w, (dir / name).string(), SavedKeys::kChanged);
}

Scene::Scene(const SimOptions& o)
    : options_(o),
      rig_(rigConfig(o)),
      textures_(o.scene.seed, 3, 10,
                o.family == Family::kValidation ? TextureStyle::kValidation : TextureStyle::kStandard),
      world_(buildWorld(o.scene, textures_)),
      trajectory_(o.scene.scene, o.scene.runSeed(), o.g_norm,
                  o.family == Family::kValidation ? TrajectoryStyle::kHandheld : TrajectoryStyle::kDrone,
                  o.scene.route == Route::kBlock),
      frames_(static_cast<std::size_t>(std::floor(o.duration_s * o.camera_rate_hz + 1e-9)) + 1) {
  for (int c = 0; c < 2; ++c) {
    cams_[c] = rig_.cams[c];
    cams_[c].width = rig_.image_width;
    cams_[c].height = rig_.image_height;
    renderers_.emplace_back(cams_[c], textures_, lensHalfFovRad(o.lens));
  }
  if (!o.vins_rig.empty()) {
    // The family's cam0 keeps its path; the rig's body is where its mount puts it.
    SimOptions family = o;
    family.vins_rig.clear();
    trajectory_.setBodyOffset(rigConfig(family).T_b_c[0] * rig_.T_b_c[0].inverse());
  }
  const RealismOptions& r = o.realism;
  if (!r.enabled) return;
  if (r.blur_samples < 1) throw std::invalid_argument("realism: blur_samples must be >= 1");
  if (r.low_texture_fraction > 0 || r.plain_ground) {  // plain materials on some static surfaces
    std::mt19937_64 rng(o.scene.seed * 7919u + 11u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (Quad& q : world_.statics) {
      const bool ground = std::abs(q.origin.z()) < 1e-6 && q.u.cross(q.v).normalized().z() > 0.99;
      if (u(rng) < r.low_texture_fraction || (r.plain_ground && ground))
        q.contrast = static_cast<float>(r.low_texture_contrast);
    }
  }
  for (int c = 0; c < 2; ++c)
    vignetting_[c] =
        vignettingProfile(cams_[c].width, cams_[c].height, cams_[c].cx, cams_[c].cy, r.vignetting_k1, r.vignetting_k2);
  exposure_.assign(frames_, 1.0);
  if (!r.auto_exposure) return;
  // The meter: cam0 at a quarter of the resolution, vignetted, at each frame's time.
  camera::CameraParams preview = cams_[0];
  preview.width /= 4;
  preview.height /= 4;
  preview.fx /= 4;
  preview.fy /= 4;
  preview.cx /= 4;
  preview.cy /= 4;
  const Renderer meter_renderer(preview, textures_);
  const cv::Mat meter_vignetting =
      vignettingProfile(preview.width, preview.height, preview.cx, preview.cy, r.vignetting_k1, r.vignetting_k2);
  std::vector<double> meter(frames_);
  for (std::size_t k = 0; k < frames_; ++k) {
    const double t = static_cast<double>(k) / o.camera_rate_hz;
    cv::Mat rad =
        meter_renderer.renderRadiance(world_.quadsAt(t), bodyPose(trajectory_.at(t)) * rig_.T_b_c[0], world_.sky).image;
    cv::multiply(rad, meter_vignetting, rad);
    meter[k] = cv::mean(rad)[0];
  }
  exposure_ = autoExposureSequence(meter, r);
}

RenderOutput Scene::exposedRadiance(int cam, double t_s) const {
  const RealismOptions& r = options_.realism;
  auto renderAt = [&](double t) {
    return renderers_[cam].renderRadiance(world_.quadsAt(t), bodyPose(trajectory_.at(t)) * rig_.T_b_c[cam], world_.sky);
  };
  RenderOutput centre = renderAt(t_s);
  const int n = r.exposure_time_s > 0 ? r.blur_samples : 1;
  if (n == 1) return centre;
  // n sub-frames evenly over [t − T/2, t + T/2]; the centre one (odd n) is the frame itself.
  cv::Mat sum = cv::Mat::zeros(centre.image.size(), CV_32F);
  for (int i = 0; i < n; ++i) {
    const double t = t_s + r.exposure_time_s * (static_cast<double>(i) / (n - 1) - 0.5);
    if (n % 2 == 1 && i == n / 2)
      sum += centre.image;
    else
      sum += renderAt(t).image;
  }
  centre.image = sum / static_cast<double>(n);
  return centre;
}

Scene::Scene(const SimOptions& o, const std::function<void(World&, const TextureBank&)>& customize) : Scene(o) {
  customize(world_, textures_);
}

SceneFrame Scene::renderFrame(std::size_t k) const {
  SceneFrame f;
  f.index = k;
  f.t_s = static_cast<double>(k) / options_.camera_rate_hz;
  f.t_ns = options_.t0_ns + static_cast<TimeNs>(k) * static_cast<TimeNs>(std::llround(1e9 / options_.camera_rate_hz));
  const std::vector<Quad> quads = world_.quadsAt(f.t_s);
  const BodyState s = trajectory_.at(f.t_s);
  f.T_w_b = bodyPose(s);
  const std::uint64_t seed = options_.scene.runSeed() * 1000003ull;
  if (!options_.realism.enabled) {
    for (int c = 0; c < 2; ++c)
      f.cam[c] = renderers_[c].render(quads, f.T_w_b * rig_.T_b_c[c], world_.sky, options_.image_noise_sigma,
                                      seed + k * 2 + c);
    return f;
  }
  for (int c = 0; c < 2; ++c) {
    f.cam[c] = exposedRadiance(c, f.t_s);
    f.cam[c].image = applySensor(f.cam[c].image, vignetting_[c], exposure_[k], c, options_.realism, seed + k * 2 + c);
  }
  return f;
}

namespace {

/// Coverage statistics from each frame's share of cam0 pixels on moving objects.
Coverage coverageOf(const std::vector<double>& per_frame) {
  Coverage c;
  double sum = 0;
  std::size_t over = 0;
  for (double v : per_frame) {
    sum += v;
    c.max = std::max(c.max, v);
    over += v >= 0.30 ? 1 : 0;
  }
  c.mean = sum / static_cast<double>(per_frame.size());
  c.frames_over_30pct = static_cast<double>(over) / static_cast<double>(per_frame.size());
  return c;
}

/// EuRoC's cam0/cam1 data.csv: one image per stamp, named by it.
void writeImageLists(const fs::path& mav0, const std::vector<TimeNs>& stamps) {
  std::string csv = "#timestamp [ns],filename\n";
  for (TimeNs t : stamps) csv += std::to_string(t) + "," + std::to_string(t) + ".png\n";
  writeText(mav0 / "cam0" / "data.csv", csv);
  writeText(mav0 / "cam1" / "data.csv", csv);
}

/// Renders every frame into mav0/cam{0,1}/{data,mask}/<stamp>.png (and depth/<stamp>.tiff
/// with write_depth) on `threads` threads; returns each frame's share of cam0 pixels on
/// moving objects.
std::vector<double> renderImages(const Scene& scene, const std::vector<TimeNs>& stamps, const fs::path& mav0,
                                 int threads, const std::function<void(std::size_t, std::size_t)>& progress) {
  const bool write_depth = scene.options().write_depth;
  const std::size_t frames = stamps.size();
  std::vector<double> coverage(frames, 0.0);

  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  std::string error;
  auto worker = [&]() {
    try {
      for (std::size_t k = next++; k < frames; k = next++) {
        const SceneFrame f = scene.renderFrame(k);
        const std::string name = std::to_string(stamps[k]) + ".png";
        for (int c = 0; c < 2; ++c) {
          const RenderOutput& r = f.cam[c];
          const fs::path cam = mav0 / ("cam" + std::to_string(c));
          if (!cv::imwrite((cam / "data" / name).string(), r.image) ||
              !cv::imwrite((cam / "mask" / name).string(), r.mask))
            throw InputError((cam / "data" / name).string(), "cannot write image");
          const fs::path depth = cam / "depth" / (std::to_string(stamps[k]) + ".tiff");
          if (write_depth && !cv::imwrite(depth.string(), r.depth))
            throw InputError(depth.string(), "cannot write depth image");
          if (c == 0) coverage[k] = static_cast<double>(cv::countNonZero(r.mask)) / (r.mask.rows * r.mask.cols);
        }
        ++done;
      }
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (error.empty()) error = e.what();
      next = frames;
      failed = true;
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < std::max(1, threads); ++i) pool.emplace_back(worker);
  while (done < frames && !failed) {
    if (progress) progress(done, frames);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  for (auto& th : pool) th.join();
  if (!error.empty()) throw std::runtime_error(error);
  if (progress) progress(frames, frames);

  return coverage;
}

}  // namespace

SimResult simulate(const SimOptions& o, const std::string& out_dir,
                   const std::function<void(std::size_t, std::size_t)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path root(out_dir), mav0 = root / "mav0";
  std::error_code ec;
  std::vector<std::string> subs = {"cam0/data", "cam0/mask", "cam1/data",
                                   "cam1/mask", "imu0",      "state_groundtruth_estimate0"};
  if (o.write_depth) subs.insert(subs.end(), {"cam0/depth", "cam1/depth"});
  for (const std::string& sub : subs) {
    fs::create_directories(mav0 / sub, ec);
    if (ec) throw InputError((mav0 / sub).string(), "cannot create folder: " + ec.message());
  }
  const Scene scene(o);
  const Config& rig = scene.rig();
  const World& world = scene.world();
  const Trajectory& traj = scene.trajectory();

  SimResult result;
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> truth;
  synthesizeImu(traj, o, imu, truth);
  result.imu_samples = imu.size();
  result.path_length_m = traj.pathLength(o.duration_s);
  writeImuAndTruth(mav0, imu, truth);
  writeSensorYamls(mav0, rig, o);
  writeVinsConfig(rig, (root / "config").string(), o.vins_rig.empty() ? "sim_stereo_imu_config.yaml" : rig.path,
                  !o.vins_rig.empty());

  const std::size_t frames = scene.frameCount();
  const TimeNs frame_dt = static_cast<TimeNs>(std::llround(1e9 / o.camera_rate_hz));
  result.frames = frames;
  std::vector<TimeNs> stamps(frames);
  const TimeNs td_ns = static_cast<TimeNs>(std::llround(o.td_s * 1e9));
  for (std::size_t k = 0; k < frames; ++k) stamps[k] = o.t0_ns + static_cast<TimeNs>(k) * frame_dt - td_ns;
  const std::vector<double> coverage = renderImages(scene, stamps, mav0, o.threads, progress);
  writeImageLists(mav0, stamps);

  result.coverage = coverageOf(coverage);
  writeText(root / "meta.json", metaJson(o, world, result, rig).dump(2) + "\n");
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace idyvins::sim
