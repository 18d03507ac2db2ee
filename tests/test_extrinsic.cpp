// Online extrinsic calibration's pure math (backend/extrinsic.h): the pose prior, the marginal
// σ of a block in a prior, the hand–eye rotation and the camera rotation from tracks.

#include <gtest/gtest.h>

#include <random>

#include "backend/extrinsic.h"
#include "backend/parameter_blocks.h"
#include "core/so3.h"
#include "cost_check.h"

namespace idyvins::backend {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

std::mt19937 ex_rng(99);
Vector3d gauss3(double s) {
  std::normal_distribution<double> n(0, s);
  return Vector3d(n(ex_rng), n(ex_rng), n(ex_rng));
}

TEST(PosePriorFactor, ResidualIsTheWhitenedPoseErrorAndItsJacobianMatchesNumeric) {
  Extrinsic at;
  at.q_b_c = expQuat(Vector3d(0.3, -1.2, 0.5));
  at.t_b_c = Vector3d(0.1, -0.05, 0.02);
  const PosePriorFactor prior(at, 0.05, 5.0 * M_PI / 180.0);
  const Quaterniond q = at.q_b_c * expQuat(Vector3d(0.01, 0, -0.02));
  std::vector<double> x(7);
  setPose(at.t_b_c + Vector3d(0.02, 0, -0.01), q, x.data());
  const double* blocks[] = {x.data()};
  Eigen::Matrix<double, 6, 1> r;
  ASSERT_TRUE(prior.Evaluate(blocks, r.data(), nullptr));
  const double per_rad = 180.0 / (5.0 * M_PI);
  EXPECT_NEAR(r(0), 0.4, 1e-12);
  EXPECT_NEAR(r(2), -0.2, 1e-12);
  EXPECT_NEAR(r(3), 0.01 * per_rad, 1e-5);  // 2 vec(q0⁻¹q) ≈ the rotation vector (2 sin(θ/2) ≈ θ)
  EXPECT_NEAR(r(5), -0.02 * per_rad, 1e-5);
  test::checkCostFunction(prior, {x.data()}, 1e-6, "pose prior");
  const PosePriorFactor translation_only(at, 0.05, 0.0);
  ASSERT_TRUE(translation_only.Evaluate(blocks, r.data(), nullptr));
  EXPECT_EQ(r.tail<3>().norm(), 0.0);
}

TEST(MarginalSigma, IsTheBlocksMarginalStandardDeviationUnderAGaugeFreedom) {
  // Two blocks: a pose block (6 tangent) and a scalar s; the information couples them and leaves
  // one direction of the scalar block free (a gauge): the pose's marginal σ must be its own.
  MarginalizationPrior p;
  double pose[7] = {0, 0, 0, 0, 0, 0, 1}, gauge[2] = {0, 0};
  p.blocks = {pose, gauge};
  p.sizes = {7, 2};
  p.tangent_sizes = {6, 2};
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(7, 8);
  const double sigma_t = 0.01, sigma_r = 0.002;
  for (int i = 0; i < 3; ++i) J(i, i) = 1.0 / sigma_t, J(i + 3, i + 3) = 1.0 / sigma_r;
  J(6, 6) = 1.0;  // only the first scalar is observed; the second is free
  p.J0 = J;
  const auto s = marginalSigma(p, pose);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->t_m, sigma_t, 1e-9);
  EXPECT_NEAR(s->rot_rad, sigma_r, 1e-9);
  double other[7];
  EXPECT_FALSE(marginalSigma(p, other));
}

/// Rotation pairs of a rig with mount q_b_c turning about varied axes, with noise on the
/// camera's rotations and one wrong pair.
std::vector<RotationPair> rotationPairs(const Quaterniond& q_b_c, int n, double noise_rad) {
  std::vector<RotationPair> pairs;
  for (int k = 0; k < n; ++k) {
    const Quaterniond q_body = expQuat(gauss3(0.08));
    const Quaterniond q_cam = q_b_c.conjugate() * q_body * q_b_c * expQuat(gauss3(noise_rad));
    pairs.push_back({q_body, q_cam});
  }
  pairs[n / 2].q_cam = expQuat(Vector3d(0.3, 0, 0));  // a pair from a bad essential matrix
  return pairs;
}

TEST(HandEyeRotation, RecoversTheMountFromRotationPairs) {
  const Quaterniond truth = expQuat(Vector3d(-1.2, 1.2, -1.2));  // a camera looking along the body's x
  const auto q = handEyeRotation(rotationPairs(truth, 30, 0.002));
  ASSERT_TRUE(q);
  EXPECT_LT(q->angularDistance(truth) * 180 / M_PI, 0.3);
}

TEST(HandEyeRotation, WaitsWhileTheRotationsDoNotConstrainTheMount) {
  // Rotation about one axis only: the mount's rotation about it is free, so no answer yet.
  const Quaterniond truth = expQuat(Vector3d(0.2, 1.0, -0.4));
  std::vector<RotationPair> pairs;
  for (int k = 0; k < 30; ++k) {
    const Quaterniond q_body = expQuat(Vector3d(0, 0, 0.05 * (1 + k % 3)));
    pairs.push_back({q_body, truth.conjugate() * q_body * truth});
  }
  EXPECT_FALSE(handEyeRotation(pairs));
  EXPECT_FALSE(handEyeRotation({pairs[0], pairs[1]}));  // too few pairs
}

TEST(RelativeCameraRotation, IsTheRotationBetweenTwoViewsOfAScene) {
  const Quaterniond q_a_b = expQuat(Vector3d(0.02, -0.05, 0.03));  // camera b in camera a
  const Vector3d t_a_b(0.3, 0.05, 0.1);
  std::uniform_real_distribution<double> u(-1, 1), d(3, 20);
  std::vector<Vector2d> xy_a, xy_b;
  for (int k = 0; k < 80; ++k) {
    const Vector3d p_a = Vector3d(u(ex_rng), 0.8 * u(ex_rng), 1.0) * d(ex_rng);
    const Vector3d p_b = q_a_b.conjugate() * (p_a - t_a_b);
    xy_a.push_back(p_a.head<2>() / p_a.z());
    xy_b.push_back(p_b.head<2>() / p_b.z() + gauss3(0.3 / 460).head<2>());
  }
  const auto q = relativeCameraRotation(xy_a, xy_b, 460.0);
  ASSERT_TRUE(q);
  EXPECT_LT(q->angularDistance(q_a_b) * 180 / M_PI, 0.3);
  xy_a.resize(10);
  xy_b.resize(10);
  EXPECT_FALSE(relativeCameraRotation(xy_a, xy_b, 460.0));
}

}  // namespace
}  // namespace idyvins::backend
