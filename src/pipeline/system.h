#pragma once
// idyvins as a library (DESIGN §3 `pipeline`): one object that takes IMU samples and
// stereo frames in time order and gives back, per frame, the pose, the labelled
// features and the stage timings, and at the end the static and dynamic maps. A ROS
// node, a live camera driver or the `idyvins` command embed it the same way:
//
//   pipeline::System system(loadConfig("config.yaml"));
//   for (const auto& m : measurements)           // time order, IMU before a same-stamp frame
//     if (auto* imu = std::get_if<ImuSample>(&m)) system.addImu(*imu);
//     else use(system.addFrame(std::get<StereoFrame>(m)));  // FrameOutput
//   const pipeline::Result result = system.finish();      // maps, trajectory, counters
//
// Observers (evaluation against masks, stats, progress) subscribe with addObserver().

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backend/estimator.h"
#include "core/measurements.h"
#include "dynamic/dynamic.h"
#include "frontend/feature_frame.h"
#include "io/config.h"
#include "pipeline/front_end.h"

namespace idyvins::pipeline {

/// Everything the system says about one stereo frame.
struct FrameOutput {
  std::size_t index = 0;            ///< 0-based count of frames given to the system
  TimeNs t_ns = 0;                  ///< the frame's time stamp
  frontend::FeatureFrame features;  ///< labelled features, removed / lost-moving ones, tracking and filter ms
  backend::FrameResult estimate;    ///< initialized, body state, reset and status, solve and marginalization ms
  std::optional<dynamic::FrameStats> idy;  ///< IDY preprocessing statistics (idy modes only)
  /// Points the front end judged moving at this frame, triangulated in the world from their
  /// stereo match (label 1, id = feature id): they go to the dynamic map.
  std::vector<backend::MapPoint> eliminated_points;
};

/// Receives every frame's output right after the system has computed it.
class FrameObserver {
 public:
  virtual ~FrameObserver() = default;
  /// `input` is the frame as given to addFrame (images, masks); `output` what came of it.
  virtual void onFrame(const StereoFrame& input, const FrameOutput& output) = 0;
};

/// One estimated state with its time stamp (body in the world).
struct StampedState {
  TimeNs t_ns = 0;
  imu::NavState state;
};

/// A reset of the estimator: when, at which frame, and why.
struct ResetEvent {
  TimeNs t_ns = 0;
  std::size_t frame = 0;
  std::string why;
};

/// Counters over a whole run.
struct Summary {
  std::size_t frames = 0;
  TimeNs first_t_ns = 0, last_t_ns = 0;  ///< time stamps of the first and last frame
  TimeNs init_t_ns = -1;                 ///< first initialized frame (-1: never)
  std::size_t frames_without_prior = 0;  ///< idy modes: frames the IDY filter saw without a motion prior
  std::size_t lost_tested = 0, lost_moving = 0;  ///< lost-corner test totals (DESIGN §4.9)
  double sum_tracking_ms = 0, sum_filter_ms = 0, sum_optimization_ms = 0, sum_marginalization_ms = 0;
  backend::SolveProfile solve_sum;  ///< sums over the frames with a window solve
  std::size_t solves = 0, solves_converged = 0;
  std::vector<ResetEvent> resets;
  std::string last_status;  ///< the estimator's status at the last frame
};

/// What finish() returns.
struct Result {
  std::vector<backend::MapPoint> static_map;   ///< label 0, id = landmark id
  /// Eliminated points (label 1, in the order they were found) then confirmed-dynamic
  /// landmarks (label 2).
  std::vector<backend::MapPoint> dynamic_map;
  std::vector<StampedState> trajectory;  ///< every initialized frame
  Summary summary;
};

/// The whole per-frame system of one mode: front end (tracker + the mode's filter, IDY
/// motion prior from the estimator's newest state), estimator, maps. One per sequence.
class System {
 public:
  /// Mode from config.dynamic.mode. Throws InputError unless the config is stereo + IMU.
  explicit System(const Config& config);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  /// Observers are called in the order added, after each frame; not owned.
  void addObserver(FrameObserver& observer) { observers_.push_back(&observer); }
  void addImu(const ImuSample& sample);
  /// Processes one stereo frame (after the IMU samples up to its time stamp).
  const FrameOutput& addFrame(const StereoFrame& frame);
  /// Moves the window's static landmarks into the static map and returns the maps, the
  /// trajectory and the counters. Call once, at the end.
  Result finish();

  Mode mode() const { return mode_; }
  const Config& config() const { return config_; }
  const backend::Estimator& estimator() const { return estimator_; }
  const Summary& summary() const { return summary_; }

 private:
  frontend::MotionPrior priorFor(TimeNs t_ns) const;
  void mapLostMoving(const frontend::FeatureFrame& ff, FrameOutput& out);
  void mapEliminated(const frontend::FeatureFrame& ff, FrameOutput& out);
  void account(FrameOutput& out);

  Config config_;
  Mode mode_;
  FrontEnd front_end_;
  backend::Estimator estimator_;
  std::vector<FrameObserver*> observers_;
  FrameOutput last_;
  Summary summary_;
  std::vector<StampedState> trajectory_;
  std::vector<backend::MapPoint> eliminated_;
  /// Left and right camera poses of the previous frame (when it was initialized): the
  /// lost-corner test's points are triangulated in the frame they were seen in.
  std::optional<std::pair<Eigen::Isometry3d, Eigen::Isometry3d>> prev_T_w_c_;
};

/// Pose of a stamped state (for trajectory writers and ATE).
StampedPose toStampedPose(const StampedState& s);

}  // namespace idyvins::pipeline
