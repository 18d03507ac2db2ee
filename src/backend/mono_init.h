#pragma once
// Monocular initialization helpers (pure math): the window's structure from motion up to
// scale (VINS-Mono's order: a reference frame with enough parallax to the newest, their
// relative pose from the essential matrix, the other frames by PnP, a bundle adjustment),
// and the alignment of those poses with the IMU that adds the metric scale.

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "backend/initializer.h"
#include "imu/preintegration.h"

namespace idyvins::backend {

/// One feature track of the window: normalized left-camera points in the consecutive
/// frames start_frame, start_frame + 1, ...
struct MonoTrack {
  int start_frame = 0;
  std::vector<Eigen::Vector2d> xy;
};

/// Thresholds of monocularStructure.
struct MonoSfmOptions {
  double min_parallax_px = 30.0;  ///< mean parallax of the reference pair (VINS-Mono's 30 px)
  int min_pair_tracks = 20;       ///< tracks the reference pair shares
  int min_pair_inliers = 12;      ///< essential-matrix inliers of the reference pair
  int min_pnp_points = 10;        ///< triangulated points a frame's PnP needs
  double ransac_px = 0.3;         ///< essential-matrix RANSAC threshold (px)
  double max_rms_px = 2.0;        ///< after the bundle adjustment
};

/// The gyroscope's word on the window's rotations: q_prev_c[i], the camera's rotation from
/// frame i − 1 to frame i (q_c(i−1)_c(i); [0] unused), with its standard deviation (rad per
/// axis). The bundle adjustment holds the cameras to it: a single camera's forward motion
/// trades rotation against translation (the bas-relief ambiguity) far more than a
/// gyroscope's rotation is wrong over one frame.
struct MonoRotationPrior {
  std::vector<Eigen::Quaterniond> q_prev_c;
  double sigma_rad = 0;
};

/// The window's camera poses up to scale: the world is the reference frame's camera, and the
/// newest camera is 1 (unit) from it.
struct MonoStructure {
  std::vector<Eigen::Isometry3d> T_w_c;  ///< one per frame
  int reference = -1;                    ///< the frame paired with the newest
  int points = 0;                        ///< triangulated tracks in the bundle adjustment
  double rms_px = 0;                     ///< their reprojection error after it
};

/// Structure from motion over `frames` window frames (the newest is frames − 1); nullopt with
/// `why` set when no frame has enough parallax to the newest, a PnP fails, or the adjustment
/// leaves a large error.
std::optional<MonoStructure> monocularStructure(const std::vector<MonoTrack>& tracks, int frames, double focal_px,
                                                const MonoSfmOptions& options, std::string& why,
                                                const MonoRotationPrior* prior = nullptr);

/// Alignment with the metric scale: body orientations q_w_b, camera positions p_w_c known up to
/// the scale s (p_w_b = s p_w_c − R_w_b t_b_c), preintegrations pre[i] from frame i − 1 to i
/// (pre[0] unused, biases corrected). Solves velocities, gravity and s (VINS-Mono's linear
/// alignment with the gravity refined on its sphere); ok when |g| is within 10 % of g_norm
/// before the refinement and s > 0.
struct ScaledAlignment : Alignment {
  double scale = 0;
  double scale_sigma = 0;  ///< relative standard deviation of the scale, from the residuals' spread
};
ScaledAlignment alignWithScale(const std::vector<Eigen::Quaterniond>& q_w_b, const std::vector<Eigen::Vector3d>& p_w_c,
                               const Eigen::Vector3d& t_b_c, const std::vector<const imu::Preintegration*>& pre,
                               double g_norm);

}  // namespace idyvins::backend
