#include "backend/marginalization.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "backend/parameter_blocks.h"
#include "core/so3.h"

namespace idyvins::backend {

namespace {
int tangentSize(int size) { return size == kPoseSize ? kPoseTangentSize : size; }

/// A term's weighted residual and tangent Jacobians (row-major, m x tangent size per block, one
/// after the other in `jac`); buffers reused from term to term.
struct Linearized {
  std::vector<double> r, raw, jac;
  std::vector<int> jac_off, tangent;
  std::vector<double*> raw_ptrs;
};

/// Evaluates a term into `out` (robust loss folded in with Triggs' correction, as Ceres does).
void linearize(const MarginalizationTerm& t, Linearized& out) {
  const auto& sizes = t.cost->parameter_block_sizes();
  const int m = t.cost->num_residuals();
  const std::size_t nb = sizes.size();
  std::size_t raw_size = 0, jac_size = 0;
  out.jac_off.resize(nb);
  out.tangent.resize(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    out.tangent[k] = tangentSize(sizes[k]);
    out.jac_off[k] = static_cast<int>(jac_size);
    raw_size += static_cast<std::size_t>(m * sizes[k]);
    jac_size += static_cast<std::size_t>(m * out.tangent[k]);
  }
  out.r.resize(static_cast<std::size_t>(m));
  out.raw.resize(raw_size);
  out.jac.resize(jac_size);
  auto& raw_ptrs = out.raw_ptrs;
  raw_ptrs.resize(nb);
  for (std::size_t k = 0, at = 0; k < nb; at += static_cast<std::size_t>(m * sizes[k]), ++k)
    raw_ptrs[k] = out.raw.data() + at;
  if (!t.cost->Evaluate(t.blocks.data(), out.r.data(), raw_ptrs.data()))
    throw std::runtime_error("marginalization: a residual block failed to evaluate");
  for (std::size_t k = 0; k < nb; ++k)
    for (int i = 0; i < m; ++i)
      std::copy_n(raw_ptrs[k] + i * sizes[k], out.tangent[k], out.jac.data() + out.jac_off[k] + i * out.tangent[k]);
  if (!t.loss) return;
  Eigen::Map<Eigen::VectorXd> r(out.r.data(), m);
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
  if (alpha_sq_norm == 0.0) {  // Huber's case (ρ'' ≤ 0): only the scaling, of every block at once
    for (double& v : out.jac) v *= sqrt_rho1;
    r *= residual_scaling;
    return;
  }
  for (std::size_t k = 0; k < nb; ++k) {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Jk(
        out.jac.data() + out.jac_off[k], m, out.tangent[k]);
    const Eigen::RowVectorXd rJ = r.transpose() * Jk;
    Jk = sqrt_rho1 * (Jk - alpha_sq_norm * r * rJ);
  }
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
  std::unordered_map<double*, int> size_of, index;
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

/// H (column-major, leading dimension ld) block at (row ia, column ib) += Aᵀ B for row-major A
/// (m x a) and B (m x b); the column loop vectorizes.
void addAtB(const double* __restrict A, int a, const double* __restrict B, int b, int m, double* __restrict H,
            Eigen::Index ld, int ia, int ib) {
  for (int r = 0; r < m; ++r)
    for (int j = 0; j < b; ++j) {
      const double s = B[r * b + j];
      double* col = H + (ib + j) * ld + ia;
      const double* ar = A + r * a;
      for (int i = 0; i < a; ++i) col[i] += ar[i] * s;
    }
}

/// A tall term (the previous prior): its JᵀJ through one dense product, scattered into H.
void addTall(const Linearized& l, int m, const std::vector<int>& at, Eigen::MatrixXd& H) {
  int cols = 0;
  for (int t : l.tangent) cols += t;
  Eigen::MatrixXd A(m, cols);
  for (std::size_t k = 0, c = 0; k < at.size(); c += static_cast<std::size_t>(l.tangent[k]), ++k)
    A.middleCols(static_cast<Eigen::Index>(c), l.tangent[k]) =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            l.jac.data() + l.jac_off[k], m, l.tangent[k]);
  Eigen::MatrixXd AtA(cols, cols);
  AtA.noalias() = A.transpose() * A;
  for (std::size_t k1 = 0, c1 = 0; k1 < at.size(); c1 += static_cast<std::size_t>(l.tangent[k1]), ++k1)
    for (std::size_t k2 = 0, c2 = 0; k2 < at.size(); c2 += static_cast<std::size_t>(l.tangent[k2]), ++k2)
      H.block(at[k1], at[k2], l.tangent[k1], l.tangent[k2]) +=
          AtA.block(static_cast<Eigen::Index>(c1), static_cast<Eigen::Index>(c2), l.tangent[k1], l.tangent[k2]);
}

/// The Gauss-Newton system H δ = -g of all terms in the block order.
void accumulate(const std::vector<MarginalizationTerm>& terms, BlockOrder& o, Eigen::MatrixXd& H, Eigen::VectorXd& g) {
  H = Eigen::MatrixXd::Zero(o.m + o.n, o.m + o.n);
  g = Eigen::VectorXd::Zero(o.m + o.n);
  Linearized l;
  std::vector<int> at;
  for (const auto& t : terms) {
    linearize(t, l);
    const int m = static_cast<int>(l.r.size());
    at.resize(t.blocks.size());
    for (std::size_t k = 0; k < t.blocks.size(); ++k) at[k] = o.index.at(t.blocks[k]);
    for (std::size_t k = 0; k < t.blocks.size(); ++k) {
      const double* J = l.jac.data() + l.jac_off[k];
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < l.tangent[k]; ++j)
          g(at[k] + j) += J[i * l.tangent[k] + j] * l.r[static_cast<std::size_t>(i)];
    }
    if (m > 16) {
      addTall(l, m, at, H);
      continue;
    }
    for (std::size_t a = 0; a < t.blocks.size(); ++a)
      for (std::size_t b = 0; b < t.blocks.size(); ++b)
        addAtB(l.jac.data() + l.jac_off[a], l.tangent[a], l.jac.data() + l.jac_off[b], l.tangent[b], m, H.data(),
               H.rows(), at[a], at[b]);
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
