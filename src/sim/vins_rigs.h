#pragma once
// The rigs of VINS-Fusion's config/ folder (its commit: docs/cli.md), from their published numbers: each as a
// Config the simulator renders with and writes back as VINS-Fusion's config and camodocal
// camera files (`idyvins simulate --rig NAME`).

#include <string>
#include <vector>

#include "config/config.h"

namespace idyvins::sim {

/// One camodocal camera file: PINHOLE (fx fy cx cy, k1 k2 p1 p2) or MEI (ξ, γ1 γ2 u0 v0, k1 k2 p1 p2).
struct VinsCamera {
  const char* file;
  bool mei;
  int width, height;  ///< as the camera file states them
  double xi;
  double k[4];     ///< fx fy cx cy, or γ1 γ2 u0 v0
  double dist[4];  ///< k1 k2 p1 p2
};

/// body_T_camX's top three rows, row-major.
struct VinsMount {
  double m[12];
};

/// One VINS-Fusion config. Its rates are not in the config: they are the sensor's usual ones,
/// stated here. A one-camera config renders the second camera of its stereo sibling too (a
/// EuRoC folder has cam1; the run takes cam0 only).
struct VinsRig {
  const char* name;         ///< `simulate --rig` name
  const char* config_file;  ///< VINS-Fusion's file name
  int num_cam;
  bool imu;
  int width, height;  ///< the config's image size (a camera file may state another)
  VinsCamera cams[2];
  VinsMount T_b_c[2];  ///< body_T_cam0, body_T_cam1
  double noise[5];     ///< acc_n gyr_n acc_w gyr_w g_norm
  int estimate_extrinsic, estimate_td, max_cnt;
  double min_dist;
  int flow_back;
  double camera_rate_hz, imu_rate_hz;
};

/// Every rig, in VINS-Fusion's folder order.
const std::vector<VinsRig>& vinsRigs();
/// The rig named `name`, or nullptr.
const VinsRig* findVinsRig(const std::string& name);
/// "euroc_mono_imu, euroc_stereo, …": for help texts and refusals.
std::string vinsRigNames();
/// The rig as the config VINS-Fusion's file describes (cams and T_b_c hold both cameras,
/// num_cam says how many the config names).
Config vinsRigConfig(const VinsRig& rig);

}  // namespace idyvins::sim
