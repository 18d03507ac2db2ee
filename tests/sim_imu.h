#pragma once
// Noiseless IMU along a simulated trajectory, integrated against its own ground truth (the
// simulator's IMU tests).

#include <string>
#include <vector>

#include "imu/preintegration.h"
#include "sim/simulator.h"

namespace idyvins::test {

/// 10 s of noiseless IMU synthesized along `traj`, integrated from the first ground-truth
/// state: the predicted end state, the true one and the number of samples.
struct NoiselessEnd {
  imu::NavState predicted;
  GroundTruthState truth;
  std::size_t samples = 0;
};

inline NoiselessEnd integrateNoiseless(const std::string& scene, const sim::Trajectory& traj) {
  sim::SimOptions o;
  o.scene.scene = scene;
  o.duration_s = 10.0;
  o.imu.scale = 0.0;
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(traj, o, imu, gt);
  const ImuNoise noise{0.1, 0.01, 0.001, 0.0001, o.g_norm};
  const imu::Preintegration pre =
      imu::integrateBetween(imu, imu.front().t_ns, imu.back().t_ns, gt[0].ba, gt[0].bg, noise);
  return {pre.predict({gt[0].q_w_b, gt[0].p_w_b, gt[0].v_w, gt[0].ba, gt[0].bg}), gt.back(), imu.size()};
}

}  // namespace idyvins::test
