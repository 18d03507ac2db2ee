#include <gtest/gtest.h>

#include <array>
#include <random>

#include "backend/imu_factor.h"
#include "backend/marginalization.h"
#include "backend/parameter_blocks.h"
#include "backend/projection_factors.h"
#include "core/so3.h"
#include "cost_check.h"

namespace idyvins::backend {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

std::mt19937 rng(1234);
double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
Vector3d rand3(double s) { return Vector3d(uni(-s, s), uni(-s, s), uni(-s, s)); }
Quaterniond randQ(double s = M_PI) { return expQuat(rand3(s)); }

std::vector<double> poseBlock(const Vector3d& p, const Quaterniond& q) {
  std::vector<double> b(7);
  setPose(p, q, b.data());
  return b;
}

imu::Preintegration randomPreintegration(const Vector3d& ba, const Vector3d& bg) {
  const ImuNoise noise{0.08, 0.004, 0.004, 2e-5, 9.81};
  imu::Preintegration pre(Vector3d(0.3, -0.1, 9.9), Vector3d(0.1, 0.2, -0.1), ba, bg, noise);
  for (int k = 1; k <= 20; ++k)
    pre.push(0.005, Vector3d(0.3, -0.1, 9.9) + rand3(1.0), Vector3d(0.1, 0.2, -0.1) + rand3(0.3));
  return pre;
}

TEST(PoseManifold, PlusMinusRoundTrip) {
  PoseManifold m;
  for (int t = 0; t < 20; ++t) {
    const auto x = poseBlock(rand3(5), randQ());
    Eigen::Matrix<double, 6, 1> d;
    d << rand3(1), rand3(0.5);
    double y[7], back[6];
    ASSERT_TRUE(m.Plus(x.data(), d.data(), y));
    ASSERT_TRUE(m.Minus(y, x.data(), back));
    EXPECT_LT((Eigen::Map<Eigen::Matrix<double, 6, 1>>(back) - d).norm(), 1e-12);
  }
}

TEST(ImuFactor, JacobiansMatchNumericAtRandomStates) {
  for (int t = 0; t < 20; ++t) {
    const Vector3d lin_ba = rand3(0.1), lin_bg = rand3(0.01);
    const imu::Preintegration pre = randomPreintegration(lin_ba, lin_bg);
    ImuFactor factor(&pre);
    auto pi = poseBlock(rand3(5), randQ()), pj = poseBlock(rand3(5), randQ());
    std::vector<double> si(9), sj(9);
    for (auto* s : {&si, &sj}) {
      Eigen::Map<Eigen::Matrix<double, 9, 1>> v(s->data());
      v << rand3(2), lin_ba + rand3(0.05), lin_bg + rand3(0.02);  // biases off the linearization
    }
    test::checkCostFunction(factor, {pi.data(), si.data(), pj.data(), sj.data()}, 1e-6, "imu");
  }
}

TEST(ImuFactor, ResidualIsZeroAtThePredictedState) {
  const imu::Preintegration pre = randomPreintegration(Vector3d::Zero(), Vector3d::Zero());
  imu::NavState si;
  si.q_w_b = randQ();
  si.v_w = rand3(2);
  si.ba = rand3(0.05);
  si.bg = rand3(0.01);
  const imu::NavState sj = pre.predict(si);
  EXPECT_LT(pre.residual(si, sj).norm(), 1e-12);
}

TEST(BiasPriorFactor, ResidualIsTheWhitenedBiasErrorAndItsJacobianMatchesNumeric) {
  const Vector3d ba0 = rand3(0.1), bg0 = rand3(0.01);
  const BiasPriorFactor factor(ba0, bg0, 0.02, 0.001);
  std::vector<double> sb(9);
  Eigen::Map<Eigen::Matrix<double, 9, 1>> v(sb.data());
  v << rand3(2), ba0 + Vector3d(0.04, 0, -0.02), bg0 + Vector3d(0, 0.003, 0);
  const double* blocks[] = {sb.data()};
  Eigen::Matrix<double, 6, 1> r;
  ASSERT_TRUE(factor.Evaluate(blocks, r.data(), nullptr));
  Eigen::Matrix<double, 6, 1> expected;
  expected << 2.0, 0.0, -1.0, 0.0, 3.0, 0.0;  // (b − b0)/σ; the speed is not in it
  EXPECT_LT((r - expected).norm(), 1e-9) << r.transpose();
  test::checkCostFunction(factor, {sb.data()}, 1e-6, "bias prior");
  // A zero sigma leaves that bias free: its rows are zero whatever the bias.
  const BiasPriorFactor acc_only(ba0, bg0, 0.02, 0.0);
  ASSERT_TRUE(acc_only.Evaluate(blocks, r.data(), nullptr));
  EXPECT_LT(r.tail<3>().norm(), 1e-15);
  EXPECT_NEAR(r(0), 2.0, 1e-9);
}

/// Random scene: anchor observation of a point at depth 2..20 m seen from two poses.
struct ProjectionSetup {
  std::vector<double> pose_i, pose_j;
  double inv_depth;
  Vector2d xy_i, xy_j, xy_j_right, xy_i_right;
  Extrinsic ex0, ex1;
};

ProjectionSetup randomProjection() {
  ProjectionSetup s;
  s.ex0.q_b_c = randQ(0.3) * Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY()));
  s.ex0.t_b_c = rand3(0.1);
  s.ex1.q_b_c = s.ex0.q_b_c * randQ(0.02);
  s.ex1.t_b_c = s.ex0.t_b_c + s.ex0.q_b_c * Vector3d(0.11, 0, 0);
  const Vector3d pi = rand3(1), pj = pi + rand3(0.5);
  const Quaterniond qi = randQ(0.5), qj = qi * randQ(0.1);
  s.pose_i = poseBlock(pi, qi);
  s.pose_j = poseBlock(pj, qj);
  s.xy_i = Vector2d(uni(-0.5, 0.5), uni(-0.4, 0.4));
  const double depth = uni(2, 20);
  s.inv_depth = 1.0 / depth;
  // Observations near (not at) the true projections, so residuals are non-zero.
  const Vector3d in_j = transferPoint({s.xy_i.x(), s.xy_i.y(), 1}, s.inv_depth, pi, qi, pj, qj, s.ex0, s.ex0);
  const Vector3d in_jr = transferPoint({s.xy_i.x(), s.xy_i.y(), 1}, s.inv_depth, pi, qi, pj, qj, s.ex0, s.ex1);
  const Vector3d in_ir = transferPoint({s.xy_i.x(), s.xy_i.y(), 1}, s.inv_depth, pi, qi, pi, qi, s.ex0, s.ex1);
  s.xy_j = in_j.head<2>() / in_j.z() + Vector2d(uni(-0.01, 0.01), uni(-0.01, 0.01));
  s.xy_j_right = in_jr.head<2>() / in_jr.z() + Vector2d(uni(-0.01, 0.01), uni(-0.01, 0.01));
  s.xy_i_right = in_ir.head<2>() / in_ir.z() + Vector2d(uni(-0.01, 0.01), uni(-0.01, 0.01));
  return s;
}

TEST(ProjectionFactors, JacobiansMatchNumericAtRandomStates) {
  double scale = 2.5;  // a dynamic-candidate style information scale
  for (int t = 0; t < 50; ++t) {
    ProjectionSetup s = randomProjection();
    ProjectionWeight w{460.0, 1.5, t % 2 ? &scale : nullptr};
    ProjectionTwoFrame one(s.xy_i, s.xy_j, s.ex0, s.ex0, w);
    ProjectionTwoFrame two(s.xy_i, s.xy_j_right, s.ex0, s.ex1, w);
    ProjectionOneFrameTwoCam stereo(s.xy_i, s.xy_i_right, s.ex0, s.ex1, w);
    test::checkCostFunction(one, {s.pose_i.data(), s.pose_j.data(), &s.inv_depth}, 1e-6, "2f1c");
    test::checkCostFunction(two, {s.pose_i.data(), s.pose_j.data(), &s.inv_depth}, 1e-6, "2f2c");
    test::checkCostFunction(stereo, {&s.inv_depth}, 1e-6, "1f2c");
  }
}

TEST(ProjectionFactorsRay, JacobiansMatchNumericAndTheRayAtTheObservationGivesTheFixedRayFactor) {
  double scale = 2.5;
  for (int t = 0; t < 50; ++t) {
    ProjectionSetup s = randomProjection();
    ProjectionWeight w{460.0, 1.5, t % 2 ? &scale : nullptr};
    // The landmark block: the anchor ray away from the anchor observation, the inverse depth.
    std::array<double, 3> lm{s.xy_i.x() + uni(-0.01, 0.01), s.xy_i.y() + uni(-0.01, 0.01), s.inv_depth};
    ProjectionTwoFrameRay one(s.xy_j, s.ex0, s.ex0, w);
    ProjectionTwoFrameRay two(s.xy_j_right, s.ex0, s.ex1, w);
    ProjectionOneFrameTwoCamRay stereo(s.xy_i_right, s.ex0, s.ex1, w);
    AnchorRayObservation anchor(s.xy_i, w);
    test::checkCostFunction(one, {s.pose_i.data(), s.pose_j.data(), lm.data()}, 1e-6, "2f1c ray");
    test::checkCostFunction(two, {s.pose_i.data(), s.pose_j.data(), lm.data()}, 1e-6, "2f2c ray");
    test::checkCostFunction(stereo, {lm.data()}, 1e-6, "1f2c ray");
    test::checkCostFunction(anchor, {lm.data()}, 1e-6, "anchor ray");
    // The anchor residual is the ray's offset from the observation, weighted.
    Vector2d r;
    const double* a_params[] = {lm.data()};
    ASSERT_TRUE(anchor.Evaluate(a_params, r.data(), nullptr));
    EXPECT_LT((r - w.sqrtInfo() * (Vector2d(lm[0], lm[1]) - s.xy_i)).norm(), 1e-12);
    // With the ray on the anchor observation the factors are the fixed-ray ones.
    lm[0] = s.xy_i.x();
    lm[1] = s.xy_i.y();
    Vector2d r_ray, r_fixed;
    const double* ray_params[] = {s.pose_i.data(), s.pose_j.data(), lm.data()};
    const double* fixed_params[] = {s.pose_i.data(), s.pose_j.data(), &s.inv_depth};
    ASSERT_TRUE(two.Evaluate(ray_params, r_ray.data(), nullptr));
    ASSERT_TRUE(
        ProjectionTwoFrame(s.xy_i, s.xy_j_right, s.ex0, s.ex1, w).Evaluate(fixed_params, r_fixed.data(), nullptr));
    EXPECT_LT((r_ray - r_fixed).norm(), 1e-12);
    ASSERT_TRUE(anchor.Evaluate(a_params, r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-12);
  }
}

TEST(ProjectionFactorsTd, JacobiansMatchNumericIncludingTheTimeOffset) {
  double scale = 2.5;
  for (int t = 0; t < 50; ++t) {
    ProjectionSetup s = randomProjection();
    ProjectionWeight w{460.0, 1.5, t % 2 ? &scale : nullptr};
    // Image velocities up to ~1/s on the normalized plane (fast rotation), offsets of ±30 ms.
    const TimedObservation i{s.xy_i, Vector2d(uni(-1, 1), uni(-1, 1)), uni(-0.03, 0.03)};
    const TimedObservation j{s.xy_j, Vector2d(uni(-1, 1), uni(-1, 1)), uni(-0.03, 0.03)};
    const TimedObservation jr{s.xy_j_right, Vector2d(uni(-1, 1), uni(-1, 1)), j.td_obs};
    const TimedObservation ir{s.xy_i_right, Vector2d(uni(-1, 1), uni(-1, 1)), i.td_obs};
    double td = uni(-0.03, 0.03);
    ProjectionTwoFrameTd one(i, j, s.ex0, s.ex0, w);
    ProjectionTwoFrameTd two(i, jr, s.ex0, s.ex1, w);
    ProjectionOneFrameTwoCamTd stereo(i, ir, s.ex0, s.ex1, w);
    test::checkCostFunction(one, {s.pose_i.data(), s.pose_j.data(), &s.inv_depth, &td}, 1e-6, "2f1c td");
    test::checkCostFunction(two, {s.pose_i.data(), s.pose_j.data(), &s.inv_depth, &td}, 1e-6, "2f2c td");
    test::checkCostFunction(stereo, {&s.inv_depth, &td}, 1e-6, "1f2c td");
  }
}

TEST(ProjectionFactorsTd, MovesEachObservationAlongItsVelocityByTheOffsetChange) {
  ProjectionSetup s = randomProjection();
  const ProjectionWeight w{460.0, 1.5, nullptr};
  const TimedObservation i{s.xy_i, Vector2d(0.4, -0.2), 0.002}, j{s.xy_j, Vector2d(-0.3, 0.5), 0.006};
  ProjectionTwoFrameTd timed(i, j, s.ex0, s.ex0, w);
  double td = 0.012;
  const double* params[] = {s.pose_i.data(), s.pose_j.data(), &s.inv_depth, &td};
  Vector2d r_timed, r_fixed;
  ASSERT_TRUE(timed.Evaluate(params, r_timed.data(), nullptr));
  // The fixed-offset factor at xy − (td − td_obs)·v gives the same residual.
  ProjectionTwoFrame fixed(s.xy_i - 0.010 * i.velocity, s.xy_j - 0.006 * j.velocity, s.ex0, s.ex0, w);
  ASSERT_TRUE(fixed.Evaluate(params, r_fixed.data(), nullptr));
  EXPECT_LT((r_timed - r_fixed).norm(), 1e-12);
  // At the offsets the observations were stamped with, nothing moves.
  ProjectionTwoFrameTd still({s.xy_i, i.velocity, td}, {s.xy_j, j.velocity, td}, s.ex0, s.ex0, w);
  ProjectionTwoFrame plain(s.xy_i, s.xy_j, s.ex0, s.ex0, w);
  ASSERT_TRUE(still.Evaluate(params, r_timed.data(), nullptr));
  ASSERT_TRUE(plain.Evaluate(params, r_fixed.data(), nullptr));
  EXPECT_LT((r_timed - r_fixed).norm(), 1e-12);
  EXPECT_GT(r_fixed.norm(), 0.0);
}

std::vector<double> extrinsicBlock(const Extrinsic& e) { return poseBlock(e.t_b_c, e.q_b_c); }

TEST(ProjectionFactorsEx, JacobiansMatchNumericIncludingTheMountAndTheOffset) {
  std::uniform_real_distribution<double> v(-1, 1);
  for (int t = 0; t < 50; ++t) {
    ProjectionSetup s = randomProjection();
    const ProjectionWeight w{460.0, 1.5, nullptr};
    const Extrinsic rel = relative(s.ex0, s.ex1);
    auto ex = extrinsicBlock(s.ex0);
    ProjectionTwoFrameEx left(s.xy_i, s.xy_j, Extrinsic{}, w);
    ProjectionTwoFrameEx right(s.xy_i, s.xy_j_right, rel, w);
    test::checkCostFunction(left, {s.pose_i.data(), s.pose_j.data(), ex.data(), &s.inv_depth}, 1e-6, "2f1c ex");
    test::checkCostFunction(right, {s.pose_i.data(), s.pose_j.data(), ex.data(), &s.inv_depth}, 1e-6, "2f2c ex");
    const TimedObservation i{s.xy_i, Vector2d(v(rng), v(rng)), uni(-0.03, 0.03)};
    const TimedObservation jr{s.xy_j_right, Vector2d(v(rng), v(rng)), uni(-0.03, 0.03)};
    double td = uni(-0.03, 0.03);
    ProjectionTwoFrameExTd timed(i, jr, rel, w);
    test::checkCostFunction(timed, {s.pose_i.data(), s.pose_j.data(), ex.data(), &s.inv_depth, &td}, 1e-6,
                            "2f2c ex td");
  }
}

TEST(ProjectionFactorsEx, GiveTheFixedMountFactorsResidualsAtTheBlocksValue) {
  ProjectionSetup s = randomProjection();
  const ProjectionWeight w{460.0, 1.5, nullptr};
  auto ex = extrinsicBlock(s.ex0);
  const double* with_ex[] = {s.pose_i.data(), s.pose_j.data(), ex.data(), &s.inv_depth};
  const double* fixed[] = {s.pose_i.data(), s.pose_j.data(), &s.inv_depth};
  Vector2d a, b;
  ASSERT_TRUE(
      ProjectionTwoFrameEx(s.xy_i, s.xy_j_right, relative(s.ex0, s.ex1), w).Evaluate(with_ex, a.data(), nullptr));
  ASSERT_TRUE(ProjectionTwoFrame(s.xy_i, s.xy_j_right, s.ex0, s.ex1, w).Evaluate(fixed, b.data(), nullptr));
  EXPECT_LT((a - b).norm(), 1e-9);
  EXPECT_GT(b.norm(), 0.0);
  // compose undoes relative: the right camera's mount from the left one's and the pair.
  const Extrinsic back = compose(s.ex0, relative(s.ex0, s.ex1));
  EXPECT_LT((back.t_b_c - s.ex1.t_b_c).norm(), 1e-12);
  EXPECT_LT(back.q_b_c.angularDistance(s.ex1.q_b_c), 1e-12);
}

TEST(ProjectionFactors, ResidualIsTheNormalizedReprojectionErrorInPixels) {
  ProjectionSetup s = randomProjection();
  ProjectionTwoFrame f(s.xy_i, s.xy_j, s.ex0, s.ex0, {460.0, 1.5, nullptr});
  const double* params[] = {s.pose_i.data(), s.pose_j.data(), &s.inv_depth};
  Vector2d r;
  ASSERT_TRUE(f.Evaluate(params, r.data(), nullptr));
  const Vector3d p =
      transferPoint({s.xy_i.x(), s.xy_i.y(), 1}, s.inv_depth, Eigen::Map<const Vector3d>(s.pose_i.data()),
                    Eigen::Map<const Quaterniond>(s.pose_i.data() + 3), Eigen::Map<const Vector3d>(s.pose_j.data()),
                    Eigen::Map<const Quaterniond>(s.pose_j.data() + 3), s.ex0, s.ex0);
  EXPECT_LT((r - 460.0 / 1.5 * (p.head<2>() / p.z() - s.xy_j)).norm(), 1e-9);
}

TEST(ProjectionFactors, InformationScaleHookReweightsAtRunTime) {
  ProjectionSetup s = randomProjection();
  double scale = 1.0;
  ProjectionTwoFrame f(s.xy_i, s.xy_j, s.ex0, s.ex0, {460.0, 1.5, &scale});
  const double* params[] = {s.pose_i.data(), s.pose_j.data(), &s.inv_depth};
  Vector2d r1, r2;
  ASSERT_TRUE(f.Evaluate(params, r1.data(), nullptr));
  scale = 0.25;  // e.g. 1/m_j with m_j = 4 px²: information / 4, residual / 2
  ASSERT_TRUE(f.Evaluate(params, r2.data(), nullptr));
  EXPECT_LT((r2 - 0.5 * r1).norm(), 1e-12);
  EXPECT_GT(r1.norm(), 0.0);
}

TEST(MarginalizationFactor, JacobiansMatchNumericAwayFromLinearizationPoint) {
  auto prior = std::make_shared<MarginalizationPrior>();
  auto pose = poseBlock(rand3(3), randQ());
  std::vector<double> sb(9);
  for (double& v : sb) v = uni(-1, 1);
  prior->blocks = {pose.data(), sb.data()};
  prior->sizes = {7, 9};
  prior->tangent_sizes = {6, 9};
  prior->x0 = {Eigen::Map<Eigen::VectorXd>(pose.data(), 7), Eigen::Map<Eigen::VectorXd>(sb.data(), 9)};
  prior->J0 = Eigen::MatrixXd::Random(15, 15);
  prior->r0 = Eigen::VectorXd::Random(15);
  MarginalizationFactor f(prior);
  // Move away from x0.
  Eigen::Matrix<double, 6, 1> d;
  d << rand3(0.3), rand3(0.4);
  std::vector<double> moved(7);
  posePlus(pose.data(), d.data(), moved.data());
  for (double& v : sb) v += uni(-0.2, 0.2);
  test::checkCostFunction(f, {moved.data(), sb.data()}, 1e-6, "marginalization");
}

}  // namespace
}  // namespace idyvins::backend
