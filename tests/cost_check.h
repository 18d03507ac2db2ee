#pragma once
// Checks a Ceres cost function's analytic Jacobians against central differences
// on the manifold (pose blocks of size 7 perturbed by posePlus, others additively).

#include <ceres/cost_function.h>

#include <vector>

#include "backend/parameter_blocks.h"
#include "jacobian_check.h"

namespace idyvins::test {

inline void checkCostFunction(const ceres::CostFunction& cost, const std::vector<double*>& blocks, double rel = 1e-6,
                              const std::string& what = "") {
  const auto& sizes = cost.parameter_block_sizes();
  const int m = cost.num_residuals();
  ASSERT_EQ(sizes.size(), blocks.size());
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jac(sizes.size());
  std::vector<double*> jac_ptrs;
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    jac[k].resize(m, sizes[k]);
    jac_ptrs.push_back(jac[k].data());
  }
  Eigen::VectorXd r(m);
  ASSERT_TRUE(cost.Evaluate(blocks.data(), r.data(), jac_ptrs.data()));
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    const bool pose = sizes[k] == backend::kPoseSize;
    const int tangent = pose ? backend::kPoseTangentSize : sizes[k];
    const std::vector<double> x0(blocks[k], blocks[k] + sizes[k]);
    auto f = [&](const Eigen::VectorXd& d) {
      std::vector<double> x(sizes[k]);
      if (pose) {
        backend::posePlus(x0.data(), d.data(), x.data());
      } else {
        for (int i = 0; i < sizes[k]; ++i) x[i] = x0[i] + d(i);
      }
      std::vector<double*> params = blocks;
      params[k] = x.data();
      Eigen::VectorXd out(m);
      cost.Evaluate(params.data(), out.data(), nullptr);
      return out;
    };
    const Eigen::MatrixXd numeric = numericJacobian(f, tangent);
    expectJacobianNear(jac[k].leftCols(tangent), numeric, rel, what + " block " + std::to_string(k));
    if (pose) {
      const double last_col = jac[k].col(6).norm();
      EXPECT_EQ(last_col, 0.0) << what << ": pose Jacobian's 7th column must be zero";
    }
  }
}

}  // namespace idyvins::test
