#pragma once
// The one numerical-differentiation checker every analytic Jacobian is tested with:
// central differences of a function of a tangent-space perturbation δ.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <functional>

namespace idyvins::test {

/// Central-difference Jacobian of f(δ) at δ = 0 (f returns the residual for a
/// perturbation δ applied on the manifold by the caller).
inline Eigen::MatrixXd numericJacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, int tangent_dim,
                                       double h = 1e-6) {
  const Eigen::VectorXd f0 = f(Eigen::VectorXd::Zero(tangent_dim));
  Eigen::MatrixXd J(f0.size(), tangent_dim);
  for (int k = 0; k < tangent_dim; ++k) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(tangent_dim);
    d(k) = h;
    J.col(k) = (f(d) - f(-d)) / (2.0 * h);
  }
  return J;
}

/// Asserts ‖analytic − numeric‖_F ≤ rel · max(‖numeric‖_F, 1).
inline void expectJacobianNear(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric, double rel = 1e-6,
                               const std::string& what = "") {
  ASSERT_EQ(analytic.rows(), numeric.rows()) << what;
  ASSERT_EQ(analytic.cols(), numeric.cols()) << what;
  const double scale = std::max(numeric.norm(), 1.0);
  EXPECT_LE((analytic - numeric).norm(), rel * scale) << what << "\nanalytic:\n"
                                                      << analytic << "\nnumeric:\n"
                                                      << numeric;
}

}  // namespace idyvins::test
