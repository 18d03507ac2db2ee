#include "sim/trajectory.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/so3.h"

namespace idyvins::sim {

using Eigen::Vector3d;

namespace {
// The block: main street (y = 0) between the cross streets at x = 60 and x = 130, back street at y = -40.
constexpr double kBlockX0 = 60.0, kBlockX1 = 130.0, kBlockY0 = 0.0, kBlockY1 = -40.0;
}  // namespace

double Trajectory::BlockRoute::heading(double s, double* curvature) const {
  // Four sides, each a straight then a right turn; heading 0 (east) at the start.
  double psi = 0, remaining = s;
  for (int k = 0; k < 4; ++k) {
    const double straight = k % 2 == 0 ? straight_x : straight_y;
    if (remaining < straight) {
      if (curvature) *curvature = 0;
      return psi;
    }
    remaining -= straight;
    if (remaining < turn_length) {
      const double u = remaining / turn_length;
      if (curvature) *curvature = -(M_PI / 2) * (1 - std::cos(2 * M_PI * u)) / turn_length;
      return psi - (M_PI / 2) * (u - std::sin(2 * M_PI * u) / (2 * M_PI));
    }
    remaining -= turn_length;
    psi -= M_PI / 2;
  }
  if (curvature) *curvature = 0;
  return psi;
}

Eigen::Vector2d Trajectory::BlockRoute::position(double s) const {
  // Cubic Hermite between table samples with the exact tangent (cos psi, sin psi).
  const double x = s / step;
  std::size_t i = static_cast<std::size_t>(std::floor(x));
  if (i + 1 >= table.size()) i = table.size() - 2;
  const double u = x - static_cast<double>(i);
  const double psi0 = heading(static_cast<double>(i) * step, nullptr);
  const double psi1 = heading(std::min(static_cast<double>(i + 1) * step, lap - 1e-12), nullptr);
  const Eigen::Vector2d m0 = step * Eigen::Vector2d(std::cos(psi0), std::sin(psi0));
  const Eigen::Vector2d m1 = step * Eigen::Vector2d(std::cos(psi1), std::sin(psi1));
  const double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * table[i] + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * table[i + 1] + (u3 - u2) * m1;
}

Trajectory::Trajectory(const std::string& scene, std::uint64_t seed, double g_norm, TrajectoryStyle style, bool block)
    : style_(style), g_norm_(g_norm) {
  std::mt19937_64 rng(seed * 7919 + 3);
  if (scene != "city" && scene != "parking_lot")
    throw std::invalid_argument("unknown scene '" + scene + "' (expected city or parking_lot)");
  if (block) {
    if (scene != "city" || style != TrajectoryStyle::kDrone)
      throw std::invalid_argument("the block route is flown by the drone in the city");
    setUpBlockLap(rng);
  } else if (style == TrajectoryStyle::kHandheld) {
    setUpHandheld(scene, rng);
  } else {
    setUpDrone(scene, rng);
  }
}

void Trajectory::setUpBlockLap(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  const double two_pi = 2.0 * M_PI;
  block_ = true;
  BlockRoute& r = route_;
  // How far a turn reaches along its entry (and, by symmetry, its exit) direction.
  double reach = 0;
  const int n_turn = 20000;
  for (int i = 0; i < n_turn; ++i) {  // midpoint rule on a smooth integrand
    const double u = (i + 0.5) / n_turn;
    reach += std::cos((M_PI / 2) * (u - std::sin(2 * M_PI * u) / (2 * M_PI))) * r.turn_length / n_turn;
  }
  r.straight_x = (kBlockX1 - kBlockX0) - 2 * reach;
  r.straight_y = (kBlockY0 - kBlockY1) - 2 * reach;
  r.lap = 2 * (r.straight_x + r.straight_y) + 4 * r.turn_length;
  r.start = Eigen::Vector2d(kBlockX0 + reach, kBlockY0);
  // Position table: RK4 (Simpson) on dp/ds = (cos psi, sin psi), exact psi.
  const std::size_t n = static_cast<std::size_t>(std::ceil(r.lap / r.step)) + 2;
  r.table.resize(n);
  r.table[0] = r.start;
  auto tangent = [&](double s) {
    const double psi = r.heading(std::fmod(s, r.lap), nullptr);
    return Eigen::Vector2d(std::cos(psi), std::sin(psi));
  };
  for (std::size_t i = 1; i < n; ++i) {
    const double s = static_cast<double>(i - 1) * r.step;
    r.table[i] = r.table[i - 1] + r.step / 6 * (tangent(s) + 4 * tangent(s + r.step / 2) + tangent(s + r.step));
  }
  r.s0 = r.lap * std::uniform_real_distribution<double>(0.0, 1.0)(rng);  // where the run starts
  // 4 m up (above the trucks' roofs where the turns cross the lanes), small world-frame waves.
  c0_ = {0.0, 0.0, 4.0};
  waves_[0] = {{{0.15, two_pi / 7.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
  waves_[1] = {{{0.15, two_pi / 6.0, phase(rng)}, {0, 1, 0}, {0, 1, 0}}};
  waves_[2] = {{{0.3, two_pi / 7.0, phase(rng)}, {0.08, two_pi / 2.9, phase(rng)}, {0, 1, 0}}};
  yaw_wave_ = {0.3, two_pi / 8.0, phase(rng)};
}

void Trajectory::setUpHandheld(const std::string& scene, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  const double two_pi = 2.0 * M_PI;
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
}

void Trajectory::setUpDrone(const std::string& scene, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  const double two_pi = 2.0 * M_PI;
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
  if (block_) {
    const double s = std::fmod(route_.s0 + route_.speed * t, route_.lap);
    double kappa = 0;
    const double psi = route_.heading(s, &kappa);
    const double v = route_.speed;
    Eigen::Vector2d d;
    if (order == 0)
      d = route_.position(s);
    else if (order == 1)
      d = v * Eigen::Vector2d(std::cos(psi), std::sin(psi));
    else
      d = v * v * kappa * Eigen::Vector2d(-std::sin(psi), std::cos(psi));
    out.x() += d.x();
    out.y() += d.y();
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

Vector3d Trajectory::position(double t) const {
  return offset_ ? Vector3d(deriv(t, 0) + flownOrientation(t) * t_b_o_) : deriv(t, 0);
}

Eigen::Quaterniond Trajectory::orientation(double t) const {
  return offset_ ? (flownOrientation(t) * q_b_o_).normalized() : flownOrientation(t);
}

void Trajectory::setBodyOffset(const Eigen::Isometry3d& T_b_o) {
  offset_ = true;
  q_b_o_ = Eigen::Quaterniond(T_b_o.linear()).normalized();
  t_b_o_ = T_b_o.translation();
}

Eigen::Quaterniond Trajectory::flownOrientation(double t) const {
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

BodyState Trajectory::flownAt(double t) const {
  BodyState s;
  s.p_w_b = deriv(t, 0);
  s.v_w = deriv(t, 1);
  s.a_w = deriv(t, 2);
  s.q_w_b = flownOrientation(t);
  const double h = 1e-4;
  const Eigen::Quaterniond q0 = flownOrientation(t - h), q1 = flownOrientation(t + h);
  s.omega_b = logQuat(q0.conjugate() * q1) / (2.0 * h);
  // Express the rate at t (the difference above is centred, in the frame at t - h):
  s.omega_b = (s.q_w_b.conjugate() * q0) * s.omega_b;
  return s;
}

BodyState Trajectory::at(double t) const {
  if (!offset_) return flownAt(t);
  // o rides on the flown body: p_o = p_b + R r, v_o = v_b + ω_w × R r; its acceleration by a
  // centred difference of that velocity (1 ms: truncation ~1e-7 m/s², far below any IMU's noise).
  auto velocity = [&](const BodyState& b) { return Vector3d(b.v_w + (b.q_w_b * b.omega_b).cross(b.q_w_b * t_b_o_)); };
  const BodyState b = flownAt(t);
  const double h = 1e-3;
  BodyState s;
  s.p_w_b = b.p_w_b + b.q_w_b * t_b_o_;
  s.v_w = velocity(b);
  s.a_w = (velocity(flownAt(t + h)) - velocity(flownAt(t - h))) / (2.0 * h);
  s.q_w_b = (b.q_w_b * q_b_o_).normalized();
  s.omega_b = q_b_o_.conjugate() * b.omega_b;
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
