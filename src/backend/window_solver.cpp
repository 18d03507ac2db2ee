// solveWindow: Ceres 2.1's trust-region minimizer with its traditional dogleg strategy, Jacobi
// scaling and stopping rules, restated for the window (so that a problem converges the same way
// it did in Ceres), with a linear solver that knows the window's structure: every landmark block
// (1 or 3 columns) is eliminated on its own, its few pose columns updated by its Schur complement,
// then the dense reduced system of the poses, speeds, biases and calibration is solved by
// Cholesky. Residuals and Jacobians live in flat buffers filled once per linearization.

#include "backend/window_solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace idyvins::backend::window {

using Eigen::VectorXd;

namespace {

/// Calls f with the tangent width t as a compile-time constant for the window's common widths
/// (1: an inverse depth or the time offset, 6: a pose, 9: speed and biases), else as an int, so
/// that the kernels below unroll and vectorize over a block's columns. Every kernel keeps the
/// order of the additions into each output element (rows in order), so results do not change.
template <class F>
void withWidth(int t, F f) {
  switch (t) {
    case 1:
      return f(std::integral_constant<int, 1>());
    case 6:
      return f(std::integral_constant<int, 6>());
    case 9:
      return f(std::integral_constant<int, 9>());
    default:
      return f(t);
  }
}

/// The first t columns of a row-major m x size Jacobian into out (m x t); false at a value
/// that is not finite.
template <class T>
bool copyTangent(const double* __restrict in, int size, int m, T t, double* __restrict out) {
  bool finite = true;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < t; ++j) {
      const double v = in[i * size + j];
      finite = finite && std::isfinite(v);
      out[i * t + j] = v;
    }
  return finite;
}

/// Ceres' Corrector on a row-major m x t Jacobian: sqrt(ρ') (J − α/|r|² r rᵀ J); only the scaling
/// when α is 0 (always so for Huber, whose ρ'' ≤ 0).
void correctJacobian(const double* res, int m, int t, double sqrt_rho1, double alpha_sq, double* out) {
  if (alpha_sq == 0.0) {
    if (sqrt_rho1 != 1.0)
      for (int i = 0; i < m * t; ++i) out[i] *= sqrt_rho1;
    return;
  }
  for (int j = 0; j < t; ++j) {
    double rj = 0;
    for (int i = 0; i < m; ++i) rj += res[i] * out[i * t + j];
    for (int i = 0; i < m; ++i) out[i * t + j] = sqrt_rho1 * (out[i * t + j] - alpha_sq * res[i] * rj);
  }
}

}  // namespace

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

void Solver::layout() {
  const auto& blocks = p_.blocks();
  const std::size_t nb = blocks.size();
  col_.assign(nb, -1);
  tan_.assign(nb, 0);
  x_off_.assign(nb, -1);
  std::vector<bool> used(nb, false);
  for (const auto& r : p_.residuals())
    for (int b : r.blocks) used[static_cast<std::size_t>(b)] = used[static_cast<std::size_t>(b)] || !blocks[b].constant;
  tangentSizes();
  std::vector<int> lm_of_block(nb, -1);
  for (std::size_t b = 0; b < nb; ++b)  // landmarks first, in the order added, then the rest
    if (used[b] && blocks[b].landmark) {
      lm_of_block[b] = static_cast<int>(lms_.size());
      lms_.push_back({static_cast<int>(b), n_, tan_[b], {}});
      col_[b] = n_;
      n_ += tan_[b];
    }
  n_e_ = n_;
  // The blocks landmarks touch (poses, calibration) next, so that the Schur updates stay in
  // one corner of the reduced matrix; then the rest (speeds and biases).
  std::vector<bool> near(nb, false);
  for (const auto& r : p_.residuals()) {
    const bool with_landmark =
        std::any_of(r.blocks.begin(), r.blocks.end(), [&](int b) { return lm_of_block[b] >= 0; });
    if (with_landmark)
      for (int b : r.blocks) near[static_cast<std::size_t>(b)] = true;
  }
  for (bool pass : {true, false})
    for (std::size_t b = 0; b < nb; ++b)
      if (used[b] && !blocks[b].landmark && near[b] == pass) {
        col_[b] = n_;
        n_ += tan_[b];
      }
  for (std::size_t b = 0; b < nb; ++b)
    if (used[b]) {
      x_off_[b] = n_x_;
      n_x_ += blocks[b].size;
    }
  layoutResiduals(lm_of_block);
  r_.assign(static_cast<std::size_t>(rows_), 0.0);
  r_cand_ = r_;
  J_.assign(static_cast<std::size_t>(n_j_), 0.0);
}

/// Each block's tangent size; a manifold must have the pose convention (PlusJacobian [I; 0]).
void Solver::tangentSizes() {
  const auto& blocks = p_.blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const auto* m = blocks[b].manifold;
    tan_[b] = m ? m->TangentSize() : blocks[b].size;
    if (m) {
      std::vector<double> P(static_cast<std::size_t>(blocks[b].size * tan_[b]));
      m->PlusJacobian(blocks[b].x, P.data());
      const Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>> Pm(P.data(), blocks[b].size, tan_[b]);
      const bool pose_like = Pm.topRows(tan_[b]).isIdentity(0.0) && Pm.bottomRows(blocks[b].size - tan_[b]).isZero(0.0);
      if (!pose_like) throw std::invalid_argument("solveWindow: a manifold whose PlusJacobian is not [I; 0]");
    }
  }
}

/// The residual blocks with a solved block, their rows and Jacobian offsets, and each landmark's list.
void Solver::layoutResiduals(const std::vector<int>& lm_of_block) {
  for (const auto& def : p_.residuals()) {
    Res q{&def, def.cost->num_residuals(), rows_, -1, {}};
    bool any = false;
    for (int b : def.blocks) {
      const bool solved = col_[static_cast<std::size_t>(b)] >= 0;
      any = any || solved;
      q.j_off.push_back(solved ? n_j_ : -1);
      if (solved) n_j_ += q.m * tan_[static_cast<std::size_t>(b)];
      if (solved && lm_of_block[static_cast<std::size_t>(b)] >= 0) {
        if (q.landmark >= 0) throw std::invalid_argument("solveWindow: a residual block with two landmark blocks");
        q.landmark = lm_of_block[static_cast<std::size_t>(b)];
      }
    }
    if (!any) continue;  // every block constant: no part of the problem (Ceres' fixed cost)
    if (q.landmark >= 0) lms_[static_cast<std::size_t>(q.landmark)].res.push_back(static_cast<int>(res_.size()));
    rows_ += q.m;
    res_.push_back(std::move(q));
  }
}

bool Solver::evaluateResidual(const Res& q, bool jacobians, std::vector<double>& r, double& cost) {
  const auto& blocks = p_.blocks();
  const auto& def = *q.def;
  double* params[16];
  double* jac[16];
  const std::size_t nb = def.blocks.size();
  if (nb > 16) throw std::invalid_argument("solveWindow: more than 16 blocks in a residual block");
  std::size_t need = 0;
  for (std::size_t k = 0; k < nb; ++k) need += static_cast<std::size_t>(q.m * blocks[def.blocks[k]].size);
  if (scratch_.size() < need) scratch_.resize(need);
  std::size_t at = 0;
  for (std::size_t k = 0; k < nb; ++k) {
    const auto& blk = blocks[def.blocks[k]];
    params[k] = blk.x;
    jac[k] = (jacobians && q.j_off[k] >= 0) ? scratch_.data() + at : nullptr;
    at += static_cast<std::size_t>(q.m * blk.size);
  }
  double* res = r.data() + q.r_off;
  if (!def.cost->Evaluate(params, res, jacobians ? jac : nullptr)) return false;
  double sq = 0;
  for (int i = 0; i < q.m; ++i) {
    if (!std::isfinite(res[i])) return false;
    sq += res[i] * res[i];
  }
  double rho[3] = {sq, 1.0, 0.0};
  if (def.loss) def.loss->Evaluate(sq, rho);
  cost += 0.5 * rho[0];
  double sqrt_rho1 = 1.0, alpha_sq = 0.0, r_scale = 1.0;
  if (def.loss) {  // Ceres' Corrector (corrector.cc): Triggs' correction of the residual and Jacobian
    sqrt_rho1 = std::sqrt(rho[1]);
    r_scale = sqrt_rho1;
    if (sq != 0.0 && rho[2] > 0.0) {
      const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * sq * rho[2] / rho[1]);
      r_scale = sqrt_rho1 / (1.0 - alpha);
      alpha_sq = alpha / sq;
    }
  }
  if (jacobians) {
    for (std::size_t k = 0; k < nb; ++k) {
      if (!jac[k]) continue;
      const int size = blocks[def.blocks[k]].size, t = tan_[static_cast<std::size_t>(def.blocks[k])];
      double* out = J_.data() + q.j_off[k];
      bool finite = true;
      withWidth(t, [&](auto w) { finite = copyTangent(jac[k], size, q.m, w, out); });
      if (!finite) return false;
      if (def.loss) correctJacobian(res, q.m, t, sqrt_rho1, alpha_sq, out);
    }
  }
  for (int i = 0; i < q.m; ++i) res[i] *= r_scale;
  return true;
}

bool Solver::evaluate(bool jacobians, std::vector<double>& r, double& cost) {
  const auto t0 = Clock::now();
  cost = 0;
  bool ok = true;
  for (const Res& q : res_)
    if (!(ok = evaluateResidual(q, jacobians, r, cost))) break;
  (jacobians ? summary_->jacobian_ms : summary_->residual_ms) += msSince(t0);
  return ok && std::isfinite(cost);
}

namespace {

/// out (m) += J v for row-major J (m x t).
template <class T>
void addJv(const double* __restrict J, int m, T t, const double* __restrict v, double* __restrict out) {
  for (int i = 0; i < m; ++i) {
    double s = 0;
    for (int j = 0; j < t; ++j) s += J[i * t + j] * v[j];
    out[i] += s;
  }
}

/// out (t) += Jᵀ r.
template <class T>
void addJtr(const double* __restrict J, int m, T t, const double* __restrict r, double* __restrict out) {
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < t; ++j) out[j] += J[i * t + j] * r[i];
}

/// out (t) += the squares of J's columns.
template <class T>
void addSquares(const double* __restrict J, int m, T t, double* __restrict out) {
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < t; ++j) out[j] += J[i * t + j] * J[i * t + j];
}

/// J's columns times s (t).
template <class T>
void scaleBy(double* __restrict J, int m, T t, const double* __restrict s) {
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < t; ++j) J[i * t + j] *= s[j];
}

}  // namespace

void Solver::multiplyJ(const VectorXd& v, VectorXd& out) const {
  out.setZero(rows_);
  forEachJacobian([&](const Res& q, int off, int t, int col) {
    withWidth(t, [&](auto w) { addJv(J_.data() + off, q.m, w, v.data() + col, out.data() + q.r_off); });
  });
}

void Solver::multiplyJt(const std::vector<double>& r, VectorXd& out) const {
  out.setZero(n_);
  forEachJacobian([&](const Res& q, int off, int t, int col) {
    withWidth(t, [&](auto w) { addJtr(J_.data() + off, q.m, w, r.data() + q.r_off, out.data() + col); });
  });
}

VectorXd Solver::squaredColumnNorms() const {
  VectorXd sq = VectorXd::Zero(n_);
  forEachJacobian([&](const Res& q, int off, int t, int col) {
    withWidth(t, [&](auto w) { addSquares(J_.data() + off, q.m, w, sq.data() + col); });
  });
  return sq;
}

/// Squared column norms at the first linearization give the Jacobi scaling 1/(1 + |J_c|); every
/// Jacobian is then scaled by it (as Ceres' TrustRegionMinimizer).
void Solver::scaleColumns(bool first) {
  if (first) scaling_ = (1.0 / (1.0 + squaredColumnNorms().array().sqrt())).matrix();
  forEachJacobian([&](const Res& q, int off, int t, int col) {
    withWidth(t, [&](auto w) { scaleBy(J_.data() + off, q.m, w, scaling_.data() + col); });
  });
}

}  // namespace idyvins::backend::window
