// solveWindow's linear solver (landmarks eliminated one at a time, then the dense reduced system)
// and its trust-region loop (Ceres 2.1's TrustRegionMinimizer with the traditional DoglegStrategy:
// the same radius, regularization and acceptance rules and the same stopping tests, in the same order).

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "backend/window_solver.h"

namespace idyvins::backend::window {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

namespace {

constexpr double kMinDiagonal = 1e-6, kMaxDiagonal = 1e32, kMinMu = 1e-8, kMaxMu = 1.0, kMuIncrease = 10.0;
constexpr double kMinRadius = 1e-32, kMinRelativeDecrease = 1e-3;
constexpr int kMaxInvalidSteps = 5;

template <int A, int B, int M>
void addAtBFixed(const double* __restrict Ap, const double* __restrict Bp, double* __restrict out, int ld,
                 double sign) {
  for (int r = 0; r < M; ++r)
    for (int i = 0; i < A; ++i) {
      const double s = sign * Ap[r * A + i];
      double* o = out + i * ld;
      for (int j = 0; j < B; ++j) o[j] += s * Bp[r * B + j];
    }
}

/// out (a x b, row stride ld) += sign · Aᵀ B for row-major A (m x a) and B (m x b); the window's
/// common shapes (a projection's 2 rows by two poses, a landmark's coupling) unrolled, same sums.
void addAtB(const double* __restrict A, int a, const double* __restrict B, int b, int m, double* __restrict out, int ld,
            double sign = 1.0) {
  if (a == 6 && b == 6 && m == 2) return addAtBFixed<6, 6, 2>(A, B, out, ld, sign);
  if (a == 6 && b == 6 && m == 1) return addAtBFixed<6, 6, 1>(A, B, out, ld, sign);
  if (a == 1 && b == 6 && m == 2) return addAtBFixed<1, 6, 2>(A, B, out, ld, sign);
  for (int r = 0; r < m; ++r) {
    const double* ar = A + r * a;
    const double* br = B + r * b;
    for (int i = 0; i < a; ++i) {
      const double s = sign * ar[i];
      double* o = out + i * ld;
      for (int j = 0; j < b; ++j) o[j] += s * br[j];
    }
  }
}

/// Inverse of a small symmetric positive semi-definite matrix (the pseudo-inverse when singular).
Eigen::Matrix3d invertPsdDynamic(const MatrixXd& E) {
  const Eigen::LLT<MatrixXd> llt(E);
  if (llt.info() == Eigen::Success) return llt.solve(MatrixXd::Identity(E.rows(), E.cols()));
  const Eigen::SelfAdjointEigenSolver<MatrixXd> es(E);
  VectorXd inv = es.eigenvalues();
  const double tol = 1e-12 * std::max(1.0, inv.cwiseAbs().maxCoeff());
  for (int i = 0; i < inv.size(); ++i) inv(i) = inv(i) > tol ? 1.0 / inv(i) : 0.0;
  return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::Matrix3d invertPsd(const Eigen::Matrix3d& E3, int e) {
  if (e == 1) return Eigen::Matrix3d::Constant(E3(0, 0) > 0 ? 1.0 / E3(0, 0) : 0.0);
  return invertPsdDynamic(E3.topLeftCorner(e, e));
}

}  // namespace

/// JᵀJ of one residual block's solved, non-landmark blocks into the lower triangle of H
/// (block rows at or below block columns; a block's own square whole).
void Solver::addFf(const Res& q, RowMatrix& H) const {
  const int n_f = n_ - n_e_;
  for (std::size_t k1 = 0; k1 < q.j_off.size(); ++k1) {
    const std::size_t b1 = static_cast<std::size_t>(q.def->blocks[k1]);
    if (q.j_off[k1] < 0 || p_.blocks()[b1].landmark) continue;
    for (std::size_t k2 = 0; k2 < q.j_off.size(); ++k2) {
      const std::size_t b2 = static_cast<std::size_t>(q.def->blocks[k2]);
      if (q.j_off[k2] < 0 || p_.blocks()[b2].landmark || col_[b1] < col_[b2]) continue;
      double* out = H.data() + static_cast<std::ptrdiff_t>(col_[b1] - n_e_) * n_f + (col_[b2] - n_e_);
      addAtB(J_.data() + q.j_off[k1], tan_[b1], J_.data() + q.j_off[k2], tan_[b2], q.m, out, n_f);
    }
  }
}

/// A tall block (the marginalization prior): its JᵀJ through one dense product.
void Solver::addFfDense(const Res& q, RowMatrix& H) const {
  std::vector<std::size_t> bs;
  int cols = 0;
  for (std::size_t k = 0; k < q.j_off.size(); ++k)
    if (q.j_off[k] >= 0) {
      bs.push_back(k);
      cols += tan_[static_cast<std::size_t>(q.def->blocks[k])];
    }
  MatrixXd A(q.m, cols);
  int c = 0;
  for (std::size_t k : bs) {
    const int t = tan_[static_cast<std::size_t>(q.def->blocks[k])];
    A.middleCols(c, t) = Eigen::Map<const RowMatrix>(J_.data() + q.j_off[k], q.m, t);
    c += t;
  }
  const MatrixXd AtA = A.transpose() * A;
  int ci = 0;
  for (std::size_t k1 : bs) {
    const std::size_t b1 = static_cast<std::size_t>(q.def->blocks[k1]);
    int cj = 0;
    for (std::size_t k2 : bs) {
      const std::size_t b2 = static_cast<std::size_t>(q.def->blocks[k2]);
      if (col_[b1] >= col_[b2])
        H.block(col_[b1] - n_e_, col_[b2] - n_e_, tan_[b1], tan_[b2]) += AtA.block(ci, cj, tan_[b1], tan_[b2]);
      cj += tan_[b2];
    }
    ci += tan_[b1];
  }
}

/// Eliminates landmark l: its own normal block E (regularized by lm2), the couplings W to its pose
/// columns, H −= Wᵀ E⁻¹ W and b_f −= Wᵀ E⁻¹ b_e; W and E⁻¹ are kept for the back substitution.
void Solver::eliminate(const Landmark& l, const VectorXd& lm2, RowMatrix& H, VectorXd& bf, Elimination& el) {
  const int e = l.size, n_f = n_ - n_e_;
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  E.diagonal().head(e) = lm2.segment(l.col, e);
  el.slots.clear();
  el.w.clear();
  for (int ri : l.res) {
    const Res& q = res_[static_cast<std::size_t>(ri)];
    std::size_t ke = 0;
    for (std::size_t k = 0; k < q.j_off.size(); ++k)
      if (q.j_off[k] >= 0 && q.def->blocks[k] == l.block) ke = k;
    const double* Je = J_.data() + q.j_off[ke];
    addAtB(Je, e, Je, e, q.m, E.data(), 3);  // symmetric: the column-major layout does not matter
    for (std::size_t k = 0; k < q.j_off.size(); ++k) {
      if (q.j_off[k] < 0 || k == ke) continue;
      const int b = q.def->blocks[k], t = tan_[static_cast<std::size_t>(b)];
      auto it = std::find_if(el.slots.begin(), el.slots.end(), [&](const auto& s) { return s.first == b; });
      if (it == el.slots.end()) {
        el.slots.emplace_back(b, static_cast<int>(el.w.size()));
        el.w.resize(el.w.size() + static_cast<std::size_t>(e * t), 0.0);
        it = el.slots.end() - 1;
      }
      addAtB(Je, e, J_.data() + q.j_off[k], t, q.m, el.w.data() + it->second, t);
    }
    addFf(q, H);
  }
  el.e_inv = invertPsd(E, e);
  Eigen::Vector3d be = Eigen::Vector3d::Zero();
  be.head(e) = b_.segment(l.col, e);
  double ew[3 * 16];  // E⁻¹ W of one slot, e x t (t ≤ 16)
  for (const auto& [b1, o1] : el.slots) {
    const int t1 = tan_[static_cast<std::size_t>(b1)], f1 = col_[static_cast<std::size_t>(b1)] - n_e_;
    if (t1 > 16) throw std::invalid_argument("solveWindow: a block of more than 16 tangent columns beside a landmark");
    const Eigen::Map<const RowMatrix> W1(el.w.data() + o1, e, t1);
    Eigen::Map<RowMatrix> EW1(ew, e, t1);
    EW1.noalias() = el.e_inv.topLeftCorner(e, e) * W1;
    bf.segment(f1, t1).noalias() -= EW1.transpose() * be.head(e);
    for (const auto& [b2, o2] : el.slots) {
      const int t2 = tan_[static_cast<std::size_t>(b2)], f2 = col_[static_cast<std::size_t>(b2)] - n_e_;
      if (f1 < f2) continue;
      addAtB(ew, t1, el.w.data() + o2, t2, e, H.data() + static_cast<std::ptrdiff_t>(f1) * n_f + f2, n_f, -1.0);
    }
  }
}

/// Solves (JᵀJ + diag(lm2)) y = Jᵀr (b_) with the landmarks eliminated first; false if the reduced
/// system is not positive definite or the solution not finite.
bool Solver::solveNormal(const VectorXd& lm2, VectorXd& y) {
  const auto t0 = Clock::now();
  const int n_f = n_ - n_e_;
  RowMatrix H = RowMatrix::Zero(n_f, n_f);
  VectorXd bf = b_.tail(n_f);
  for (const Res& q : res_)
    if (q.landmark < 0) (q.m > 16 ? addFfDense(q, H) : addFf(q, H));
  elim_.resize(lms_.size());
  for (std::size_t i = 0; i < lms_.size(); ++i) eliminate(lms_[i], lm2, H, bf, elim_[i]);
  H.diagonal() += lm2.tail(n_f);
  const Eigen::LLT<RowMatrix, Eigen::Lower> llt(H);
  bool ok = llt.info() == Eigen::Success;
  y.setZero(n_);
  if (ok) {
    y.tail(n_f) = llt.solve(bf);
    for (std::size_t i = 0; i < lms_.size(); ++i) {
      const Landmark& l = lms_[i];
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      v.head(l.size) = b_.segment(l.col, l.size);
      for (const auto& [b, o] : elim_[i].slots) {
        const int t = tan_[static_cast<std::size_t>(b)];
        v.head(l.size) -= Eigen::Map<const RowMatrix>(elim_[i].w.data() + o, l.size, t) *
                          y.segment(col_[static_cast<std::size_t>(b)], t);
      }
      y.segment(l.col, l.size) = (elim_[i].e_inv * v).head(l.size);
    }
    ok = y.allFinite();
  }
  summary_->linear_solver_ms += msSince(t0);
  return ok;
}

/// Ceres' DoglegStrategy::ComputeStep: unless the last step was rejected (then only the
/// interpolation is redone), the diagonal D, the scaled gradient, the Cauchy point and the
/// Gauss–Newton step (regularized by μ·D², μ raised tenfold while the solve fails).
bool Solver::computeStep(VectorXd& step) {
  if (!reuse_) {
    reuse_ = true;
    const VectorXd sq = squaredColumnNorms();
    diag_ = sq.cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal).cwiseSqrt();
    multiplyJt(r_, b_);
    grad_ = b_.cwiseQuotient(diag_);
    VectorXd Jg;
    multiplyJ(grad_.cwiseQuotient(diag_), Jg);
    alpha_ = grad_.squaredNorm() / Jg.squaredNorm();
    bool solved = false;
    while (mu_ < kMaxMu) {
      const VectorXd lm2 = diag_.cwiseAbs2() * mu_;
      if ((solved = solveNormal(lm2, gn_))) break;
      mu_ *= kMuIncrease;
    }
    if (!solved) return false;
    gn_ = -gn_.cwiseProduct(diag_);
  }
  doglegStep(step);
  return true;
}

/// Ceres' traditional dogleg in the D-scaled space, returned in the Jacobi-scaled space.
void Solver::doglegStep(VectorXd& step) {
  const double g_norm = grad_.norm(), gn_norm = gn_.norm();
  if (gn_norm <= radius_) {
    step = gn_;
    step_norm_ = gn_norm;
  } else if (g_norm * alpha_ >= radius_) {
    step = -(radius_ / g_norm) * grad_;
    step_norm_ = radius_;
  } else {
    const double b_dot_a = -alpha_ * grad_.dot(gn_);
    const double a_sq = std::pow(alpha_ * g_norm, 2.0);
    const double b_minus_a_sq = a_sq - 2 * b_dot_a + std::pow(gn_norm, 2);
    const double c = b_dot_a - a_sq;
    const double d = std::sqrt(c * c + b_minus_a_sq * (std::pow(radius_, 2.0) - a_sq));
    const double beta = (c <= 0) ? (d - c) / b_minus_a_sq : (radius_ * radius_ - a_sq) / (d + c);
    step = (-alpha_ * (1.0 - beta)) * grad_ + beta * gn_;
    step_norm_ = step.norm();
  }
  step = step.cwiseQuotient(diag_);
}

void Solver::readState(std::vector<double>& x) const {
  x.resize(static_cast<std::size_t>(n_x_));
  for (std::size_t b = 0; b < p_.blocks().size(); ++b)
    if (x_off_[b] >= 0) std::copy_n(p_.blocks()[b].x, p_.blocks()[b].size, x.data() + x_off_[b]);
}

void Solver::writeState(const std::vector<double>& x) const {
  for (std::size_t b = 0; b < p_.blocks().size(); ++b)
    if (x_off_[b] >= 0) std::copy_n(x.data() + x_off_[b], p_.blocks()[b].size, p_.blocks()[b].x);
}

bool Solver::plus(const std::vector<double>& x, const VectorXd& delta, std::vector<double>& out) const {
  out = x;
  for (std::size_t b = 0; b < p_.blocks().size(); ++b) {
    if (x_off_[b] < 0) continue;
    const auto& blk = p_.blocks()[b];
    const double* xb = x.data() + x_off_[b];
    double* ob = out.data() + x_off_[b];
    if (blk.manifold) {
      if (!blk.manifold->Plus(xb, delta.data() + col_[b], ob)) return false;
    } else {
      for (int i = 0; i < blk.size; ++i) ob[i] = xb[i] + delta(col_[b] + i);
    }
  }
  return true;
}

double Solver::gradientMaxNorm() const {
  std::vector<double> moved;
  if (!plus(x_, -g_unscaled_, moved)) return std::numeric_limits<double>::infinity();
  double m = 0;
  for (std::size_t i = 0; i < moved.size(); ++i) m = std::max(m, std::abs(x_[i] - moved[i]));
  return m;
}

/// The end of an iteration: the callback, then the time, iteration, gradient and radius tests.
bool Solver::tick(WindowSolverSummary& s, int iteration, bool successful) {
  if (o_.after_iteration) o_.after_iteration();
  if (msSince(start_) >= 1e3 * o_.max_solver_time_s) return false;
  if (iteration >= o_.max_num_iterations) return false;
  if ((successful && gradientMaxNorm() <= o_.gradient_tolerance) || radius_ <= kMinRadius) {
    s.converged = true;
    return false;
  }
  return true;
}

/// Linearizes at x_ (cost, corrected residuals, scaled Jacobians, the unscaled gradient).
bool Solver::linearize(bool first) {
  if (!evaluate(true, r_, x_cost_)) return false;
  multiplyJt(r_, g_unscaled_);
  scaleColumns(first);
  return true;
}

WindowSolverSummary Solver::run() {
  WindowSolverSummary s;
  summary_ = &s;
  layout();
  s.preprocess_ms = msSince(start_);
  readState(x_);
  if (!linearize(true)) return s;
  s.usable = true;
  s.initial_cost = s.final_cost = x_cost_;
  if (n_ == 0) {  // nothing to solve for (every block constant)
    s.converged = true;
    return s;
  }
  radius_ = o_.initial_trust_region_radius;
  int invalid = 0, iteration = 0;
  last_successful_ = true;
  while (tick(s, iteration, last_successful_)) {
    ++iteration;
    VectorXd step, Js;
    double model_change = 0;
    bool valid = computeStep(step);
    if (valid) {
      multiplyJ(step, Js);
      model_change = -Js.dot(Eigen::Map<const VectorXd>(r_.data(), rows_) + Js / 2.0);
      valid = model_change > 0.0;
    }
    if (!valid) {
      ++s.unsuccessful_steps;
      last_successful_ = false;
      if (++invalid >= kMaxInvalidSteps) break;
      mu_ *= kMuIncrease;
      reuse_ = false;
      continue;
    }
    invalid = 0;
    if (!trial(s, step.cwiseProduct(scaling_), model_change)) break;
  }
  writeState(x_);
  s.final_cost = x_cost_;
  s.minimizer_ms = msSince(start_) - s.preprocess_ms;
  return s;
}

/// Tries x ⊞ delta: false when a tolerance ends the solve (or the new point cannot be
/// linearized); otherwise the step is accepted or rejected and the radius updated.
bool Solver::trial(WindowSolverSummary& s, const VectorXd& delta, double model_change) {
  double cand_cost = std::numeric_limits<double>::max();
  if (plus(x_, delta, x_cand_)) {
    writeState(x_cand_);
    if (!evaluate(false, r_cand_, cand_cost)) cand_cost = std::numeric_limits<double>::max();
  }
  double step_sq = 0, x_sq = 0;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    step_sq += (x_[i] - x_cand_[i]) * (x_[i] - x_cand_[i]);
    x_sq += x_[i] * x_[i];
  }
  const double ptol = o_.parameter_tolerance;
  if (std::sqrt(step_sq) <= ptol * (std::sqrt(x_sq) + ptol) ||
      std::abs(x_cost_ - cand_cost) <= o_.function_tolerance * x_cost_) {
    s.converged = true;
    return false;
  }
  const double relative_decrease = (x_cost_ - cand_cost) / model_change;
  if (relative_decrease > kMinRelativeDecrease) {
    const std::vector<double> x_before = x_;
    const double cost_before = x_cost_;
    x_ = x_cand_;
    if (!linearize(false)) {
      x_ = x_before;
      x_cost_ = cost_before;
      return false;
    }
    ++s.successful_steps;
    if (relative_decrease < 0.25) radius_ *= 0.5;
    if (relative_decrease > 0.75) radius_ = std::max(radius_, 3.0 * step_norm_);
    mu_ = std::max(kMinMu, 2.0 * mu_ / kMuIncrease);
    reuse_ = false;
    last_successful_ = true;
  } else {
    writeState(x_);
    ++s.unsuccessful_steps;
    radius_ *= 0.5;
    reuse_ = true;
    last_successful_ = false;
  }
  return true;
}

}  // namespace idyvins::backend::window

namespace idyvins::backend {

WindowSolverSummary solveWindow(const WindowProblem& problem, const WindowSolverOptions& options) {
  return window::Solver(problem, options).run();
}

}  // namespace idyvins::backend
