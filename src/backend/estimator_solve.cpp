// The window's solve: state blocks, the marginalization prior, the bias anchor after a reset,
// IMU and projection factors (candidates weighted 1/m_j, refreshed every iteration, DESIGN
// §4.5), Ceres, then the gauge restored and the preintegrations repropagated.

#include <ceres/ceres.h>

#include <chrono>
#include <deque>
#include <functional>

#include "backend/estimator.h"
#include "backend/gauge.h"
#include "backend/imu_factor.h"
#include "backend/landmark_factors.h"
#include "backend/parameter_blocks.h"
#include "backend/window_problem.h"
#include "dynamic/dynamic.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
const PoseManifold kPoseManifold;
}  // namespace

void Estimator::optimize(FrameResult& r) {
  const auto start = std::chrono::steady_clock::now();
  WindowProblem problem;
  std::vector<std::shared_ptr<ceres::CostFunction>> costs;  // owned here, borrowed by the problem
  ceres::HuberLoss huber(options_.huber_px);
  r.skipped_blocks = addStateAndImu(problem, costs);
  // Candidate weights 1/m_j (DESIGN §4.5), owned here, refreshed after every iteration.
  std::deque<CandidateWeight> weights;
  addExtrinsic(problem, costs);
  r.landmarks = addProjections(problem, costs, huber, weights, r.candidates);
  holdSpeedBiasesAcrossGaps(problem, costs);
  // The offset, observable only in motion, is held while the oldest frame is slow (as VINS-Fusion).
  if (estimatesTd() && problem.hasParameterBlock(&w_.td_s) && w_.frames[0].nav().v_w.norm() < kMinSpeedForTd)
    problem.setParameterBlockConstant(&w_.td_s);
  refreshWeights(weights);
  const Isometry3d T_w_b0_before = w_.frames[0].T_w_b();
  const auto solve_start = std::chrono::steady_clock::now();
  SolveProfile& p = r.solve;
  if (options_.window_solver) {
    WindowSolverOptions o;
    if (!weights.empty()) o.after_iteration = [&] { refreshWeights(weights); };
    o.max_num_iterations = options_.max_num_iterations;
    o.function_tolerance = options_.function_tolerance;
    if (options_.time_limited) o.max_solver_time_s = options_.max_solver_time_s;  // live only
    const WindowSolverSummary s = solveWindow(problem, o);
    p.preprocess_ms = s.preprocess_ms;
    p.residual_ms = s.residual_ms;
    p.jacobian_ms = s.jacobian_ms;
    p.linear_solver_ms = s.linear_solver_ms;
    p.minimizer_ms = s.minimizer_ms;
    p.iterations = 1 + s.successful_steps + s.unsuccessful_steps;  // as Ceres: iteration 0 counts as a step
    p.converged = s.converged;
  } else {
    solveWithCeres(problem, weights, p);
  }
  const auto post_start = std::chrono::steady_clock::now();
  storeSolved();
  if (options_.fix_gauge && options_.use_imu) restoreGauge(T_w_b0_before);  // imu: 0 holds frame 0 itself
  velocitiesFromPositions();
  for (int i = 1; i <= w_.count; ++i) {
    const imu::NavState s = w_.frames[i - 1].nav();
    if (w_.frames[i].pre && w_.frames[i].pre->needsRepropagation(s.ba, s.bg)) w_.frames[i].pre->repropagate(s.ba, s.bg);
  }
  const auto end = std::chrono::steady_clock::now();
  using Ms = std::chrono::duration<double, std::milli>;
  r.optimization_ms = Ms(end - start).count();
  p.build_ms = Ms(solve_start - start).count();
  p.post_ms = Ms(end - post_start).count();
}

void Estimator::solveWithCeres(const WindowProblem& window, std::deque<CandidateWeight>& weights,
                               SolveProfile& p) const {
  ceres::Problem problem(borrowingProblemOptions());
  window.toCeres(problem);
  struct Refresh : ceres::IterationCallback {
    std::function<void()> f;
    ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
      f();
      return ceres::SOLVER_CONTINUE;
    }
  } callback;
  callback.f = [&] { refreshWeights(weights); };
  ceres::Solver::Options o;
  if (!weights.empty()) {
    o.callbacks.push_back(&callback);
    o.update_state_every_iteration = true;  // the callback reads the current poses
  }
  o.linear_solver_type = ceres::DENSE_SCHUR;
  o.trust_region_strategy_type = ceres::DOGLEG;
  o.max_num_iterations = options_.max_num_iterations;
  o.function_tolerance = options_.function_tolerance;
  if (options_.time_limited) o.max_solver_time_in_seconds = options_.max_solver_time_s;  // live only
  o.num_threads = 1;                                                                     // deterministic
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  p.preprocess_ms = 1e3 * summary.preprocessor_time_in_seconds;
  p.residual_ms = 1e3 * summary.residual_evaluation_time_in_seconds;
  p.jacobian_ms = 1e3 * summary.jacobian_evaluation_time_in_seconds;
  p.linear_solver_ms = 1e3 * summary.linear_solver_time_in_seconds;
  p.minimizer_ms = 1e3 * summary.minimizer_time_in_seconds;
  p.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  p.converged = summary.termination_type == ceres::CONVERGENCE;
}

void Estimator::addExtrinsic(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs) {
  if (options_.estimate_extrinsic == 0 || !options_.use_imu) return;
  const bool moving = w_.frames[0].nav().v_w.norm() >= kMinSpeedForTd;
  if (!ex_.open) {
    if (!w_.initialized || !moving || w_.count < kWindowSize) return;  // not observable yet: as written
    ex_.open = true;
    setPose(rig_.T_b_c0.t_b_c, rig_.T_b_c0.q_b_c, ex_.block.data());
  }
  problem.addParameterBlock(ex_.block.data(), kPoseSize, &kPoseManifold);
  costs.push_back(std::make_shared<PosePriorFactor>(ex_.start, options_.extrinsic_prior_m,
                                                    options_.extrinsic_prior_deg * M_PI / 180.0));
  problem.addResidualBlock(costs.back().get(), nullptr, ex_.block.data());
  if (!moving) problem.setParameterBlockConstant(ex_.block.data());  // as the offset: observable in motion only
}

void Estimator::storeExtrinsic() {
  rig_.T_b_c0.t_b_c = Eigen::Map<const Vector3d>(ex_.block.data());
  rig_.T_b_c0.q_b_c = Eigen::Map<const Quaterniond>(ex_.block.data() + 3).normalized();
  if (rig_.stereo) rig_.T_b_c1 = compose(rig_.T_b_c0, ex_.T_c0_c1);
}

ExtrinsicEstimate Estimator::extrinsicEstimate() const {
  ExtrinsicEstimate e;
  e.t_b_c0 = rig_.T_b_c0.t_b_c;
  e.q_b_c0 = rig_.T_b_c0.q_b_c;
  e.open = ex_.open;
  e.rotation_known = ex_.rotation_known;
  if (ex_.sigma) {
    e.sigma_t_m = ex_.sigma->t_m;
    e.sigma_rot_deg = ex_.sigma->rot_rad * 180.0 / M_PI;
  }
  return e;
}

void Estimator::holdSpeedBiasesAcrossGaps(WindowProblem& problem,
                                          std::vector<std::shared_ptr<ceres::CostFunction>>& costs) const {
  const auto imu_in = [&](int i) { return i >= 1 && w_.frames[i].pre && w_.frames[i].pre->sumDt() <= 10.0; };
  std::vector<bool> in_prior(static_cast<std::size_t>(w_.count + 1), false);
  if (w_.prior)
    for (const double* b : w_.prior->blocks)
      for (int i = 0; i <= w_.count; ++i)
        if (b == w_.frames[i].sb.data()) in_prior[i] = true;
  for (int i = 0; i <= w_.count; ++i) {
    if (imu_in(i) || in_prior[i]) continue;  // an IMU factor into the frame, or the prior, holds its biases
    double* sb = const_cast<double*>(w_.frames[i].sb.data());  // the problem holds blocks as mutable
    if (!(i < w_.count && imu_in(i + 1))) {  // no IMU factor at all: speed and biases carried as they are
      if (problem.hasParameterBlock(sb) && !(i == 0 && seg_.bias_anchor && options_.use_imu))
        problem.setParameterBlockConstant(sb);
      continue;
    }
    if (i == 0 && !w_.prior) continue;  // the window's first frame: free, or tied by the bias anchor (as before)
    // The first IMU factor after a gap: its biases stay those carried across it, within the
    // random walk of the gap (the one factor alone would trade them for the velocity's error).
    int k = i - 1;
    while (k > 0 && !imu_in(k)) --k;
    const double gap_s = std::max(1e-3, 1e-9 * static_cast<double>(w_.frames[i].t_ns - w_.frames[std::max(k, 0)].t_ns));
    const imu::NavState s = w_.frames[i].nav();
    costs.push_back(std::make_shared<BiasPriorFactor>(s.ba, s.bg, std::max(1e-3, noise_.acc_w * std::sqrt(gap_s)),
                                                      std::max(1e-5, noise_.gyr_w * std::sqrt(gap_s))));
    problem.addResidualBlock(costs.back().get(), nullptr, sb);
  }
}

void Estimator::velocitiesFromPositions() {
  for (int i = 1; i <= w_.count; ++i) {
    const bool in = w_.frames[i].pre != nullptr, out = i < w_.count && w_.frames[i + 1].pre != nullptr;
    if (in || out) continue;  // an IMU factor estimates this frame's speed
    imu::NavState s = w_.frames[i].nav();
    const double dt = 1e-9 * static_cast<double>(w_.frames[i].t_ns - w_.frames[i - 1].t_ns);
    if (dt > 0) s.v_w = (s.p_w_b - w_.frames[i - 1].nav().p_w_b) / dt;
    w_.frames[i].setNav(s);
  }
}

bool Estimator::finiteAt(const ceres::CostFunction& cost, const std::vector<double*>& blocks) {
  std::vector<double> residuals(static_cast<std::size_t>(cost.num_residuals()));
  if (!cost.Evaluate(blocks.data(), residuals.data(), nullptr)) return false;
  for (double x : residuals)
    if (!std::isfinite(x)) return false;
  return true;
}

int Estimator::addStateAndImu(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs) {
  int skipped = 0;
  for (int i = 0; i <= w_.count; ++i) {
    problem.addParameterBlock(w_.frames[i].pose.data(), 7, &kPoseManifold);
    problem.addParameterBlock(w_.frames[i].sb.data(), 9);
  }
  if (!options_.use_imu) problem.setParameterBlockConstant(w_.frames[0].pose.data());  // the gauge, as VINS-Fusion
  // Every block is evaluated once before it enters the problem: one that is not finite at
  // the start values (a degenerate integration, a prior gone bad) is left out and counted.
  if (w_.prior) {
    costs.push_back(std::make_shared<MarginalizationFactor>(w_.prior));
    if (finiteAt(*costs.back(), w_.prior->blocks))
      problem.addResidualBlock(costs.back().get(), nullptr, w_.prior->blocks);
    else
      ++skipped;
  }
  addBiasAnchor(problem, costs);
  for (int i = 1; i <= w_.count; ++i) {
    if (!w_.frames[i].pre || w_.frames[i].pre->sumDt() > 10.0) continue;  // across an IMU gap: none
    costs.push_back(std::make_shared<ImuFactor>(w_.frames[i].pre.get()));
    const std::vector<double*> blocks{w_.frames[i - 1].pose.data(), w_.frames[i - 1].sb.data(),
                                      w_.frames[i].pose.data(), w_.frames[i].sb.data()};
    if (finiteAt(*costs.back(), blocks))
      problem.addResidualBlock(costs.back().get(), nullptr, blocks);
    else
      ++skipped;
  }
  return skipped;
}

void Estimator::addBiasAnchor(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs) {
  if (w_.prior) seg_.bias_anchor.reset();  // the window has its own prior now
  if (!seg_.bias_anchor || !options_.use_imu) return;
  costs.push_back(std::make_shared<BiasPriorFactor>(seg_.bias_anchor->head<3>(), seg_.bias_anchor->tail<3>(),
                                                    options_.reset_bias_prior_acc, options_.reset_bias_prior_gyr));
  problem.addResidualBlock(costs.back().get(), nullptr, w_.frames[0].sb.data());
}

std::vector<double*> Estimator::factorBlocks(Landmark& lm, int frame, bool with_td) {
  std::vector<double*> blocks;
  if (frame >= 0) blocks = {w_.frames[lm.start_frame].pose.data(), w_.frames[frame].pose.data()};
  if (frame >= 0 && estimatesExtrinsic()) blocks.push_back(ex_.block.data());
  if (estimatesRays()) {
    lm.ray_block = {lm.anchorRay().x(), lm.anchorRay().y(), lm.inv_depth};
    blocks.push_back(lm.ray_block.data());
  } else {
    blocks.push_back(&lm.inv_depth);
  }
  if (with_td) blocks.push_back(&w_.td_s);
  return blocks;
}

int Estimator::addProjections(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs,
                              ceres::LossFunction& huber, std::deque<CandidateWeight>& weights, int& candidates) {
  const ProjectionWeight w{rig_.focal_px, options_.sigma_px, nullptr};
  int used = 0;
  for (auto& [id, lm] : w_.fm.landmarks()) {
    if (!inSolve(lm)) continue;
    ++used;
    const bool candidate = options_.candidate_weights && lm.label == FeatureLabel::kCandidate;
    candidates += candidate;
    std::map<int, const double*> scale_of_frame;
    if (candidate) {
      for (std::size_t k = 1; k < lm.obs.size(); ++k) {
        weights.push_back({&lm, lm.start_frame + static_cast<int>(k), 1.0});
        scale_of_frame[weights.back().frame] = &weights.back().info;
      }
    }
    for (const auto& lf : landmarkFactors(lm, rig_, w, TdUse{estimatesTd(), std::nullopt}, scale_of_frame,
                                          estimatesRays(), extrinsicUse())) {
      costs.push_back(lf.cost);
      problem.addResidualBlock(lf.cost.get(), &huber, factorBlocks(lm, lf.frame, estimatesTd()));
    }
    const double* block = estimatesRays() ? lm.ray_block.data() : &lm.inv_depth;
    if (problem.hasParameterBlock(block)) problem.setLandmark(block);
  }
  return used;
}

void Estimator::storeSolved() {
  if (estimatesRays()) storeRays();
  if (estimatesExtrinsic()) storeExtrinsic();
}

void Estimator::storeRays() {
  for (auto& [id, lm] : w_.fm.landmarks()) {
    if (!inSolve(lm)) continue;
    lm.ray_estimated = true;
    lm.ray_xy = Vector2d(lm.ray_block[0], lm.ray_block[1]);
    lm.inv_depth = lm.ray_block[2];
  }
}

void Estimator::refreshWeights(std::deque<CandidateWeight>& weights) const {
  for (auto& wt : weights) {
    const Isometry3d T_ci = cameraPose(w_.frames[wt.lm->start_frame].T_w_b(), rig_.T_b_c0);
    const Isometry3d T_cj = cameraPose(w_.frames[wt.frame].T_w_b(), rig_.T_b_c0);
    const Isometry3d T_ci_cj = T_ci.inverse() * T_cj;
    const double m = dynamic::epipolarErrorPx2(wt.lm->obs.front().xy, wt.lm->obs[wt.frame - wt.lm->start_frame].xy,
                                               T_ci_cj.linear(), T_ci_cj.translation(), rig_.fx, rig_.fy);
    wt.info = dynamic::candidateInformation(m);
  }
}

void Estimator::restoreGauge(const Isometry3d& T_w_b0_before) {
  const Isometry3d G = gaugeCorrection(T_w_b0_before, w_.frames[0].T_w_b());
  const Quaterniond q_G(G.linear());
  for (int i = 0; i <= w_.count; ++i) {
    imu::NavState s = w_.frames[i].nav();
    s.p_w_b = G * s.p_w_b;
    s.q_w_b = (q_G * s.q_w_b).normalized();
    s.v_w = q_G * s.v_w;
    w_.frames[i].setNav(s);
  }
}
}  // namespace idyvins::backend
