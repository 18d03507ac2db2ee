#include "backend/marginalization.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "backend/parameter_blocks.h"
#include "core/so3.h"

namespace idyvins::backend {

namespace {
int tangentSize(int size) { return size == kPoseSize ? kPoseTangentSize : size; }

/// Evaluates a term: weighted residual and tangent Jacobians (robust loss folded
/// in with Triggs' correction, as Ceres does).
void linearize(const MarginalizationTerm& t, Eigen::VectorXd& r, std::vector<Eigen::MatrixXd>& J) {
  const auto& sizes = t.cost->parameter_block_sizes();
  const int m = t.cost->num_residuals();
  r.resize(m);
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> raw(sizes.size());
  std::vector<double*> raw_ptrs(sizes.size());
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    raw[k].resize(m, sizes[k]);
    raw_ptrs[k] = raw[k].data();
  }
  if (!t.cost->Evaluate(t.blocks.data(), r.data(), raw_ptrs.data()))
    throw std::runtime_error("marginalization: a residual block failed to evaluate");
  J.resize(sizes.size());
  for (std::size_t k = 0; k < sizes.size(); ++k) J[k] = raw[k].leftCols(tangentSize(sizes[k]));
  if (!t.loss) return;
  const double sq = r.squaredNorm();
  double rho[3];
  t.loss->Evaluate(sq, rho);
  const double sqrt_rho1 = std::sqrt(rho[1]);
  double residual_scaling = sqrt_rho1, alpha_sq_norm = 0.0;
  if (sq > 0.0 && rho[2] > 0.0) {
    const double D = 1.0 + 2.0 * sq * rho[2] / rho[1];
    const double alpha = 1.0 - std::sqrt(D);
    residual_scaling = sqrt_rho1 / (1.0 - alpha);
    alpha_sq_norm = alpha / sq;
  }
  for (auto& Jk : J) Jk = sqrt_rho1 * (Jk - alpha_sq_norm * r * (r.transpose() * Jk));
  r *= residual_scaling;
}

Eigen::VectorXd tangentDelta(const double* x, const Eigen::VectorXd& x0, int size) {
  if (size != kPoseSize) return Eigen::Map<const Eigen::VectorXd>(x, size) - x0;
  Eigen::VectorXd d(6);
  d.head<3>() = Eigen::Map<const Eigen::Vector3d>(x) - x0.head<3>();
  const Eigen::Quaterniond q0(x0(6), x0(3), x0(4), x0(5));
  const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(x + 3);
  d.tail<3>() = 2.0 * positiveW(q0.conjugate() * q).vec();
  return d;
}
}  // namespace

void MarginalizationPrior::remap(const std::unordered_map<double*, double*>& old_to_new) {
  for (auto& b : blocks) {
    const auto it = old_to_new.find(b);
    if (it != old_to_new.end()) b = it->second;
  }
}

void MarginalizationPrior::scaleInformation(double weight) {
  const double k = std::sqrt(weight);
  J0 *= k;
  r0 *= k;
}

void Marginalizer::add(MarginalizationTerm term) { terms_.push_back(std::move(term)); }

namespace {

/// The blocks of the terms: dropped ones first, then kept ones, each in first-seen order,
/// with their sizes and the offset of each in the tangent vector.
struct BlockOrder {
  std::vector<double*> dropped, kept;
  std::map<double*, int> size_of, index;
  int m = 0, n = 0;  ///< tangent dimensions of the dropped and the kept part
};

BlockOrder orderBlocks(const std::vector<MarginalizationTerm>& terms) {
  BlockOrder o;
  for (const auto& t : terms) {
    const auto& sizes = t.cost->parameter_block_sizes();
    for (std::size_t k = 0; k < t.blocks.size(); ++k) {
      o.size_of[t.blocks[k]] = sizes[k];
      const bool is_drop = std::find(t.drop.begin(), t.drop.end(), static_cast<int>(k)) != t.drop.end();
      auto& list = is_drop ? o.dropped : o.kept;
      if (std::find(list.begin(), list.end(), t.blocks[k]) == list.end()) list.push_back(t.blocks[k]);
    }
  }
  o.kept.erase(
      std::remove_if(o.kept.begin(), o.kept.end(),
                     [&](double* b) { return std::find(o.dropped.begin(), o.dropped.end(), b) != o.dropped.end(); }),
      o.kept.end());
  for (double* b : o.dropped) {
    o.index[b] = o.m;
    o.m += tangentSize(o.size_of[b]);
  }
  for (double* b : o.kept) {
    o.index[b] = o.m + o.n;
    o.n += tangentSize(o.size_of[b]);
  }
  return o;
}

/// The Gauss-Newton system H δ = -g of all terms in the block order.
void accumulate(const std::vector<MarginalizationTerm>& terms, BlockOrder& o, Eigen::MatrixXd& H, Eigen::VectorXd& g) {
  H = Eigen::MatrixXd::Zero(o.m + o.n, o.m + o.n);
  g = Eigen::VectorXd::Zero(o.m + o.n);
  for (const auto& t : terms) {
    Eigen::VectorXd r;
    std::vector<Eigen::MatrixXd> J;
    linearize(t, r, J);
    for (std::size_t a = 0; a < t.blocks.size(); ++a) {
      const int ia = o.index[t.blocks[a]];
      const int sa = static_cast<int>(J[a].cols());
      g.segment(ia, sa) += J[a].transpose() * r;
      for (std::size_t b = 0; b < t.blocks.size(); ++b) {
        const int ib = o.index[t.blocks[b]];
        H.block(ia, ib, sa, J[b].cols()) += J[a].transpose() * J[b];
      }
    }
  }
}

}  // namespace

MarginalizationPrior Marginalizer::marginalize(double eps) const {
  BlockOrder o = orderBlocks(terms_);
  const int m = o.m, n = o.n;
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  accumulate(terms_, o, H, g);
  // Schur complement of the dropped part. Hmm is solved by LDLT with a tiny diagonal
  // regularization (eps) instead of a full eigendecomposition: same result for the
  // well-conditioned blocks, several times faster for the 50-150 dropped dimensions.
  Eigen::MatrixXd Hmm = 0.5 * (H.topLeftCorner(m, m) + H.topLeftCorner(m, m).transpose());
  Hmm.diagonal().array() += eps;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Hmm);
  const Eigen::MatrixXd Hrm = H.block(m, 0, n, m);
  const Eigen::MatrixXd X = ldlt.solve(Hrm.transpose());  // Hmm⁻¹ Hmr
  Eigen::MatrixXd A = H.bottomRightCorner(n, n) - Hrm * X;
  const Eigen::VectorXd b = g.tail(n) - X.transpose() * g.head(m);
  A = 0.5 * (A + A.transpose());

  // A = J0ᵀ J0 and b = J0ᵀ r0.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es2(A);
  const Eigen::VectorXd S = (es2.eigenvalues().array() > eps).select(es2.eigenvalues().array(), 0.0);
  const Eigen::VectorXd S_inv = (es2.eigenvalues().array() > eps).select(es2.eigenvalues().array().inverse(), 0.0);
  MarginalizationPrior prior;
  prior.J0 = S.cwiseSqrt().asDiagonal() * es2.eigenvectors().transpose();
  prior.r0 = S_inv.cwiseSqrt().asDiagonal() * es2.eigenvectors().transpose() * b;
  for (double* blk : o.kept) {
    const int s = o.size_of[blk];
    prior.blocks.push_back(blk);
    prior.sizes.push_back(s);
    prior.tangent_sizes.push_back(tangentSize(s));
    prior.x0.push_back(Eigen::Map<const Eigen::VectorXd>(blk, s));
  }
  return prior;
}

MarginalizationFactor::MarginalizationFactor(std::shared_ptr<const MarginalizationPrior> prior)
    : prior_(std::move(prior)) {
  for (int s : prior_->sizes) mutable_parameter_block_sizes()->push_back(s);
  set_num_residuals(static_cast<int>(prior_->r0.size()));
}

bool MarginalizationFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const auto& p = *prior_;
  const int n = static_cast<int>(p.J0.cols());
  Eigen::VectorXd dx(n);
  int offset = 0;
  for (std::size_t k = 0; k < p.sizes.size(); ++k) {
    dx.segment(offset, p.tangent_sizes[k]) = tangentDelta(parameters[k], p.x0[k], p.sizes[k]);
    offset += p.tangent_sizes[k];
  }
  Eigen::Map<Eigen::VectorXd>(residuals, p.r0.size()) = p.r0 + p.J0 * dx;
  if (!jacobians) return true;
  offset = 0;
  for (std::size_t k = 0; k < p.sizes.size(); ++k) {
    const int ts = p.tangent_sizes[k];
    if (jacobians[k]) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(jacobians[k], p.r0.size(),
                                                                                           p.sizes[k]);
      J.setZero();
      if (p.sizes[k] == kPoseSize) {
        // d(2 vec(q0⁻¹ q Exp(δθ)))/dδθ = qLeft(q0⁻¹ q) bottom-right block.
        const Eigen::VectorXd& x0 = p.x0[k];
        const Eigen::Quaterniond q0(x0(6), x0(3), x0(4), x0(5));
        const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(parameters[k] + 3);
        const Eigen::Matrix3d d_rot = qLeft(positiveW(q0.conjugate() * q)).bottomRightCorner<3, 3>();
        J.leftCols<3>() = p.J0.middleCols(offset, 3);
        J.middleCols<3>(3) = p.J0.middleCols(offset + 3, 3) * d_rot;
      } else {
        J.leftCols(ts) = p.J0.middleCols(offset, ts);
      }
    }
    offset += ts;
  }
  return true;
}

}  // namespace idyvins::backend
