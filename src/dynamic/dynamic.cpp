#include "dynamic/dynamic.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "camera/stereo.h"
#include "core/so3.h"

namespace idyvins::dynamic {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

/// Depth range (m) of the stereo points the dynamic-scene tests judge: nearer is a
/// degenerate match, farther is clamped (a negative disparity from noise is a far point).
constexpr double kMinDepthM = 0.1, kMaxDepthM = 1000.0;
/// A point nearer than this (m) to either camera makes the stereo motion residual invalid.
constexpr double kMinPointDepthM = 0.05;

frontend::MotionPrior cameraMotionPrior(const imu::RelativeMotion& body, const Eigen::Isometry3d& T_b_c) {
  const Matrix3d R_bc = T_b_c.linear();
  const Vector3d t_bc = T_b_c.translation();
  const Matrix3d R_b = body.q_bi_bj.toRotationMatrix();
  frontend::MotionPrior p;
  p.valid = true;
  p.q_prev_cur = Eigen::Quaterniond(R_bc.transpose() * R_b * R_bc).normalized();
  p.t_prev_cur = R_bc.transpose() * (R_b * t_bc + body.p_bi_bj - t_bc);
  p.cov_p = body.cov_p;
  return p;
}

frontend::MotionPrior motionPrior(const imu::NavState& s, TimeNs t_prev, TimeNs t_cur,
                                  const std::vector<ImuSample>& imu, const ImuNoise& noise,
                                  const Eigen::Isometry3d& T_b_c) {
  if (imu.empty() || imu.front().t_ns > t_prev || imu.back().t_ns < t_cur || t_cur <= t_prev) return {};
  const imu::Preintegration pre = imu::integrateBetween(imu, t_prev, t_cur, s.ba, s.bg, noise);
  return cameraMotionPrior(pre.relativeMotion(s), T_b_c);
}

imu::RelativeMotion constantVelocityMotion(const Eigen::Isometry3d& T_w_b_older, TimeNs t_older,
                                           const Eigen::Isometry3d& T_w_b_newer, TimeNs t_newer, TimeNs t_prev,
                                           TimeNs t_cur, double acc_sigma) {
  imu::RelativeMotion m;
  if (t_newer <= t_older || t_cur <= t_prev) return m;
  const double dt = 1e-9 * static_cast<double>(t_cur - t_prev);
  const double scale = dt / (1e-9 * static_cast<double>(t_newer - t_older));
  const Eigen::Isometry3d rel = T_w_b_older.inverse() * T_w_b_newer;
  m.q_bi_bj = expQuat(scale * logQuat(Eigen::Quaterniond(rel.linear())));
  m.p_bi_bj = scale * rel.translation();
  const double sigma = 0.5 * acc_sigma * dt * dt;
  m.cov_p = sigma * sigma * Matrix3d::Identity();
  return m;
}

double credibility(const frontend::MotionPrior& p) {
  const double t = p.t_prev_cur.norm();
  if (t < 1e-9) return 1.0;
  const double sigma_p = std::sqrt(std::max(0.0, p.cov_p.trace()));
  return (1.0 + sigma_p / t) * (1.0 + sigma_p / t);
}

double epipolarErrorPx2(const Vector2d& x0, const Vector2d& x1, const Matrix3d& R, const Vector3d& t, double fx,
                        double fy) {
  const Matrix3d E = hat(t) * R;
  // K⁻¹ = [[1/fx, 0, -cx/fx], [0, 1/fy, -cy/fy], [0, 0, 1]]; with p = K x, K⁻¹ p = x.
  // [a b c] = p0ᵀ K⁻ᵀ E K⁻¹ = x0ᵀ E K⁻¹: a = (x0ᵀE)_0 / fx, b = (x0ᵀE)_1 / fy.
  const Eigen::RowVector3d l = Vector3d(x0.x(), x0.y(), 1.0).transpose() * E;
  const double a = l(0) / fx, b = l(1) / fy;
  const double e = l.dot(Vector3d(x1.x(), x1.y(), 1.0));  // = [a b c] · p1
  const double ab = a * a + b * b;
  if (ab < 1e-18) return 0.0;
  return e * e / ab;
}

StereoMotionError stereoMotionError(const Vector2d& x0_l, const Vector2d& x0_r, const Vector2d& x1_l,
                                    const Vector2d& x1_r, const Eigen::Isometry3d& T_r_l, const Matrix3d& R,
                                    const Vector3d& t, double sigma_p2, double focal, double sigma_px,
                                    const Eigen::Matrix2d& shape) {
  StereoMotionError out;
  const Matrix3d R_rl = T_r_l.linear();
  const Vector3d t_rl = T_r_l.translation();
  const double baseline = t_rl.norm();
  if (baseline < 1e-9 || focal <= 0) return out;
  // Depth along the left ray d from the right observation: x_r × (λ R_rl d + t_rl) = 0.
  const Vector3d d(x0_l.x(), x0_l.y(), 1.0), xr(x0_r.x(), x0_r.y(), 1.0);
  const Vector3d a = xr.cross(R_rl * d), b = xr.cross(t_rl);
  if (a.squaredNorm() < 1e-18) return out;
  const double lambda = -a.dot(b) / a.squaredNorm();
  // Inverse depth, clamped to [1/kMaxDepthM, 1/kMinDepthM]: a negative disparity from noise
  // is a far point.
  const double rho = std::clamp(lambda > 0 ? 1.0 / lambda : 1.0 / kMaxDepthM, 1.0 / kMaxDepthM, 1.0 / kMinDepthM);
  bool ok = true;
  auto residual = [&](double r_inv, const Vector3d& t_pc) {
    Eigen::Matrix<double, 4, 1> r;
    const Vector3d P1 = R.transpose() * (d / r_inv - t_pc);
    const Vector3d Pr = R_rl * P1 + t_rl;
    if (P1.z() < kMinPointDepthM || Pr.z() < kMinPointDepthM) ok = false;
    r.head<2>() = focal * (P1.head<2>() / P1.z() - x1_l);
    r.tail<2>() = focal * (Pr.head<2>() / Pr.z() - x1_r);
    return r;
  };
  const Eigen::Matrix<double, 4, 1> r = residual(rho, t);
  if (!ok) return out;
  const double h_rho = 1e-6 * rho, h_t = 1e-6;
  const Eigen::Matrix<double, 4, 1> J_rho = (residual(rho + h_rho, t) - residual(rho - h_rho, t)) / (2 * h_rho);
  Eigen::Matrix<double, 4, 3> J_t;
  for (int i = 0; i < 3; ++i) {
    const Vector3d e = Vector3d::Unit(i) * h_t;
    J_t.col(i) = (residual(rho, t + e) - residual(rho, t - e)) / (2 * h_t);
  }
  if (!ok) return out;
  const double sigma_rho = std::sqrt(2.0 * std::max(shape(0, 0), 0.0)) * sigma_px / (focal * baseline);
  Eigen::Matrix4d measured = Eigen::Matrix4d::Zero();
  measured.topLeftCorner<2, 2>() = shape;
  measured.bottomRightCorner<2, 2>() = shape;
  const Eigen::Matrix4d C = 2.0 * sigma_px * sigma_px * measured + sigma_rho * sigma_rho * J_rho * J_rho.transpose() +
                            sigma_p2 * J_t * J_t.transpose();
  out.valid = true;
  out.chi2 = r.dot(C.ldlt().solve(r));
  const Eigen::Vector2d r_l = r.head<2>();
  out.chi2_left = r_l.dot(C.topLeftCorner<2, 2>().ldlt().solve(r_l));
  out.residual_px2 = r.squaredNorm();
  out.depth = 1.0 / rho;
  return out;
}

double stereoNoiseScale(std::vector<double> chi2, double quantile, double ref) {
  if (ref <= 0 || chi2.empty()) return 1.0;
  const auto k = static_cast<std::size_t>(quantile * static_cast<double>(chi2.size() - 1) + 0.5);
  std::nth_element(chi2.begin(), chi2.begin() + static_cast<std::ptrdiff_t>(k), chi2.end());
  return std::max(1.0, chi2[k] / ref);
}

const char* toString(StopRule rule) {
  switch (rule) {
    case StopRule::kThreshold:
      return "largest d_s <= lambda_dy";
    case StopRule::kCvReached:
      return "CV <= sqrt(2)";
    case StopRule::kCvNotLowered:
      return "removal would not lower CV";
    case StopRule::kEmpty:
      return "too few features";
  }
  return "?";
}

Elimination eliminate(const std::vector<double>& d, double lambda_dy) {
  Elimination out;
  std::size_t n = d.size();
  if (n < 2) return out;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return d[a] > d[b]; });
  double mu = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(n);
  double var = 0;
  for (double v : d) var += (v - mu) * (v - mu);
  var /= static_cast<double>(n);
  const auto cv = [](double m, double v) { return m > 0 ? std::sqrt(std::max(v, 0.0)) / m : 0.0; };
  out.cv_before = cv(mu, var);
  const double sqrt2 = std::sqrt(2.0);
  std::size_t next = 0;
  while (true) {
    if (n < 2) {
      out.stop = StopRule::kEmpty;
      break;
    }
    const double dn = d[order[next]];
    if (dn <= lambda_dy) {
      out.stop = StopRule::kThreshold;
      break;
    }
    const double c = cv(mu, var);
    if (c <= sqrt2) {
      out.stop = StopRule::kCvReached;
      break;
    }
    const double nn = static_cast<double>(n);
    const double mu1 = (nn * mu - dn) / (nn - 1.0);
    const double var1 = nn * var / (nn - 1.0) - (dn - mu1) * (dn - mu1) / nn;
    if (cv(mu1, var1) >= c) {
      out.stop = StopRule::kCvNotLowered;
      break;
    }
    out.removed.push_back(order[next]);
    ++next;
    --n;
    mu = mu1;
    var = var1;
  }
  out.mean_after = mu;
  out.var_after = var;
  out.cv_after = cv(mu, var);
  return out;
}

void IdyFilter::apply(const frontend::FilterContext& ctx, std::vector<frontend::FilterItem>& items) {
  std::vector<std::size_t> tracked;
  for (std::size_t i = 0; i < items.size(); ++i)
    if (items[i].tracked) tracked.push_back(i);
  if (tracked.empty()) return;  // the pass over new corners
  stats_ = FrameStats{};
  stats_.tracked = tracked.size();
  if (!ctx.prior || !ctx.prior->valid) {  // no prior yet: unfiltered (and the anchors' chains break)
    stereo_anchors_.clear();
    return;
  }
  stats_.prior_valid = true;
  const double sigma = credibility(*ctx.prior);
  stats_.credibility = sigma;
  const auto& p = ctx.camera->params();
  const auto f_px = camera::pixelsPerNormalized(p);
  const double fx = f_px[0], fy = f_px[1];
  const Matrix3d R = ctx.prior->q_prev_cur.toRotationMatrix();
  std::vector<std::size_t> scored, scored_items;  // positions in `tracked` judged by d_s; their items
  std::vector<double> raw, ds;
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    const auto& it = items[tracked[k]];
    it.feature->d_s_px2 = 0;
    if (std::max(it.feature->track_length, 2) < o_.ds_from_observation) continue;  // tracked: >= its 2nd
    scored.push_back(k);
    scored_items.push_back(tracked[k]);
    raw.push_back(epipolarErrorPx2(it.prev_xy, it.feature->xy, R, ctx.prior->t_prev_cur, fx, fy));
    ds.push_back(raw.back() / sigma);
    it.feature->d_s_px2 = ds.back();
  }
  stats_.d_s = ds;
  const std::vector<bool> removed_scored = eliminateAndMark(items, scored_items, raw, ds);
  std::vector<bool> removed(tracked.size(), false);
  for (std::size_t j = 0; j < scored.size(); ++j) removed[scored[j]] = removed_scored[j];
  if (o_.stereo.enabled && o_.T_r_l) stereoTest(ctx, items, tracked, removed, R, fx);
  if (o_.mono.enabled && !o_.T_r_l) monoTest(ctx, items, tracked, removed, R, fx);
}

std::vector<bool> IdyFilter::eliminateAndMark(std::vector<frontend::FilterItem>& items,
                                              const std::vector<std::size_t>& tracked, const std::vector<double>& raw,
                                              const std::vector<double>& ds) {
  std::vector<bool> removed(tracked.size(), false);
  if (eliminate_) {  // eq. 4-5
    const Elimination e = eliminate(ds, o_.lambda_dy);
    stats_.cv_before = e.cv_before;
    stats_.cv_after = e.cv_after;
    stats_.stop_rule = toString(e.stop);
    for (std::size_t r : e.removed) {
      removed[r] = true;
      items[tracked[r]].remove = true;
      items[tracked[r]].feature->label = frontend::FeatureLabel::kEliminated;
    }
    stats_.eliminated = e.removed.size();
  } else {
    const Elimination e = eliminate(ds, 1e300);  // statistics only
    stats_.cv_before = stats_.cv_after = e.cv_before;
  }
  for (std::size_t k = 0; k < tracked.size(); ++k)
    if (!removed[k]) stats_.d_s_kept.push_back(ds[k]);
  for (std::size_t k = 0; k < tracked.size(); ++k) {  // eq. 6
    if (removed[k] || raw[k] <= o_.lambda_dy_c) continue;
    items[tracked[k]].feature->label = frontend::FeatureLabel::kCandidate;
    ++stats_.candidates;
  }
  return removed;
}

bool IdyFilter::nextAnchor(const frontend::FilterItem& it, const frontend::MotionPrior& prior, const Matrix3d& R,
                           double sigma_p2, bool need_right, StereoAnchor& anchor, int& strikes_before) const {
  // The anchor: the stereo observation the current one is compared with, and the camera
  // motion since, chained from the per-frame priors (P_anchor = R P_cur + t).
  const auto old = stereo_anchors_.find(it.feature->id);
  strikes_before = old != stereo_anchors_.end() ? old->second.strikes : 0;
  const bool prev_usable = it.prev_has_right || !need_right;
  if (old != stereo_anchors_.end() && (old->second.steps < o_.stereo.anchor_frames || !prev_usable)) {
    anchor = old->second;
    anchor.t = anchor.R * prior.t_prev_cur + anchor.t;
    anchor.R = anchor.R * R;
    anchor.var_p += sigma_p2;
    ++anchor.steps;
  } else if (prev_usable) {
    anchor = {it.prev_xy, it.prev_xy_right, R, prior.t_prev_cur, sigma_p2, 1, 0};
  } else {
    return false;
  }
  anchor.strikes = 0;  // until this frame's test fails
  return true;
}

void IdyFilter::markCandidate(frontend::Feature& f) {
  if (f.label == frontend::FeatureLabel::kCandidate) return;
  f.label = frontend::FeatureLabel::kCandidate;
  ++stats_.candidates;
}

/// Fewer features tested by the stereo motion test than this: the frame keeps the previous
/// frame's noise scale.
constexpr std::size_t kNoiseMinFeatures = 10;

void IdyFilter::updateNoiseScale(const std::vector<StereoTested>& tested) {
  // The frame's noise scale, from its own χ² (kept from the last frame when too few).
  if (tested.size() >= kNoiseMinFeatures) {
    std::vector<double> chi2;
    chi2.reserve(tested.size());
    for (const auto& t : tested) chi2.push_back(t.e.chi2);
    noise_scale_ = stereoNoiseScale(std::move(chi2), o_.stereo.noise_quantile, o_.stereo.noise_ref);
  }
  stats_.stereo_noise_scale = noise_scale_;
}

void IdyFilter::judgeStereoFailures(std::vector<frontend::FilterItem>& items, const std::vector<StereoTested>& tested,
                                    std::unordered_map<std::uint64_t, StereoAnchor>& anchors, double fx) {
  const double baseline_px = fx * o_.T_r_l->translation().norm();
  for (const auto& t : tested) {
    auto& it = items[t.item];
    if (o_.stereo.min_disparity_px > 0 && baseline_px < o_.stereo.min_disparity_px * t.e.depth) continue;
    if (t.e.chi2 / noise_scale_ <= o_.stereo.chi2) continue;
    // only the right match disagrees
    if (o_.stereo.left_chi2 > 0 && t.e.chi2_left / noise_scale_ <= o_.stereo.left_chi2) continue;
    StereoAnchor& kept = anchors[it.feature->id];
    kept.strikes = t.strikes_before + 1;
    // A first failure only marks (one bad match is not motion); a repeated one removes when
    // its χ² is clear or the failures persist (slow motion along the line of sight).
    const bool clear = t.e.chi2 / noise_scale_ > o_.stereo.remove_chi2;
    const bool persistent = o_.stereo.persistent_strikes > 0 && kept.strikes >= o_.stereo.persistent_strikes;
    if (!(clear || persistent)) {
      markCandidate(*it.feature);
      continue;
    }
    stats_.stereo_eliminated += strike(it, kept.strikes);
  }
}

bool IdyFilter::strike(frontend::FilterItem& it, int strikes) {
  if (strikes < o_.stereo.strikes || !eliminate_) {
    markCandidate(*it.feature);
    return strikes >= o_.stereo.strikes;
  }
  it.remove = true;
  it.feature->label = frontend::FeatureLabel::kEliminated;
  ++stats_.eliminated;
  return true;
}

void IdyFilter::monoTest(const frontend::FilterContext& ctx, std::vector<frontend::FilterItem>& items,
                         const std::vector<std::size_t>& tracked, const std::vector<bool>& removed, const Matrix3d& R,
                         double fx) {
  const double sigma_p2 = std::max(0.0, ctx.prior->cov_p.trace()) / 3.0;
  const double dt = std::max(0.0, toSeconds(ctx.t_cur_ns - ctx.t_prev_ns));
  std::unordered_map<std::uint64_t, StereoAnchor> anchors;  // of the features seen now
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    auto& it = items[tracked[k]];
    StereoAnchor anchor;
    int strikes_before = 0;
    if (removed[k] || !nextAnchor(it, *ctx.prior, R, sigma_p2, false, anchor, strikes_before)) continue;
    const double drift = o_.stereo.drift_mps * (anchor.steps - 1) * dt;
    const DepthSign e = depthSign(anchor.xy_l, it.feature->xy, anchor.R, anchor.t, anchor.var_p + drift * drift, fx,
                                  o_.stereo.sigma_px);
    StereoAnchor& kept = anchors[it.feature->id] = anchor;
    if (!e.valid) continue;
    ++stats_.mono_tested;
    if (e.z >= -o_.mono.z) continue;
    kept.strikes = strikes_before + 1;
    stats_.mono_eliminated += strike(it, kept.strikes);
  }
  stereo_anchors_ = std::move(anchors);
}

void IdyFilter::stereoTest(const frontend::FilterContext& ctx, std::vector<frontend::FilterItem>& items,
                           const std::vector<std::size_t>& tracked, const std::vector<bool>& removed, const Matrix3d& R,
                           double fx) {
  const double sigma_p2 = std::max(0.0, ctx.prior->cov_p.trace()) / 3.0;
  const double dt = std::max(0.0, toSeconds(ctx.t_cur_ns - ctx.t_prev_ns));
  std::unordered_map<std::uint64_t, StereoAnchor> anchors;  // of the features seen now
  std::vector<StereoTested> tested;
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    auto& it = items[tracked[k]];
    if (removed[k]) continue;
    StereoAnchor anchor;
    int strikes_before = 0;
    if (!nextAnchor(it, *ctx.prior, R, sigma_p2, true, anchor, strikes_before)) continue;
    anchors[it.feature->id] = anchor;
    if (!it.feature->has_right) continue;
    ++stats_.stereo_tested;
    // Beyond the first step the chained priors drift (velocity error × time).
    const double drift = o_.stereo.drift_mps * (anchor.steps - 1) * dt;
    const StereoMotionError e =
        stereoMotionError(anchor.xy_l, anchor.xy_r, it.feature->xy, it.feature->xy_right, *o_.T_r_l, anchor.R, anchor.t,
                          anchor.var_p + drift * drift, fx, o_.stereo.sigma_px,
                          o_.stereo.shape ? it.feature->match_shape : Eigen::Matrix2d::Identity());
    if (!e.valid) continue;
    it.feature->stereo_chi2 = e.chi2;
    it.feature->stereo_depth = e.depth;
    tested.push_back({tracked[k], strikes_before, e});
  }
  updateNoiseScale(tested);
  judgeStereoFailures(items, tested, anchors, fx);
  stereo_anchors_ = std::move(anchors);
}

std::optional<StaticPrediction> predictStaticPoint(const frontend::LostCorner& c, const frontend::MotionPrior& prior,
                                                   const camera::CameraModel& left, const Eigen::Isometry3d& T_r_l,
                                                   double sigma_px, double base_tol_px) {
  double depth;
  if (!prior.valid || !camera::stereoDepth(c.xy, c.xy_right, T_r_l, depth) || depth < kMinDepthM) return std::nullopt;
  // The point as static, moved into the current frame by the prior (points of the current
  // camera map into the previous one by R_prev_cur, t_prev_cur).
  const Matrix3d R_cur_prev = prior.q_prev_cur.toRotationMatrix().transpose();
  auto predict = [&](double z, Vector2d& uv) {
    const Vector3d p_prev = Vector3d(c.xy.x(), c.xy.y(), 1.0) * z;
    const Vector3d p_cur = R_cur_prev * (p_prev - prior.t_prev_cur);
    return p_cur.z() > kMinDepthM && left.project(p_cur, uv);
  };
  StaticPrediction p;
  if (!predict(depth, p.uv_pred)) return std::nullopt;
  p.p_pred = R_cur_prev * (Vector3d(c.xy.x(), c.xy.y(), 1.0) * depth - prior.t_prev_cur);
  const double f = left.focal(), b = T_r_l.translation().norm();
  const double sigma_rho = std::sqrt(2.0) * sigma_px / (f * b);
  double tol_depth = 0;
  for (double s : {-3.0, 3.0}) {
    const double rho = std::max(1.0 / depth + s * sigma_rho, 1e-6);  // up to a point at infinity
    Vector2d uv;
    if (!predict(1.0 / rho, uv)) return std::nullopt;  // the interval reaches behind the camera
    tol_depth = std::max(tol_depth, (uv - p.uv_pred).norm());
  }
  p.tol_px = base_tol_px + tol_depth + 3.0 * f * std::sqrt(std::max(prior.cov_p.trace(), 0.0)) / depth;
  return p;
}

frontend::LostCornerJudgement IdyFilter::judgeLost(const frontend::FilterContext& ctx,
                                                   const std::vector<frontend::LostCorner>& lost,
                                                   frontend::LostCornerProbe& probe) {
  frontend::LostCornerJudgement j;
  if (!ctx.prior || !ctx.camera || !o_.T_r_l) return j;
  std::vector<frontend::LostCornerSearch> searches;
  for (std::size_t i = 0; i < lost.size(); ++i) {
    const auto p = predictStaticPoint(lost[i], *ctx.prior, *ctx.camera, *o_.T_r_l, o_.lost_stereo_sigma_px,
                                      o_.lost_base_tolerance_px);
    if (p && probe.searchable(p->uv_pred)) searches.push_back({i, p->uv_pred, p->p_pred, p->tol_px});
  }
  j.tested = searches.size();
  if (searches.empty()) return j;
  const std::vector<frontend::LostCornerFinding> found = probe.find(searches);
  std::vector<frontend::LostCornerSearch> not_found;
  for (std::size_t i = 0; i < searches.size(); ++i)
    if (!found[i].found && found[i].best_zncc < o_.lost_max_zncc) not_found.push_back(searches[i]);
  if (not_found.empty()) return j;
  // Occlusion: something nearer than the static point now stands where it should be (a
  // vehicle passing in front of the background): the corner is hidden, not moved.
  const std::vector<double> depth = probe.depthAt(not_found);
  for (std::size_t k = 0; k < not_found.size(); ++k)
    if (!(depth[k] > 0 && depth[k] < o_.lost_occlusion_ratio * not_found[k].p_pred.z()))
      j.moving.push_back(not_found[k].corner);
  return j;
}

}  // namespace idyvins::dynamic
