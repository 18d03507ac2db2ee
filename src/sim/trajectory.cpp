#include "sim/trajectory.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/so3.h"

namespace idyvins::sim {

using Eigen::Vector3d;

Trajectory::Trajectory(const std::string& scene, std::uint64_t seed, double g_norm, TrajectoryStyle style)
    : style_(style), g_norm_(g_norm) {
  std::mt19937_64 rng(seed * 7919 + 3);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  const double two_pi = 2.0 * M_PI;
  if (scene != "city" && scene != "parking_lot")
    throw std::invalid_argument("unknown scene '" + scene + "' (expected city or parking_lot)");
  if (style == TrajectoryStyle::kHandheld) {
    // Walking at about 1.3 m/s with a 1.8 Hz gait (vertical bob 3 cm, sideways sway at half
    // the step rate), the hand pitching and rolling a few degrees, looking around by ±0.5 rad.
    const double step = two_pi * 1.8;
    if (scene == "city") {
      c0_ = {0.0, 0.0, 1.7};  // along the street near the centre line, below the trucks' roofs
      c1_ = {1.3, 0.0, 0.0};
      waves_[0] = {{{0.25 / (two_pi / 13.0), two_pi / 13.0, phase(rng)}, {0.02, step, phase(rng)}, {0, 1, 0}}};
      waves_[1] = {{{0.5, two_pi / 17.0, phase(rng)}, {0.035, step / 2, phase(rng)}, {0, 1, 0}}};
    } else {
      // Clockwise around the garage centre, between the two traffic loops.
      ellipse_ = true;
      ell_a_ = 13.8;
      ell_b_ = 8.1;
      ell_w_ = -0.15;
      ell_phase_ = phase(rng);
      c0_ = {0.0, 0.0, 1.7};
      waves_[0] = {{{0.3, two_pi / 7.0, phase(rng)}, {0.02, step, phase(rng)}, {0, 1, 0}}};
      waves_[1] = {{{0.3, two_pi / 9.0, phase(rng)}, {0.035, step / 2, phase(rng)}, {0, 1, 0}}};
    }
    waves_[2] = {{{0.1, two_pi / 11.0, phase(rng)}, {0.03, step, phase(rng)}, {0, 1, 0}}};
    yaw_wave_ = {0.5, two_pi / 9.0, phase(rng)};
    pitch_waves_ = {{{0.08, two_pi / 6.3, phase(rng)}, {0.015, step, phase(rng)}}};
    roll_waves_ = {{{0.05, two_pi / 5.1, phase(rng)}, {0.012, step / 2, phase(rng)}}};
    return;
  }
  if (scene == "city") {
    // Along the street (+x) at 1.4-2.6 m/s, close to the centre line, about 2.2 m up.
    c0_ = {0.0, 0.0, 2.2};
    c1_ = {2.0, 0.0, 0.0};
    waves_[0] = {{{0.6 / (two_pi / 11.0), two_pi / 11.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
    waves_[1] = {{{0.5, two_pi / 9.0, phase(rng)}, {0.15, two_pi / 3.7, phase(rng)}, {0, 1, 0}}};
    waves_[2] = {{{0.3, two_pi / 7.0, phase(rng)}, {0.08, two_pi / 2.9, phase(rng)}, {0, 1, 0}}};
    yaw_wave_ = {0.35, two_pi / 8.0, phase(rng)};
  } else if (scene == "parking_lot") {
    // An ellipse around the garage centre at about 2 m/s, 1.5 m up (vehicle-roof height).
    ellipse_ = true;
    ell_phase_ = phase(rng);
    c0_ = {0.0, 0.0, 1.5};
    waves_[0] = {{{0.2, two_pi / 6.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
    waves_[1] = {{{0.2, two_pi / 5.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
    waves_[2] = {{{0.1, two_pi / 4.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
    yaw_wave_ = {0.45, two_pi / 7.0, phase(rng)};
  }
}

Vector3d Trajectory::deriv(double t, int order) const {
  Vector3d out;
  for (int axis = 0; axis < 3; ++axis) {
    double v = 0;
    if (order == 0) v = c0_[axis] + c1_[axis] * t;
    if (order == 1) v = c1_[axis];
    for (const Wave& w : waves_[axis])
      v += w.amp * std::pow(w.omega, order) * std::sin(w.omega * t + w.phase + order * M_PI / 2);
    out[axis] = v;
  }
  if (ellipse_) {
    const double th = ell_w_ * t + ell_phase_;
    const double c = std::cos(th + order * M_PI / 2), s = std::sin(th + order * M_PI / 2);
    const double k = std::pow(ell_w_, order);
    out.x() += ell_a_ * k * c;
    out.y() += ell_b_ * k * s;
  }
  return out;
}

double Trajectory::yaw(double t) const {
  const Vector3d v = deriv(t, 1);
  return std::atan2(v.y(), v.x()) + yaw_wave_.amp * std::sin(yaw_wave_.omega * t + yaw_wave_.phase);
}

Vector3d Trajectory::position(double t) const { return deriv(t, 0); }

Eigen::Quaterniond Trajectory::orientation(double t) const {
  if (style_ == TrajectoryStyle::kHandheld) {
    double pitch = 0, roll = 0;
    for (const Wave& w : pitch_waves_) pitch += w.amp * std::sin(w.omega * t + w.phase);
    for (const Wave& w : roll_waves_) roll += w.amp * std::sin(w.omega * t + w.phase);
    return (Eigen::AngleAxisd(yaw(t), Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3d::UnitY()) *
            Eigen::AngleAxisd(roll, Vector3d::UnitX()))
        .normalized();
  }
  const Vector3d z = (deriv(t, 2) + Vector3d(0, 0, g_norm_)).normalized();
  const double psi = yaw(t);
  const Vector3d h(std::cos(psi), std::sin(psi), 0.0);
  const Vector3d x = (h - h.dot(z) * z).normalized();
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return Eigen::Quaterniond(R).normalized();
}

BodyState Trajectory::at(double t) const {
  BodyState s;
  s.p_w_b = deriv(t, 0);
  s.v_w = deriv(t, 1);
  s.a_w = deriv(t, 2);
  s.q_w_b = orientation(t);
  const double h = 1e-4;
  const Eigen::Quaterniond q0 = orientation(t - h), q1 = orientation(t + h);
  s.omega_b = logQuat(q0.conjugate() * q1) / (2.0 * h);
  // Express the rate at t (the difference above is centred, in the frame at t - h):
  s.omega_b = (s.q_w_b.conjugate() * q0) * s.omega_b;
  return s;
}

double Trajectory::pathLength(double duration) const {
  double len = 0;
  Vector3d prev = position(0);
  for (double t = 0.001; t <= duration + 1e-9; t += 0.001) {
    const Vector3d p = position(t);
    len += (p - prev).norm();
    prev = p;
  }
  return len;
}

}  // namespace idyvins::sim
