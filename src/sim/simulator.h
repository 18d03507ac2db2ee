#pragma once
// `idyvins simulate`: writes a complete EuRoC-layout dataset of a rendered dynamic
// scene with ground truth, masks, a VINS-Fusion config and meta.json.

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/measurements.h"
#include "sim/camera_effects.h"
#include "sim/renderer.h"
#include "sim/trajectory.h"
#include "sim/world.h"

namespace idyvins::sim {

/// IMU error model (continuous-time densities; defaults: ADIS16448 as in EuRoC's sensor.yaml).
struct ImuErrorModel {
  double gyro_density = 1.6968e-4;      ///< rad/s/√Hz
  double gyro_random_walk = 1.9393e-5;  ///< rad/s²/√Hz
  double acc_density = 2.0e-3;          ///< m/s²/√Hz
  double acc_random_walk = 3.0e-3;      ///< m/s³/√Hz
  double gyro_bias0_sigma = 0.003;      ///< rad/s, random initial bias
  double acc_bias0_sigma = 0.05;        ///< m/s², random initial bias
  double scale = 1.0;                   ///< multiplies every term (0 = perfect IMU)
};

/// Which family of sequences: the one the defaults are tuned on, or the validation family
/// no default is tuned on (DESIGN §6): EuRoC's intrinsics without distortion (each camera
/// its own), a slightly misaligned 0.11 m stereo pair, VINS-Fusion's EuRoC IMU noise keys
/// in the config (the IMU itself keeps the ADIS16448 model), other materials and a
/// handheld trajectory. Same scenes, traffic and realism presets.
enum class Family { kStandard, kValidation };
bool parseFamily(const std::string& text, Family& family);
const char* toString(Family family);

/// The cameras' lens: the family's pinhole, a full-frame fisheye of 150° across the image
/// diagonal (both cameras, the family's principal points, the same mounts): Kannala–Brandt
/// (equidistant with small k2 k3) or MEI (ξ 1.2, small k1 k2); or a circular Kannala–Brandt
/// fisheye of 185° across its lens circle, dark outside it.
enum class Lens { kPinhole, kKannalaBrandt, kMei, kKannalaBrandtCircle };
/// "pinhole", "kb", "mei" or "kb185".
bool parseLens(const std::string& text, Lens& lens);
const char* toString(Lens lens);
/// The diagonal field of view of the full-frame fisheye lenses (degrees).
constexpr double kFisheyeDiagonalFovDeg = 150.0;
/// The circular lens's field of view across its lens circle (degrees).
constexpr double kCircleFovDeg = 185.0;
/// Half the lens's field of view where the lens has a circle (rad); π otherwise.
inline double lensHalfFovRad(Lens lens) {
  return lens == Lens::kKannalaBrandtCircle ? 0.5 * kCircleFovDeg * M_PI / 180.0 : M_PI;
}

/// Everything `simulate` needs.
struct SimOptions {
  Family family = Family::kStandard;
  Lens lens = Lens::kPinhole;
  SceneOptions scene;
  double duration_s = 60.0;
  double camera_rate_hz = 20.0;
  double imu_rate_hz = 200.0;
  ImuErrorModel imu;
  double image_noise_sigma = 2.0;  ///< gray levels (realism off)
  /// Camera realism (vignetting, gains, auto-exposure, blur, shot/read noise); disabled
  /// by default: images as before, with image_noise_sigma Gaussian noise.
  RealismOptions realism;
  int threads = 2;
  /// Also write each camera's depth: mav0/cam{0,1}/depth/<stamp>.tiff, float32 z in the
  /// camera frame (m), 0 where no surface (sky); for checking tracks against the scene.
  bool write_depth = false;
  /// Camera–IMU time offset of the written data (s): each image is stamped with its capture
  /// time on the IMU clock minus td_s (VINS-Fusion: image clock + td = IMU clock).
  double td_s = 0.0;
  /// A rig of VINS-Fusion's config folder (sim/vins_rigs.h) in place of the family's: its
  /// cameras, mounts, image size and keys; cam0 looks where the family's cam0 looks, the body
  /// (IMU, ground truth) sits where the rig's mount puts it. Empty: the family's rig.
  std::string vins_rig;
  TimeNs t0_ns = 1'700'000'000'000'000'000;
  double g_norm = 9.81;
};

/// The simulator's stereo rig and the VINS-Fusion config describing it (noise keys in
/// VINS-Fusion's semantics, derived from the IMU error model at scale 1).
Config rigConfig(const SimOptions& options);

/// IMU samples and ground-truth states (at IMU rate) for a trajectory.
void synthesizeImu(const Trajectory& trajectory, const SimOptions& options, std::vector<ImuSample>& imu,
                   std::vector<GroundTruthState>& truth);

/// Coverage statistics of moving objects in cam0.
struct Coverage {
  double mean = 0, max = 0;
  double frames_over_30pct = 0;  ///< fraction of frames with ≥ 30 % of pixels on moving objects
};

/// Summary of a written dataset.
struct SimResult {
  std::size_t frames = 0, imu_samples = 0;
  double path_length_m = 0;
  Coverage coverage;
  double seconds = 0;  ///< wall time
};

/// One rendered stereo frame with its ground truth.
struct SceneFrame {
  std::size_t index = 0;
  TimeNs t_ns = 0;
  double t_s = 0;           ///< seconds since the start
  Eigen::Isometry3d T_w_b;  ///< body pose
  RenderOutput cam[2];      ///< left, right: image, mask, depth
};

/// A scene ready to render in memory: rig, textures, world, trajectory, renderers.
/// renderFrame is const and thread-safe.
class Scene {
 public:
  explicit Scene(const SimOptions& options);
  /// Same, letting the caller add to or change the world (tests, custom scenes).
  Scene(const SimOptions& options, const std::function<void(World&, const TextureBank&)>& customize);
  Scene(const Scene&) = delete;  // renderers refer to the texture bank
  Scene& operator=(const Scene&) = delete;
  std::size_t frameCount() const { return frames_; }
  SceneFrame renderFrame(std::size_t k) const;
  const Config& rig() const { return rig_; }
  const World& world() const { return world_; }
  const Trajectory& trajectory() const { return trajectory_; }
  const SimOptions& options() const { return options_; }

 private:
  SimOptions options_;
  Config rig_;
  TextureBank textures_;
  World world_;
  Trajectory trajectory_;
  std::vector<Renderer> renderers_;
  std::size_t frames_;
  camera::CameraParams cams_[2];  ///< the rendered cameras: the rig's at the config's image size
  cv::Mat vignetting_[2];         ///< realism: V(r) per camera
  std::vector<double> exposure_;  ///< realism: auto-exposure factor per frame
  /// realism: one camera's radiance averaged over the exposure (sub-frames along the
  /// trajectory, vehicles moving); mask and depth at the frame's time.
  RenderOutput exposedRadiance(int cam, double t_s) const;
};

/// Writes the dataset into out_dir (created). `progress(done, total)` is called
/// from the calling thread. Throws InputError if out_dir cannot be written.
SimResult simulate(const SimOptions& options, const std::string& out_dir,
                   const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Writes a VINS-Fusion config (+ camodocal camera files) for a rig into a folder: the family
/// rigs' values rounded as their configs always were, or (`as_published`) every digit.
void writeVinsConfig(const Config& config, const std::string& folder, const std::string& name,
                     bool as_published = false);

}  // namespace idyvins::sim
