#pragma once
// IMU preintegration between two frames i and j on the manifold (midpoint rule),
// with the 15x15 covariance recursion Σ ← F Σ Fᵀ + V Q Vᵀ (F = I + Fc δt, V = G δt),
// the bias Jacobians for first-order bias correction, and repropagation.
//
// Error-state order (15): δp(0) δθ(3) δv(6) δba(9) δbg(12).
// Noise order (18): n_a0 n_g0 n_a1 n_g1 n_ba n_bg.
// World gravity: a_w = R_w_b (a_b − ba) − g_w with g_w = (0, 0, g_norm), z up.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "core/measurements.h"

namespace idyvins::imu {

using Matrix15 = Eigen::Matrix<double, 15, 15>;
using Vector15 = Eigen::Matrix<double, 15, 1>;

/// Error-state offsets.
enum StateIndex : int { kP = 0, kR = 3, kV = 6, kBa = 9, kBg = 12 };

/// Navigation state of the body in the world: R_w_b, p_w_b, v_w, biases.
struct NavState {
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
};

/// Relative body motion between two frames: R_bi_bj, p_bi_bj (in bi) and the
/// 3x3 position block of the preintegration covariance (DESIGN §4.1).
struct RelativeMotion {
  Eigen::Quaterniond q_bi_bj = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_bi_bj = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_p = Eigen::Matrix3d::Zero();
};

/// Preintegrated IMU measurements from frame i to frame j.
class Preintegration {
 public:
  /// Starts at the sample (acc0, gyr0) taken at frame i, with linearization biases.
  Preintegration(const Eigen::Vector3d& acc0, const Eigen::Vector3d& gyr0, const Eigen::Vector3d& ba,
                 const Eigen::Vector3d& bg, const ImuNoise& noise);

  /// Integrates one step of dt seconds up to the sample (acc1, gyr1).
  void push(double dt, const Eigen::Vector3d& acc1, const Eigen::Vector3d& gyr1);

  /// Re-integrates every stored sample with new linearization biases.
  void repropagate(const Eigen::Vector3d& ba, const Eigen::Vector3d& bg);

  /// True when the biases moved far enough from the linearization point that a
  /// first-order correction is no longer good (then call repropagate).
  bool needsRepropagation(const Eigen::Vector3d& ba, const Eigen::Vector3d& bg) const;

  /// Bias-corrected deltas (first order) for biases ba, bg.
  Eigen::Vector3d correctedDeltaP(const Eigen::Vector3d& ba, const Eigen::Vector3d& bg) const;
  Eigen::Vector3d correctedDeltaV(const Eigen::Vector3d& ba, const Eigen::Vector3d& bg) const;
  Eigen::Quaterniond correctedDeltaQ(const Eigen::Vector3d& bg) const;

  /// 15-dim residual between states i and j (unweighted), for gravity magnitude g.
  Vector15 residual(const NavState& si, const NavState& sj) const;

  /// Predicts state j from state i (bias-corrected deltas; biases carried over).
  NavState predict(const NavState& si) const;

  /// Relative body motion and position covariance (for the dynamic motion prior).
  RelativeMotion relativeMotion(const NavState& si) const;

  double sumDt() const { return sum_dt_; }
  const Eigen::Vector3d& deltaP() const { return delta_p_; }
  const Eigen::Vector3d& deltaV() const { return delta_v_; }
  const Eigen::Quaterniond& deltaQ() const { return delta_q_; }
  const Matrix15& jacobian() const { return jacobian_; }
  const Matrix15& covariance() const { return covariance_; }
  const Eigen::Vector3d& linearizedBg() const { return bg_; }
  const Eigen::Vector3d& gravity() const { return g_w_; }

 private:
  struct Sample {
    double dt;
    Eigen::Vector3d acc, gyr;
  };
  void reset();
  void step(double dt, const Eigen::Vector3d& acc1, const Eigen::Vector3d& gyr1);

  Eigen::Vector3d acc0_first_, gyr0_first_;
  Eigen::Vector3d acc0_, gyr0_;
  Eigen::Vector3d ba_, bg_;
  Eigen::Matrix<double, 18, 1> noise_diag_;  ///< diagonal of Q
  Eigen::Vector3d g_w_;
  double sum_dt_ = 0;
  Eigen::Vector3d delta_p_, delta_v_;
  Eigen::Quaterniond delta_q_;
  Matrix15 jacobian_, covariance_;
  std::vector<Sample> samples_;
};

/// Integrates IMU samples from state si at time t_i to time t_j (midpoint rule,
/// interpolating the end samples); samples must cover [t_i, t_j].
/// Returns the preintegration; used for prediction and for the motion prior.
Preintegration integrateBetween(const std::vector<ImuSample>& samples, TimeNs t_i, TimeNs t_j,
                                const Eigen::Vector3d& ba, const Eigen::Vector3d& bg, const ImuNoise& noise);

}  // namespace idyvins::imu
