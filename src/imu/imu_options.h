#pragma once
// The IMU's parameters: the single place their defaults live, with their config keys
// (core/params.h): noise (VINS-Fusion's keys), the limits beyond which a sample is dropped,
// the spike gate.

#include "core/measurements.h"
#include "core/params.h"
#include "imu/spike_gate.h"

namespace idyvins::imu {

struct ImuOptions {
  ImuNoise noise;  ///< VINS-Fusion's acc_n, gyr_n, acc_w, gyr_w, g_norm
  /// IMU samples beyond these (or not finite) are dropped and counted (pipeline::Summary):
  /// a robot must live through a few impossible samples. Defaults: 16 g, 35 rad/s.
  double max_acc_mps2 = 16 * 9.80665;
  double max_gyr_radps = 35.0;
  SpikeGateOptions spike;  ///< short spikes within those limits, dropped (imu/spike_gate.h)

  /// Declares every key; the noise keys are required with `noise_required` (a config with imu: 1).
  void declareParams(ParamVisitor& v, bool noise_required) {
    v.section("IMU noise (VINS-Fusion semantics, docs/conventions.md)");
    v.param({"acc_n", "m/s^2, accelerometer noise of one sample", ParamRule::kImuNoise, noise_required}, noise.acc_n);
    v.param({"gyr_n", "rad/s, gyroscope noise of one sample", ParamRule::kImuNoise, noise_required}, noise.gyr_n);
    v.param({"acc_w", "m/s^3, accelerometer bias random walk", ParamRule::kImuNoise, noise_required}, noise.acc_w);
    v.param({"gyr_w", "rad/s^2, gyroscope bias random walk", ParamRule::kImuNoise, noise_required}, noise.gyr_w);
    v.param({"g_norm", "m/s^2, gravity magnitude", ParamRule::kGravity, noise_required}, noise.g_norm);
    v.param({"imu_max_acc", "m/s^2, acceleration norm above which a sample is dropped (counted)", ParamRule::kPositive},
            max_acc_mps2);
    v.param({"imu_max_gyr", "rad/s, angular rate norm above which a sample is dropped (counted)", ParamRule::kPositive},
            max_gyr_radps);
    spike.visit(v);
  }
};

}  // namespace idyvins::imu
