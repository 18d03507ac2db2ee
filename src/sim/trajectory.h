#pragma once
// Smooth, drone-like body trajectories with analytic position derivatives.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace idyvins::sim {

/// Kinematic state of the body at one instant.
struct BodyState {
  Eigen::Vector3d p_w_b, v_w, a_w;  ///< position, velocity, acceleration in the world
  Eigen::Quaterniond q_w_b;         ///< orientation
  Eigen::Vector3d omega_b;          ///< angular rate in the body frame (rad/s)
};

/// How the rig is carried.
enum class TrajectoryStyle {
  kDrone,     ///< a quadrotor: roll/pitch from the thrust direction (the tuning suites)
  kHandheld,  ///< walked by a person: gait bob and sway, looking around, roll/pitch of the hand
};

/// A trajectory p(t) = c0 + c1 t + Σ A sin(ω t + φ) per axis (plus an ellipse in the
/// parking lot), yaw following the velocity heading plus an oscillation; roll/pitch
/// from the thrust direction (a_w + g ẑ), as a quadrotor flies, or (handheld) small
/// oscillations of the hand and the gait.
class Trajectory {
 public:
  /// Trajectory for a scene ("city" or "parking_lot"), phases from the seed.
  /// `block`: laps around the city block (drone style only).
  Trajectory(const std::string& scene, std::uint64_t seed, double g_norm = 9.81,
             TrajectoryStyle style = TrajectoryStyle::kDrone, bool block = false);
  BodyState at(double t) const;
  Eigen::Quaterniond orientation(double t) const;
  Eigen::Vector3d position(double t) const;
  /// From now on the body is another frame o rigidly attached to the one flown (T_b_o: o's
  /// pose in it): at, orientation and position describe o (another rig's IMU on the same path).
  void setBodyOffset(const Eigen::Isometry3d& T_b_o);
  /// Path length over [0, duration] (numerical, 1 ms steps).
  double pathLength(double duration) const;

 private:
  struct Wave {
    double amp, omega, phase;
  };
  Eigen::Vector3d deriv(double t, int order) const;
  Eigen::Quaterniond flownOrientation(double t) const;
  BodyState flownAt(double t) const;
  bool offset_ = false;
  Eigen::Quaterniond q_b_o_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_b_o_ = Eigen::Vector3d::Zero();
  double yaw(double t) const;
  void setUpBlockLap(std::mt19937_64& rng);                            ///< the drone's lap of a city block
  void setUpHandheld(const std::string& scene, std::mt19937_64& rng);  ///< a walk with the rig in hand
  void setUpDrone(const std::string& scene, std::mt19937_64& rng);     ///< the tuning suites' drone
  std::array<double, 3> c0_{}, c1_{};
  std::array<std::array<Wave, 3>, 3> waves_{};
  bool ellipse_ = false;  ///< parking lot: ellipse around the centre
  double ell_a_ = 14, ell_b_ = 8, ell_w_ = 0.19, ell_phase_ = 0;
  /// Laps around the city block: a rounded rectangle at constant speed whose turns have a
  /// smooth curvature (sin² profile, so acceleration and angular rate stay continuous).
  struct BlockRoute {
    double speed = 2.2, turn_length = 16.0, s0 = 0;
    double straight_x = 0, straight_y = 0, lap = 0;  ///< lengths (m)
    Eigen::Vector2d start = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector2d> table;  ///< position every `step` metres along the lap
    double step = 0.02;
    double heading(double s, double* curvature) const;  ///< s in [0, lap)
    Eigen::Vector2d position(double s) const;
  };
  bool block_ = false;
  BlockRoute route_;
  Wave yaw_wave_{0, 1, 0};
  std::array<Wave, 2> pitch_waves_{}, roll_waves_{};  ///< handheld: pitch and roll (rad)
  TrajectoryStyle style_ = TrajectoryStyle::kDrone;
  double g_norm_;
};

}  // namespace idyvins::sim
