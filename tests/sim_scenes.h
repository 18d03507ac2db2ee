#pragma once
// Rendered scenes for the front-end and dynamic-scene tests (the simulator in memory).

#include <Eigen/Geometry>
#include <string>

#include "config/config.h"
#include "frontend/feature_frame.h"
#include "sim/simulator.h"

namespace idyvins::test {

using Eigen::Vector3d;

inline StereoFrame stereo(const sim::SceneFrame& f) {
  StereoFrame s;
  s.t_ns = f.t_ns;
  s.index = f.index;
  s.left = f.cam[0].image;
  s.right = f.cam[1].image;
  return s;
}

inline sim::SimOptions options(const std::string& scene, sim::Level level, double duration, bool opening = false) {
  sim::SimOptions o;
  o.scene.scene = scene;
  o.scene.level = level;
  o.scene.seed = 1;
  o.scene.opening_vehicle = opening;
  o.duration_s = duration;
  return o;
}

/// A city street without traffic plus one vehicle driving along `lane_dir` (default +y: crossing), textured as
/// vehicle 1.
inline sim::Scene crossingVehicleScene(double duration_s, const std::string& type, const Vector3d& size,
                                       const Vector3d& lane_start, double speed,
                                       const Vector3d& lane_dir = Vector3d::UnitY()) {
  return sim::Scene(options("city", sim::Level::kNone, duration_s), [&](sim::World& w, const sim::TextureBank& tex) {
    sim::Vehicle v;
    v.id = 1;
    v.type = type;
    v.size = size;
    v.lane_start = lane_start;
    v.lane_dir = lane_dir;
    v.lane_length = 400;
    v.speed = speed;
    v.texture = tex.index(sim::TextureKind::kVehicle, 1);
    w.vehicles.push_back(v);
  });
}

/// The exact camera motion between two rendered frames as a motion prior.
inline frontend::MotionPrior truePrior(const sim::SceneFrame& prev, const sim::SceneFrame& cur, const Config& rig) {
  const Eigen::Isometry3d T_prev_cur = (prev.T_w_b * rig.T_b_c[0]).inverse() * (cur.T_w_b * rig.T_b_c[0]);
  frontend::MotionPrior p;
  p.valid = true;
  p.q_prev_cur = Eigen::Quaterniond(T_prev_cur.linear());
  p.t_prev_cur = T_prev_cur.translation();
  p.cov_p = Eigen::Matrix3d::Identity() * 1e-4;
  return p;
}

}  // namespace idyvins::test
