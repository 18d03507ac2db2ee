#pragma once
// The sliding window's state as plain data (STYLE 6; what OpenVINS' State is): the frames with
// their parameter blocks and preintegrations, the landmarks, the marginalization prior, the
// time offset and the IMU samples still needed; beside it what outlives a window (the segment
// bookkeeping of resets, the maps). Only the estimator and its rooms change it.

#include <array>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "backend/extrinsic.h"
#include "backend/feature_manager.h"
#include "backend/frame_result.h"
#include "backend/marginalization.h"
#include "core/measurements.h"
#include "imu/preintegration.h"

namespace idyvins::backend {

/// One frame of the window: its pose (p_w_b, q_w_b xyzw) and speed-bias (v_w, ba, bg) blocks.
struct WindowFrame {
  TimeNs t_ns = 0;  ///< IMU clock
  std::array<double, 7> pose{};
  std::array<double, 9> sb{};
  std::unique_ptr<imu::Preintegration> pre;  ///< from the previous frame to this one
  Eigen::Isometry3d T_w_b() const;
  imu::NavState nav() const;
  void setNav(const imu::NavState& s);
};

/// The window: frames 0..count (the oldest first), landmarks, prior, offset, IMU samples.
struct WindowState {
  std::array<WindowFrame, kWindowSize + 1> frames;
  int count = -1;            ///< index of the newest frame (-1: empty)
  bool initialized = false;  ///< gravity-aligned, solved
  FeatureManager fm;
  std::shared_ptr<MarginalizationPrior> prior;  ///< null before the first keyframe left the window
  double td_s = 0;                              ///< camera–IMU time offset (s), a solver block with estimate_td
  std::vector<ImuSample> imu;                   ///< samples from the oldest frame on (and the last good state's)
  /// The body poses of frames 0..count.
  std::vector<Eigen::Isometry3d> poses() const;
};

/// What carries a trajectory across a reset (DESIGN §4.11): the last good state, and how the
/// next segment starts from it.
struct SegmentState {
  std::optional<imu::NavState> last_good;  ///< after the newest successful frame
  TimeNs last_good_t_ns = 0;
  bool reanchor_pending = false;  ///< a reset happened since: the next initialization continues from last_good
  /// Frames solved since this segment's initialization, and whether the last good state came
  /// late enough in its segment for its biases to be trusted after a failure (kSettledFrames).
  int frames = 0;
  bool last_good_settled = false;
  /// The last good state's biases (ba, bg), tying the first window after a failure until its
  /// first marginalization prior (EstimatorOptions::reset_bias_prior_acc, _gyr).
  std::optional<Eigen::Matrix<double, 6, 1>> bias_anchor;
  bool td_restarted = false;  ///< the initialization restarted once for the offset (since the last failure)
  /// estimate_td: the initialization's PnP body poses and their times, collected over
  /// kTdSearchSpanS while the window slides (slide() keeps WindowState::imu from the first).
  std::vector<Eigen::Isometry3d> td_poses;
  std::vector<TimeNs> td_times;
};

/// The left camera's mount while estimate_extrinsic refines it (backend/extrinsic.h); it outlives
/// windows: a reset keeps the estimate.
struct ExtrinsicState {
  std::array<double, 7> block{};    ///< T_b_c0 as a pose block (t, q xyzw), the window's while `open`
  Extrinsic start;                  ///< the prior's centre: the config's mount, or the hand–eye rotation's (2)
  Extrinsic T_c0_c1;                ///< the stereo pair's relative pose, rigid
  bool open = false;                ///< in the window's solves, once the motion first excited it
  bool rotation_known = true;       ///< estimate_extrinsic 2: false until the hand–eye rotation converged
  std::vector<RotationPair> pairs;  ///< estimate_extrinsic 2: gyroscope and track rotations so far
  std::optional<PoseSigma> sigma;   ///< from the newest marginalization prior holding the block
};

/// The maps the window feeds (DESIGN §4.7).
struct MapState {
  std::vector<MapPoint> static_points;  ///< static landmarks that left the window
  std::set<std::uint64_t> mapped;       ///< ids in a map already (static or confirmed dynamic)
  /// Confirmed-dynamic landmark ids (DESIGN §4.6): they left the window for good, so later
  /// observations of the same front-end track are ignored.
  std::set<std::uint64_t> dynamic_ids;
};

}  // namespace idyvins::backend
