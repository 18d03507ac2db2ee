#pragma once
// The solver behind solveWindow (window_problem.h), shared by its two source files: the layout and
// evaluation (window_solver.cpp), the linear solver and the trust-region loop (window_solver_steps.cpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <vector>

#include "backend/window_problem.h"

namespace idyvins::backend::window {

using Clock = std::chrono::steady_clock;

class Solver {
 public:
  Solver(const WindowProblem& problem, const WindowSolverOptions& options) : p_(problem), o_(options) {}
  WindowSolverSummary run();

 private:
  struct Res {
    const WindowProblem::Residual* def;
    int m, r_off, landmark = -1;  ///< landmark: index into lms_
    std::vector<int> j_off;       ///< per block: offset of its tangent Jacobian in J_ (-1: constant)
  };
  struct Landmark {
    int block, col, size;
    std::vector<int> res;  ///< indices into res_
  };

  struct Elimination {                       ///< a landmark's couplings W (e x t per pose block, row-major) and E⁻¹
    std::vector<std::pair<int, int>> slots;  ///< block, offset in w
    std::vector<double> w;
    Eigen::Matrix3d e_inv;  ///< its top-left e x e, zero elsewhere
  };
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  void layout();
  void tangentSizes();
  void layoutResiduals(const std::vector<int>& lm_of_block);
  bool linearize(bool first);
  bool trial(WindowSolverSummary& s, const Eigen::VectorXd& delta, double model_change);
  void addFf(const Res& q, RowMatrix& H) const;
  void addFfDense(const Res& q, RowMatrix& H) const;
  bool evaluate(bool jacobians, std::vector<double>& r, double& cost);
  bool evaluateResidual(const Res& q, bool jacobians, std::vector<double>& r, double& cost);
  void scaleColumns(bool first);
  Eigen::VectorXd squaredColumnNorms() const;
  /// f(residual, offset of the block's Jacobian in J_, tangent size, first column) for every solved block.
  template <class F>
  void forEachJacobian(F f) const {
    for (const Res& q : res_)
      for (std::size_t k = 0; k < q.j_off.size(); ++k) {
        if (q.j_off[k] < 0) continue;
        const std::size_t b = static_cast<std::size_t>(q.def->blocks[k]);
        f(q, q.j_off[k], tan_[b], col_[b]);
      }
  }
  void multiplyJ(const Eigen::VectorXd& v, Eigen::VectorXd& out) const;
  void multiplyJt(const std::vector<double>& r, Eigen::VectorXd& out) const;
  bool solveNormal(const Eigen::VectorXd& lm2, Eigen::VectorXd& y);
  void eliminate(const Landmark& l, const Eigen::VectorXd& lm2, RowMatrix& H, Eigen::VectorXd& bf, Elimination& el);
  bool computeStep(Eigen::VectorXd& step);
  void doglegStep(Eigen::VectorXd& step);
  void readState(std::vector<double>& x) const;
  void writeState(const std::vector<double>& x) const;
  bool plus(const std::vector<double>& x, const Eigen::VectorXd& delta, std::vector<double>& out) const;
  double gradientMaxNorm() const;
  bool tick(WindowSolverSummary& s, int iteration, bool successful);

  const WindowProblem& p_;
  const WindowSolverOptions& o_;
  const Clock::time_point start_ = Clock::now();
  std::vector<int> col_, tan_, x_off_;  ///< per block: first column (-1: not solved), tangent size, offset in x
  std::vector<Res> res_;
  std::vector<Landmark> lms_;
  int n_ = 0, n_e_ = 0, n_x_ = 0, rows_ = 0, n_j_ = 0;
  std::vector<double> r_, J_, r_cand_, x_, x_cand_, scratch_;
  std::vector<Elimination> elim_;
  Eigen::VectorXd scaling_, diag_, b_, grad_, gn_, g_unscaled_;
  double x_cost_ = 0, alpha_ = 0, radius_ = 0, mu_ = 1e-8, step_norm_ = 0;
  bool reuse_ = false, last_successful_ = true;
  WindowSolverSummary* summary_ = nullptr;
};

double msSince(Clock::time_point t);

}  // namespace idyvins::backend::window
