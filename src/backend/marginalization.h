#pragma once
// Marginalization: the residual blocks touching the dropped states are linearized
// at the current estimate, the dropped states are eliminated by a Schur
// complement, and what remains becomes a linear prior factor on the kept states.

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <memory>
#include <unordered_map>
#include <vector>

namespace idyvins::backend {

/// One residual block to be marginalized: its cost, optional loss, parameter
/// blocks, and which of them (indices into `blocks`) are dropped.
struct MarginalizationTerm {
  std::shared_ptr<const ceres::CostFunction> cost;
  std::shared_ptr<const ceres::LossFunction> loss;  ///< may be null
  std::vector<double*> blocks;
  std::vector<int> drop;
};

/// The linear prior left by a marginalization: residual r0 + J0 Δx over the kept
/// blocks, with Δx the tangent difference to the linearization point x0. Pose
/// blocks (size 7) use Δx = [p − p0, 2 vec(q0⁻¹ q)]; other blocks x − x0.
struct MarginalizationPrior {
  std::vector<double*> blocks;      ///< addresses of the kept blocks (for the next problem)
  std::vector<int> sizes;           ///< ambient sizes
  std::vector<int> tangent_sizes;   ///< 6 for poses, else = size
  std::vector<Eigen::VectorXd> x0;  ///< linearization values
  Eigen::MatrixXd J0;               ///< rows x sum(tangent_sizes)
  Eigen::VectorXd r0;
  /// Replaces block addresses (after the window slides); unknown ones are kept.
  void remap(const std::unordered_map<double*, double*>& old_to_new);
  /// Keeps the fraction `weight` (0, 1] of the prior's information: its cost at every
  /// Δx is multiplied by `weight` (a fading memory, EstimatorOptions::prior_fading).
  void scaleInformation(double weight);
};

/// Collects terms, then marginalizes. Block sizes are those of the cost functions.
class Marginalizer {
 public:
  void add(MarginalizationTerm term);
  /// Linearizes every term at the current values of the blocks and eliminates the
  /// dropped blocks. Eigenvalues below `eps` of the reduced system are dropped.
  MarginalizationPrior marginalize(double eps = 1e-8) const;

 private:
  std::vector<MarginalizationTerm> terms_;
};

/// Ceres factor for a marginalization prior; its blocks are prior.blocks.
class MarginalizationFactor final : public ceres::CostFunction {
 public:
  explicit MarginalizationFactor(std::shared_ptr<const MarginalizationPrior> prior);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  std::shared_ptr<const MarginalizationPrior> prior_;
};

}  // namespace idyvins::backend
