#include "backend/window_problem.h"

#include <ceres/problem.h>

#include <stdexcept>

namespace idyvins::backend {

void WindowProblem::addParameterBlock(double* x, int size, const ceres::Manifold* manifold) {
  const auto it = index_.find(x);
  if (it != index_.end()) {  // added before (by a residual block): as Ceres, the manifold given now holds
    Block& b = blocks_[static_cast<std::size_t>(it->second)];
    if (b.size != size)
      throw std::invalid_argument("addParameterBlock: a block's size differs from the one it was added with");
    if (manifold) b.manifold = manifold;
    log_.emplace_back(Op::kBlock, it->second);
    return;
  }
  index_.emplace(x, static_cast<int>(blocks_.size()));
  log_.emplace_back(Op::kBlock, static_cast<int>(blocks_.size()));
  blocks_.push_back({x, size, manifold});
}

void WindowProblem::addResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                                     const std::vector<double*>& blocks) {
  const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
  if (sizes.size() != blocks.size())
    throw std::invalid_argument("addResidualBlock: block count differs from the cost's");
  Residual r{cost, loss, {}};
  r.blocks.reserve(blocks.size());
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    auto it = index_.find(blocks[k]);
    if (it == index_.end()) {
      index_.emplace(blocks[k], static_cast<int>(blocks_.size()));
      blocks_.push_back({blocks[k], sizes[k], nullptr});
      it = index_.find(blocks[k]);
    } else if (blocks_[static_cast<std::size_t>(it->second)].size != sizes[k]) {
      throw std::invalid_argument("addResidualBlock: a block's size differs from the one it was added with");
    }
    r.blocks.push_back(it->second);
  }
  log_.emplace_back(Op::kResidual, static_cast<int>(residuals_.size()));
  residuals_.push_back(std::move(r));
}

void WindowProblem::setParameterBlockConstant(const double* x) {
  const auto it = index_.find(x);
  if (it == index_.end()) throw std::invalid_argument("setParameterBlockConstant: unknown block");
  blocks_[static_cast<std::size_t>(it->second)].constant = true;
  log_.emplace_back(Op::kConstant, it->second);
}

void WindowProblem::setLandmark(const double* x) {
  const auto it = index_.find(x);
  if (it == index_.end()) throw std::invalid_argument("setLandmark: unknown block");
  blocks_[static_cast<std::size_t>(it->second)].landmark = true;
}

void WindowProblem::toCeres(ceres::Problem& problem) const {
  for (const auto& [op, i] : log_) {
    const auto at = static_cast<std::size_t>(i);
    if (op == Op::kBlock) {
      problem.AddParameterBlock(blocks_[at].x, blocks_[at].size, const_cast<ceres::Manifold*>(blocks_[at].manifold));
    } else if (op == Op::kConstant) {
      problem.SetParameterBlockConstant(blocks_[at].x);
    } else {
      std::vector<double*> xs;
      for (int b : residuals_[at].blocks) xs.push_back(blocks_[static_cast<std::size_t>(b)].x);
      problem.AddResidualBlock(const_cast<ceres::CostFunction*>(residuals_[at].cost),
                               const_cast<ceres::LossFunction*>(residuals_[at].loss), xs);
    }
  }
}

}  // namespace idyvins::backend
