#include <gtest/gtest.h>

#include <cmath>

#include "backend/gauge.h"

namespace idyvins::backend {
namespace {

Eigen::Isometry3d pose(const Eigen::Quaterniond& q, const Eigen::Vector3d& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}

double yawOf(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

TEST(Gauge, UndoesAYawRotationAndTranslationOfTheWholeWindow) {
  // A window of three poses, moved rigidly by a yaw of 0.3 rad and a translation.
  const Eigen::Quaterniond q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, -0.3, 1).normalized()));
  const Eigen::Isometry3d before[3] = {pose(q0, {1, 2, 3}),
                                       pose(q0 * Eigen::Quaterniond(0.99, 0.1, 0, 0).normalized(), {2, 2, 3.5}),
                                       pose(q0, {3, 1, 3})};
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  M.translation() = Eigen::Vector3d(-4, 0.5, 0.2);
  const Eigen::Isometry3d G = gaugeCorrection(before[0], M * before[0]);
  for (const auto& T : before) {
    const Eigen::Isometry3d back = G * M * T;
    EXPECT_LT((back.translation() - T.translation()).norm(), 1e-12);
    EXPECT_LT(Eigen::Quaterniond(back.linear()).angularDistance(Eigen::Quaterniond(T.linear())), 1e-12);
  }
}

TEST(Gauge, KeepsRollAndPitchAsOptimized) {
  // The solve tilted the oldest frame by 2 degrees about x and turned it by 0.1 rad in yaw:
  // the correction restores the yaw and the position, not the tilt (gravity makes it observable).
  const Eigen::Isometry3d before =
      pose(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())), {5, -1, 2});
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()));
  const Eigen::Isometry3d after = pose(turn * tilt * Eigen::Quaterniond(before.linear()), {5.3, -0.8, 2.1});
  const Eigen::Isometry3d G = gaugeCorrection(before, after);
  // A pure rotation about z.
  EXPECT_NEAR(G.linear()(2, 2), 1.0, 1e-12);
  const Eigen::Isometry3d fixed = G * after;
  EXPECT_LT((fixed.translation() - before.translation()).norm(), 1e-12);
  EXPECT_NEAR(yawOf(fixed.linear()), yawOf(before.linear()), 2e-3);  // tilt about x moves the x-axis yaw only slightly
  // The tilt (angle between body z axes seen in the world) is kept.
  const double tilt_after = std::acos(after.linear().row(2).dot(before.linear().row(2)));
  const double tilt_fixed = std::acos(fixed.linear().row(2).dot(before.linear().row(2)));
  EXPECT_NEAR(tilt_fixed, tilt_after, 1e-12);
  EXPECT_NEAR(tilt_fixed, 2.0 * M_PI / 180.0, 1e-9);
}

TEST(Gauge, IdentityWhenNothingMoved) {
  const Eigen::Isometry3d T = pose(Eigen::Quaterniond(0.8, 0.2, -0.3, 0.4).normalized(), {1, 2, 3});
  const Eigen::Isometry3d G = gaugeCorrection(T, T);
  EXPECT_LT((G.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
}

}  // namespace
}  // namespace idyvins::backend
