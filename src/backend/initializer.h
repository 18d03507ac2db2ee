#pragma once
// Stereo-inertial initialization helpers (pure math): gyroscope bias from visual
// rotations, and velocity + gravity from visual poses and preintegrated IMU.

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "core/measurements.h"
#include "imu/preintegration.h"

namespace idyvins::backend {

/// Gyroscope bias bg that best explains the relative rotations of consecutive poses: pre[i]
/// integrates from frame i-1 to frame i (pre[0] unused), each linearized at its own bias.
Eigen::Vector3d solveGyroBias(const std::vector<Eigen::Quaterniond>& q_w_b,
                              const std::vector<const imu::Preintegration*>& pre);

/// Camera–IMU time offset from rotations alone, at initialization: the shift δ (s) of the
/// IMU intervals [t_{i−1} + δ, t_i + δ] within ±max_shift_s that, each with its best
/// gyroscope bias, makes the integrated gyroscope agree best with the relative rotations of
/// the visual body orientations q_w_b at times t_ns (grid of step_s, refined by a parabola).
/// Consecutive pairs whose shifted intervals the samples do not cover for every δ are left
/// out. nullopt when fewer than 3 pairs remain or the best shift lies on the range's edge.
/// contrast, when given: the least cost kContrastShiftS either side of the best shift (a side
/// the range holds) over
/// the best cost (near 1: the rotations do not tell the shift, e.g. at rest or turning at a
/// constant rate).
std::optional<double> alignRotationTimes(const std::vector<Eigen::Quaterniond>& q_w_b, const std::vector<TimeNs>& t_ns,
                                         const std::vector<ImuSample>& imu, double max_shift_s, double step_s = 0.001,
                                         double* contrast = nullptr);

/// The shift either side of the best at which alignRotationTimes measures its contrast (s).
constexpr double kContrastShiftS = 0.03;

/// Result of the linear alignment.
struct Alignment {
  bool ok = false;
  std::vector<Eigen::Vector3d> v_w;  ///< velocities in the visual world frame
  Eigen::Vector3d g_w;               ///< gravity "up" vector in the visual world frame (|g| = g_norm)
  double g_norm_estimated = 0;       ///< |g| before it was fixed
};

/// Solves velocities and gravity from visual body poses (metric, e.g. stereo) and the
/// preintegrations (biases already corrected); checks |g| within 10 % of g_norm.
Alignment alignVelocityGravity(const std::vector<Eigen::Isometry3d>& T_w_b,
                               const std::vector<const imu::Preintegration*>& pre, double g_norm);

}  // namespace idyvins::backend
