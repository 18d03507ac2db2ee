#pragma once
// idyvins as a library (DESIGN §3 `pipeline`): one object that takes IMU samples and
// stereo frames in time order and gives back, per frame, the pose, the labelled
// features and the stage timings, and at the end the static and dynamic maps. A ROS
// node, a live camera driver or the `idyvins` command embed it the same way:
//
//   pipeline::System system(loadConfig("config.yaml"));
//   for (const auto& m : measurements)           // time order, IMU before a same-stamp frame
//     if (auto* imu = std::get_if<ImuSample>(&m)) system.addImu(*imu);
//     else if (const FrameOutput* out = system.addFrame(std::get<StereoFrame>(m))) use(*out);
//   const pipeline::Result result = system.finish();      // maps, trajectory, counters
//
// Observers (evaluation against masks, stats, progress) subscribe with addObserver().

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backend/frame_result.h"
#include "config/config.h"
#include "core/measurements.h"
#include "dynamic/dynamic.h"
#include "frontend/feature_frame.h"
#include "imu/spike_gate.h"
#include "map/loop_closer.h"

namespace idyvins::pipeline {

/// Everything the system says about one stereo frame.
struct FrameOutput {
  std::size_t index = 0;                   ///< 0-based count of frames given to the system
  TimeNs t_ns = 0;                         ///< the frame's time stamp
  frontend::FeatureFrame features;         ///< labelled features, removed / lost-moving ones, tracking and filter ms
  backend::FrameResult estimate;           ///< initialized, body state, reset and status, solve and marginalization ms
  std::optional<dynamic::FrameStats> idy;  ///< IDY preprocessing statistics (idy modes only)
  /// Points the front end judged moving at this frame, triangulated in the world from their
  /// stereo match (label kEliminated, id = feature id): they go to the dynamic map.
  std::vector<backend::MapPoint> eliminated_points;
  /// Static landmarks that left the window at this frame (label kStatic, id = landmark id):
  /// the static map grows by these (a live viewer's map; finish() returns all of them and
  /// those still in the window).
  std::vector<backend::MapPoint> new_static_points;
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

/// A reset of the estimator: when, at which frame, and why; and how the trajectory went on.
struct ResetEvent {
  TimeNs t_ns = 0;
  std::size_t frame = 0;
  std::string why;
  /// The first initialized frame after it (-1: none), and how the new segment was put in the
  /// world frame of the last good state (backend::FrameResult::reanchored: "imu",
  /// "extrapolated" or "held"; empty when no state came before).
  TimeNs resumed_t_ns = -1;
  std::string continued_by;
};

/// estimate_extrinsic: the cameras' mounts at the end of a run against the config's.
struct ExtrinsicSummary {
  int mode = 0;  ///< the config's estimate_extrinsic
  backend::ExtrinsicEstimate estimate;
  std::vector<Eigen::Isometry3d> T_b_c;  ///< body_T_cam0/1 as estimated (the stereo pair rigid)
  double rotation_change_deg = 0;        ///< cam0's rotation from the config's
  double translation_change_m = 0;       ///< cam0's translation from the config's
};

/// Counters over a whole run.
struct Summary {
  std::size_t frames = 0;
  /// Frames left unprocessed at finish(): their time on the IMU clock (stamp + td) is after the last IMU sample.
  std::size_t frames_beyond_imu = 0;
  /// IMU samples dropped by addImu: not finite or beyond imu_max_acc / imu_max_gyr, and
  /// stamped at or before the previous sample.
  std::size_t imu_out_of_range = 0, imu_out_of_order = 0;
  /// Short spikes within those limits dropped by the spike gate (imu/spike_gate.h): runs, samples.
  std::size_t imu_spikes = 0, imu_spike_samples = 0;
  double td_s = 0;            ///< camera–IMU time offset at the end (the config's td unless estimated)
  bool td_estimated = false;  ///< the config's estimate_td
  std::optional<ExtrinsicSummary> extrinsic;     ///< estimate_extrinsic 1 or 2
  TimeNs first_t_ns = 0, last_t_ns = 0;          ///< time stamps of the first and last frame
  TimeNs init_t_ns = -1;                         ///< first initialized frame (-1: never)
  std::size_t frames_without_prior = 0;          ///< idy modes: frames the IDY filter saw without a motion prior
  std::size_t frames_stereo_only = 0;            ///< frames carried across an IMU gap by stereo alone (bridge_imu_gaps)
  std::size_t lost_tested = 0, lost_moving = 0;  ///< lost-corner test totals (DESIGN §4.9)
  frontend::TrackLosses lost_tracks, lost_new;   ///< why tracks ended, summed (FeatureFrame)
  double sum_tracking_ms = 0, sum_filter_ms = 0, sum_optimization_ms = 0, sum_marginalization_ms = 0;
  backend::SolveProfile solve_sum;  ///< sums over the frames with a window solve
  std::size_t solves = 0, solves_converged = 0;
  std::vector<ResetEvent> resets;
  std::string last_status;  ///< the estimator's status at the last frame
  /// Why initialization restarted or slid, by the estimator's status ("initializing: PnP
  /// failed, restarting", ...): what whyNoTrajectory (outputs.h) explains.
  std::map<std::string, std::size_t> init_failures;
  std::size_t sum_features = 0;  ///< features of every frame after the filter, summed
};

/// What finish() returns.
struct Result {
  std::vector<backend::MapPoint> static_map;  ///< label kStatic, id = landmark id
  /// Eliminated points (kEliminated, in the order they were found) then confirmed-dynamic
  /// landmarks (kConfirmedDynamic).
  std::vector<backend::MapPoint> dynamic_map;
  std::vector<StampedState> trajectory;  ///< every initialized frame
  Summary summary;
  /// Loop closure (config loop_closure: 1): every initialized frame's pose corrected by the
  /// final pose graph, the loops closed, and what it cost.
  bool loop_enabled = false;
  std::vector<StampedPose> loop_trajectory;
  std::vector<map::LoopEvent> loops;
  map::LoopStats loop_stats;
  /// The static map re-anchored to the corrected poses (map::LoopCloser::correctedLandmarks).
  std::vector<backend::MapPoint> loop_static_map;
};

/// How System runs the two halves of a frame (DESIGN §4.10). The data flow is fixed, so
/// the results never depend on thread timing:
/// - feedback_delay 0 (sequential default): frame k's front end uses the motion prior from
///   the state of frame k−1 and sees a reset detected at frame k−1;
/// - feedback_delay 1: frame k's front end runs before frame k−1's back end has finished,
///   so its prior comes from the state of frame k−2 propagated with the IMU to frame k−1,
///   and a reset detected at frame k−1 reaches the tracker at frame k+1.
/// pipelined = true runs frame k's front end on the calling thread while frame k−1's back
/// end runs on a second thread; it needs feedback_delay 1 and gives exactly the outputs
/// of the sequential run with feedback_delay 1.
struct RunOptions {
  bool pipelined = false;
  int feedback_delay = 0;  ///< 0 or 1 frames
  /// The options of a pipelined run (two threads, feedback_delay 1).
  static RunOptions twoThreads() { return {true, 1}; }
};

/// Throws InputError when System cannot run `config` (the rigs it runs: stereo + IMU); what
/// its constructor refuses, for `info` to say before a run.
void checkRunnable(const Config& config);
/// Throws InputError when config.mode needs masks and the rig's cam0 (whose masks datasets
/// hold) is its right camera.
void checkMaskCamera(const Config& config);

/// The whole per-frame system of one mode: front end (tracker + the mode's filter, IDY
/// motion prior from the estimator's newest state), estimator, maps. One per sequence.
class System {
 public:
  /// Frames that may wait for IMU samples before they are processed without them.
  static constexpr std::size_t kMaxPendingFrames = 20;
  /// Mode from config.mode. Throws InputError unless the config is stereo + IMU,
  /// std::invalid_argument for inconsistent run options.
  explicit System(const Config& config, const RunOptions& run = {});
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  /// Observers are called in the order added, for every frame in order, on the calling
  /// thread, once the frame's back end has finished; not owned.
  void addObserver(FrameObserver& observer) { observers_.push_back(&observer); }
  /// Takes the next IMU sample. Dropped and counted (Summary): a sample not after the previous
  /// one, not finite or beyond imu_max_acc / imu_max_gyr, and the samples of a short spike
  /// (imu/spike_gate.h: a possible spike is held back up to imu_spike_max_ms, so a frame may
  /// wait that much longer for its IMU).
  void addImu(const ImuSample& sample);
  /// Processes one stereo frame (after the IMU samples up to its time stamp). The frame's
  /// time on the IMU clock is its stamp + td (the config's, or the current estimate with
  /// estimate_td); when that is later than the newest IMU sample the frame waits for the next
  /// call (at most kMaxPendingFrames frames wait; finish() processes the rest). Returns the
  /// output of the newest frame whose back end finished during this call: this frame with
  /// feedback_delay 0, the previous one with 1 (null when none finished). Observers see every
  /// frame. The pointer is valid until the next call.
  const FrameOutput* addFrame(const StereoFrame& frame);
  /// Processes the frames waiting for IMU samples that the samples given since now reach
  /// (a live driver calls it after addImu so that a frame whose IMU came late is not held
  /// until the next frame arrives). Returns the number of frames processed. The outputs
  /// are those of the same calls without poll(): only when frames are processed changes.
  std::size_t poll();
  /// Processes the frames still waiting for IMU samples that the samples reach (the others
  /// are counted in Summary::frames_beyond_imu), completes the frame still in flight (its
  /// observers are called), moves the window's
  /// static landmarks into the static map and returns the maps, the trajectory and the
  /// counters. Call once, at the end.
  Result finish();

  Mode mode() const { return mode_; }
  const RunOptions& runOptions() const { return run_; }
  /// Threads the system computes on (1, or 2 when pipelined).
  int threads() const { return run_.pipelined ? 2 : 1; }
  const Config& config() const { return config_; }
  const Summary& summary() const { return summary_; }
  /// The loop closer (null unless the config's loop_closure); read it after finish().
  const map::LoopCloser* loopCloser() const { return loop_.get(); }
  /// Live use: `state`'s pose moved by the loop closer's newest correction (map frame once
  /// relocalized in a loaded map). False without loop closure or before that relocalization.
  bool loopCorrected(const imu::NavState& state, Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b) const {
    return loop_ && loop_->correctNow(state.p_w_b, state.q_w_b, p_w_b, q_w_b);
  }
  /// Starts in a saved map (before the first frame; needs the config's loop_closure): the run
  /// relocalizes against it and keeps closing loops against it (map::LoopCloser::loadMap);
  /// `extend` false: localization only. Throws InputError (naming `source`) when the map was
  /// built with another left camera (model, size, intrinsics, extrinsics: rigFingerprint).
  void loadMap(const map::SavedMap& map, bool extend, const std::string& source = "map");

 private:
  class Worker;
  /// A frame whose front end is done and whose back end is pending or running.
  struct InFlight {
    StereoFrame input;
    FrameOutput out;
    std::vector<ImuSample> imu;  ///< samples up to the frame's time, not yet given to the estimator
  };
  TimeNs imuTime(const StereoFrame& frame) const;  ///< the frame's stamp + the current offset
  bool imuCovers(const StereoFrame& frame) const;  ///< the IMU samples up to imuTime(frame) are here
  void process(const StereoFrame& frame);          ///< front end now, back end now or with the next frame
  frontend::MotionPrior priorFor(TimeNs t_prev, TimeNs t_cur) const;
  void backEnd(InFlight& f);                  ///< estimator and dynamic map of one frame (the worker's job)
  void completeInFlight();                    ///< waits for (or runs) the back end in flight, then finalizes it
  ExtrinsicSummary extrinsicSummary() const;  ///< the estimate at the end against the config's
  void finalize(InFlight& f);
  void mapLostMoving(const frontend::FeatureFrame& ff, FrameOutput& out);
  void mapEliminated(const frontend::FeatureFrame& ff, FrameOutput& out);
  void account(FrameOutput& out);
  void feedLoopCloser(const InFlight& f);  ///< the keyframe that left the window, with its image
  void finishLoops(Result& result);

  Config config_;    ///< leftFirst of the config given
  bool cam0_right_;  ///< the config's cam0 is the right camera: each frame's images swapped on arrival
  Mode mode_;
  RunOptions run_;
  struct Parts;  ///< the front end and the estimator (system.cpp: Ceres and OpenCV stay there)
  std::unique_ptr<Parts> parts_;
  std::vector<FrameObserver*> observers_;
  std::unique_ptr<InFlight> in_flight_;  ///< feedback_delay 1: the frame whose back end is pending
  std::unique_ptr<InFlight> done_;       ///< the frame last finalized (what addFrame returns)
  std::unique_ptr<Worker> worker_;       ///< pipelined: the back-end thread
  imu::SpikeGate spike_gate_;            ///< holds back a possible spike until it is decided
  std::optional<TimeNs> last_imu_t_ns_;  ///< the newest accepted sample's time (held or in imu_); none yet
  std::vector<ImuSample> imu_;           ///< samples not yet handed to the estimator, and those the prior needs
  std::size_t imu_to_estimator_ = 0;     ///< imu_[i] for i < this went to the estimator already
  backend::LatestState snapshot_;        ///< the estimator's newest state after the last finalized frame
  TimeNs last_frame_t_ns_ = -1;          ///< time (IMU clock) of the previous frame given to the front end
  std::deque<StereoFrame> pending_;      ///< frames waiting for the IMU samples up to their time
  double td_s_ = 0;                      ///< camera–IMU offset (s): image stamp + td = IMU clock
  /// The left camera's mount the motion prior uses: the config's, or the estimator's estimate
  /// after the last finalized frame (estimate_extrinsic).
  Eigen::Isometry3d T_b_c0_ = Eigen::Isometry3d::Identity();
  std::optional<backend::ExtrinsicEstimate> extrinsic_;  ///< the newest estimate (estimate_extrinsic)
  Summary summary_;
  std::vector<StampedState> trajectory_;
  std::vector<backend::MapPoint> eliminated_;  ///< dynamic map: triangulated eliminated features
  std::vector<backend::MapPoint> confirmed_;   ///< dynamic map: landmarks the estimator confirmed dynamic
  /// Left and right camera poses of the previous frame (when it was initialized): the
  /// lost-corner test's points are triangulated in the frame they were seen in.
  std::optional<std::pair<Eigen::Isometry3d, Eigen::Isometry3d>> prev_T_w_c_;
  std::unique_ptr<map::LoopCloser> loop_;  ///< config loop_closure: its own thread
  /// Left images of the frames that may still leave the window as keyframes (time on the IMU clock).
  std::deque<std::pair<TimeNs, cv::Mat>> window_images_;
};

/// The left camera a saved map's descriptors and landmarks belong to (model, size, intrinsics,
/// body-camera extrinsics, rounded): maps are refused by a rig with another fingerprint.
std::string rigFingerprint(const Config& config);

/// Pose of a stamped state (for trajectory writers and ATE).
StampedPose toStampedPose(const StampedState& s);

}  // namespace idyvins::pipeline
