// VINS-Fusion's rigs (sim/vins_rigs.h): written from their published numbers, read back
// unchanged; another rig's body on the family's path keeps its IMU consistent with the truth.
// The realism preset without some of its effects.

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "config/config.h"
#include "core/error.h"
#include "sim/camera_effects.h"
#include "sim/simulator.h"
#include "sim/vins_rigs.h"
#include "sim_imu.h"
#include "test_util.h"

namespace idyvins::sim {
namespace {

using Eigen::Vector3d;

Eigen::Isometry3d poseOf(const BodyState& b) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = b.q_w_b.toRotationMatrix();
  T.translation() = b.p_w_b;
  return T;
}

TEST(VinsRigs, EveryConfigWrittenFromItsPublishedNumbersLoadsBackUnchanged) {
  const std::vector<VinsRig>& rigs = vinsRigs();
  ASSERT_EQ(rigs.size(), 18u);  // VINS-Fusion's config/ without its backup file
  std::set<std::string> names;
  for (const VinsRig& r : rigs) {
    SCOPED_TRACE(r.name);
    EXPECT_TRUE(names.insert(r.name).second);
    EXPECT_EQ(findVinsRig(r.name), &r);
    const test::TempDir dir;
    const Config want = vinsRigConfig(r);
    writeVinsConfig(want, dir.path().string(), r.config_file, true);
    const std::string path = (std::filesystem::path(dir.path()) / r.config_file).string();
    const Config got = loadConfig(path);
    // vi_car's cam0 is the right camera: loaded, said once, and run left camera first.
    EXPECT_EQ(got.cam0_right, std::string(r.name) == "vi_car");
    if (got.cam0_right) {
      ASSERT_EQ(got.warnings.size(), 1u);
      EXPECT_NE(got.warnings[0].find("m left of cam0: idyvins tracks on cam1"), std::string::npos) << got.warnings[0];
      const Config left = leftFirst(got);
      EXPECT_FALSE(left.cam0_right);
      EXPECT_EQ(left.cams[0].fx, got.cams[1].fx);
      EXPECT_EQ(left.cam_paths[1], got.cam_paths[0]);
      EXPECT_GT((left.T_b_c[0].inverse() * left.T_b_c[1]).translation().x(), 0.1) << "cam1 right of cam0 now";
    }
    EXPECT_EQ(got.num_cam, r.num_cam);
    EXPECT_EQ(got.use_imu, r.imu);
    EXPECT_EQ(got.image_width, r.width);
    EXPECT_EQ(got.image_height, r.height);
    for (int i = 0; i < r.num_cam; ++i) {
      const camera::CameraParams &a = want.cams[i], &b = got.cams[i];
      EXPECT_EQ(b.type, r.cams[i].mei ? camera::ModelType::kMei : camera::ModelType::kPinhole);
      EXPECT_EQ(b.fx, a.fx);
      EXPECT_EQ(b.fy, a.fy);
      EXPECT_EQ(b.cx, a.cx);
      EXPECT_EQ(b.cy, a.cy);
      EXPECT_EQ(b.xi, a.xi);
      for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(b.dist[k], a.dist[k]);
      // The loader makes the rotations orthonormal (EuRoC's are off by 3e-13).
      EXPECT_LT((got.T_b_c[i].matrix() - want.T_b_c[i].matrix()).cwiseAbs().maxCoeff(), 1e-9);
    }
    if (r.imu) {
      EXPECT_EQ(got.imu.noise.acc_n, r.noise[0]);
      EXPECT_EQ(got.imu.noise.gyr_w, r.noise[3]);
      EXPECT_EQ(got.imu.noise.g_norm, r.noise[4]);
    }
    EXPECT_EQ(got.estimator.estimate_extrinsic, r.estimate_extrinsic);
    EXPECT_EQ(got.estimator.estimate_td, r.estimate_td != 0);
    EXPECT_EQ(got.tracker.max_cnt, r.max_cnt);
  }
  // A few published numbers, so that the table is the configs' and not a copy of itself.
  EXPECT_EQ(findVinsRig("kitti_odom_00_02")->T_b_c[1].m[3], 0.537165718864418);
  EXPECT_EQ(findVinsRig("mynteye_stereo_imu")->cams[0].xi, 1.4456544769803834);
  EXPECT_EQ(findVinsRig("realsense_stereo_imu")->cams[0].k[0], 385.7544860839844);
  EXPECT_EQ(findVinsRig("simulation")->width, 600);
  EXPECT_EQ(findVinsRig("kitti_raw_09_30")->cams[0].width, 1226);  // its camera file's, not the config's 1241
  EXPECT_EQ(findVinsRig("no_such_rig"), nullptr);
}

TEST(VinsRigs, AnotherRigsBodyOnTheFamilysPathKeepsCam0AndItsImuIntegratesToTheTruth) {
  for (const char* name : {"simulation", "realsense_stereo_imu", "kitti_odom_00_02"}) {
    SCOPED_TRACE(name);
    SimOptions family;
    SimOptions o = family;
    o.vins_rig = name;
    const Config rig_family = rigConfig(family), rig = rigConfig(o);
    Trajectory flown("city", 3), carried("city", 3);
    carried.setBodyOffset(rig_family.T_b_c[0] * rig.T_b_c[0].inverse());
    for (double t : {0.0, 3.3, 7.1}) {
      const BodyState f = flown.at(t), c = carried.at(t);
      const Eigen::Isometry3d T_w_c0_family = poseOf(f) * rig_family.T_b_c[0], T_w_c0 = poseOf(c) * rig.T_b_c[0];
      EXPECT_LT((T_w_c0.matrix() - T_w_c0_family.matrix()).cwiseAbs().maxCoeff(), 1e-9) << t;
    }
    const test::NoiselessEnd end = test::integrateNoiseless("city", carried);
    EXPECT_LT((end.predicted.p_w_b - end.truth.p_w_b).norm(), 0.01);
    EXPECT_LT(end.predicted.q_w_b.angularDistance(end.truth.q_w_b), 1e-4);
  }
}

TEST(SimRealism, EffectsRemovedFromThePresetOneByOne) {
  const RealismOptions full = realismPreset("euroc");
  RealismOptions o = full;
  removeRealismEffects(o, "vignetting,blur,exposure");
  EXPECT_EQ(o.vignetting_k1, 0.0);
  EXPECT_EQ(o.vignetting_k2, 0.0);
  EXPECT_EQ(o.exposure_time_s, 0.0);
  EXPECT_EQ(o.blur_samples, 1);
  EXPECT_FALSE(o.auto_exposure);
  EXPECT_EQ(o.defocus_sigma_px, full.defocus_sigma_px);  // the others kept
  EXPECT_EQ(o.full_well, full.full_well);
  EXPECT_TRUE(o.plain_ground);
  EXPECT_EQ(o.preset, "euroc-without-vignetting,blur,exposure");
  o = full;
  removeRealismEffects(o, "gain,defocus,noise,plain");
  EXPECT_EQ(o.gain[1], o.gain[0]);
  EXPECT_EQ(o.defocus_sigma_px, 0.0);
  EXPECT_EQ(o.read_noise, 0.0);
  EXPECT_EQ(o.low_texture_fraction, 0.0);
  EXPECT_FALSE(o.plain_ground);
  EXPECT_TRUE(o.auto_exposure);
  EXPECT_THROW(removeRealismEffects(o, "lens_flare"), std::invalid_argument);
}

}  // namespace
}  // namespace idyvins::sim
