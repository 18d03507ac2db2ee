#pragma once
// The sliding window's least-squares problem and its own solver (DESIGN §4.4).
//
// WindowProblem records parameter blocks, residual blocks (the same ceres::CostFunction and
// LossFunction objects the factors are) and constant blocks in the order they are added, so
// the same problem can be handed to Ceres unchanged (toCeres). solveWindow minimizes it the way
// the estimator configured Ceres (trust-region dogleg, traditional, Jacobi scaling, Ceres 2.1's
// defaults and stopping rules) with a linear solver fitted to the window: the landmark blocks
// (size 1 or 3, at most one per residual block) are eliminated one at a time by their Schur
// complement, then the dense pose system is solved by Cholesky. No solver state outlives a solve.

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>

#include <cmath>
#include <functional>
#include <unordered_map>
#include <vector>

namespace ceres {
class Problem;
}  // namespace ceres

namespace idyvins::backend {

/// Options of solveWindow (the names and defaults of ceres::Solver::Options).
struct WindowSolverOptions {
  int max_num_iterations = 50;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  double max_solver_time_s = HUGE_VAL;
  double initial_trust_region_radius = 1e4;
  /// Called after every iteration (and after iteration 0) with the accepted state in the blocks;
  /// it may change residuals' weights (as a ceres::IterationCallback with update_state_every_iteration).
  std::function<void()> after_iteration;
};

/// What a solve did; times in ms.
struct WindowSolverSummary {
  bool usable = false;     ///< the blocks hold the best state found (false: evaluation failed at the start)
  bool converged = false;  ///< a tolerance was reached (Ceres' CONVERGENCE)
  int successful_steps = 0, unsuccessful_steps = 0;
  double initial_cost = 0, final_cost = 0;
  double preprocess_ms = 0, residual_ms = 0, jacobian_ms = 0, linear_solver_ms = 0, minimizer_ms = 0;
};

class WindowProblem {
 public:
  /// A block of `size` doubles at x, with its manifold (null: Euclidean); for a block added before,
  /// a manifold given here replaces its own (as ceres::Problem does).
  void addParameterBlock(double* x, int size, const ceres::Manifold* manifold = nullptr);
  /// A residual block; blocks not added yet are added (Euclidean, the cost's sizes).
  void addResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                        const std::vector<double*>& blocks);
  void addResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss, double* block) {
    addResidualBlock(cost, loss, std::vector<double*>{block});
  }
  void setParameterBlockConstant(const double* x);
  /// Marks a block as a landmark: eliminated by Schur complement, at most one per residual block.
  void setLandmark(const double* x);
  bool hasParameterBlock(const double* x) const { return index_.count(x) != 0; }
  /// The same calls, in the same order, on a Ceres problem.
  void toCeres(ceres::Problem& problem) const;

  struct Block {
    double* x;
    int size;
    const ceres::Manifold* manifold;
    bool constant = false, landmark = false;
  };
  struct Residual {
    const ceres::CostFunction* cost;
    const ceres::LossFunction* loss;
    std::vector<int> blocks;  ///< indices into blocks()
  };
  const std::vector<Block>& blocks() const { return blocks_; }
  const std::vector<Residual>& residuals() const { return residuals_; }

 private:
  enum class Op { kBlock, kResidual, kConstant };
  std::vector<Block> blocks_;
  std::vector<Residual> residuals_;
  std::vector<std::pair<Op, int>> log_;  ///< the calls in order (toCeres)
  std::unordered_map<const double*, int> index_;
};

/// Minimizes the problem in place (see the header comment). Throws std::invalid_argument for a
/// residual block with two landmark blocks.
WindowSolverSummary solveWindow(const WindowProblem& problem, const WindowSolverOptions& options);

}  // namespace idyvins::backend
