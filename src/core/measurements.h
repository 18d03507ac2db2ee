#pragma once
// Sensor measurement and state value types shared by readers, simulator and estimator.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "core/time.h"

namespace idyvins {

/// IMU noise model, with VINS-Fusion's semantics (so that VINS-Fusion configs keep
/// their tuning): acc_n, gyr_n are standard deviations of one sample's white
/// noise, acc_w, gyr_w scale the per-step bias random walk (variance acc_w² δt²).
struct ImuNoise {
  double acc_n = 0;      ///< accelerometer white noise, m/s^2
  double gyr_n = 0;      ///< gyroscope white noise, rad/s
  double acc_w = 0;      ///< accelerometer bias random walk, m/s^3
  double gyr_w = 0;      ///< gyroscope bias random walk, rad/s^2
  double g_norm = 9.81;  ///< gravity magnitude, m/s^2
};

/// One IMU sample in the body (IMU) frame: angular rate [rad/s] and specific force [m/s^2].
struct ImuSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyr_b = Eigen::Vector3d::Zero();  ///< w_b, rad/s
  Eigen::Vector3d acc_b = Eigen::Vector3d::Zero();  ///< a_b (specific force), m/s^2
};

/// A pair of 8-bit gray images taken at the same time by cam0 (left) and cam1 (right).
struct StereoFrame {
  TimeNs t_ns = 0;
  std::size_t index = 0;  ///< position of the pair in its dataset
  cv::Mat left;           ///< CV_8UC1
  cv::Mat right;          ///< CV_8UC1, empty for a monocular dataset
  cv::Mat left_mask;      ///< CV_8UC1 object ids (0 = static) when the dataset has masks and they were asked for
};

/// A time-stamped pose of the body in the world: p_w_b and q_w_b (Hamilton, unit).
struct StampedPose {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
};

/// EuRoC ground-truth state: pose, velocity in the world, gyro and accel biases.
struct GroundTruthState {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();  ///< gyro bias, rad/s
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();  ///< accel bias, m/s^2
};

}  // namespace idyvins
