#include "eval/trajectory_metrics.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace idyvins::eval {

bool parseAlignMode(const std::string& text, AlignMode& mode) {
  if (text == "se3")
    mode = AlignMode::kSe3;
  else if (text == "sim3")
    mode = AlignMode::kSim3;
  else if (text == "posyaw")
    mode = AlignMode::kPosYaw;
  else if (text == "none")
    mode = AlignMode::kNone;
  else
    return false;
  return true;
}

const char* toString(AlignMode mode) {
  switch (mode) {
    case AlignMode::kSe3:
      return "se3";
    case AlignMode::kSim3:
      return "sim3";
    case AlignMode::kPosYaw:
      return "posyaw";
    case AlignMode::kNone:
      return "none";
  }
  return "?";
}

std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<StampedPose>& ref,
                                                           const std::vector<StampedPose>& est, TimeNs max_dt_ns) {
  const bool est_longer = est.size() > ref.size();
  const auto& shorter = est_longer ? ref : est;
  const auto& longer = est_longer ? est : ref;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::size_t j = 0;
  for (std::size_t i = 0; i < shorter.size(); ++i) {
    const TimeNs t = shorter[i].t_ns;
    // Longer is sorted: advance to the first stamp >= t, then compare with its predecessor.
    while (j < longer.size() && longer[j].t_ns < t) ++j;
    std::size_t best = j < longer.size() ? j : longer.size() - 1;
    if (j > 0 && (j == longer.size() || std::llabs(longer[j - 1].t_ns - t) <= std::llabs(longer[j].t_ns - t)))
      best = j - 1;  // ties go to the earlier index, as numpy's argmin does
    if (longer.empty() || std::llabs(longer[best].t_ns - t) > max_dt_ns) continue;
    pairs.push_back(est_longer ? std::make_pair(i, best) : std::make_pair(best, i));
  }
  return pairs;
}

Similarity umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  if (src.cols() != dst.cols() || src.cols() < 2) throw std::invalid_argument("umeyama: need >= 2 point pairs");
  const double n = static_cast<double>(src.cols());
  const Eigen::Vector3d mu_s = src.rowwise().mean(), mu_d = dst.rowwise().mean();
  const Eigen::Matrix3Xd sc = src.colwise() - mu_s, dc = dst.colwise() - mu_d;
  const double sigma_s = sc.squaredNorm() / n;
  const Eigen::Matrix3d cov = dc * sc.transpose() / n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  if ((d.array() > std::numeric_limits<double>::epsilon()).count() < 2)
    throw std::invalid_argument("umeyama: degenerate point configuration");
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  Similarity out;
  out.R = svd.matrixU() * S * svd.matrixV().transpose();
  out.s = with_scale ? (d.asDiagonal() * S).trace() / sigma_s : 1.0;
  out.t = mu_d - out.s * out.R * mu_s;
  return out;
}

Similarity alignPositionYaw(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst) {
  if (src.cols() != dst.cols() || src.cols() < 1) throw std::invalid_argument("posyaw: need point pairs");
  const Eigen::Vector3d mu_s = src.rowwise().mean(), mu_d = dst.rowwise().mean();
  double a = 0, b = 0;
  for (Eigen::Index k = 0; k < src.cols(); ++k) {
    const Eigen::Vector3d s = src.col(k) - mu_s, d = dst.col(k) - mu_d;
    a += s.x() * d.y() - s.y() * d.x();
    b += s.x() * d.x() + s.y() * d.y();
  }
  Similarity out;
  out.R = Eigen::AngleAxisd(std::atan2(a, b), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out.t = mu_d - out.R * mu_s;
  return out;
}

ErrorStats computeStats(const std::vector<double>& e) {
  ErrorStats s;
  s.n = e.size();
  if (e.empty()) return s;
  const double n = static_cast<double>(e.size());
  for (double v : e) s.sse += v * v;
  s.mean = std::accumulate(e.begin(), e.end(), 0.0) / n;
  s.rmse = std::sqrt(s.sse / n);
  double var = 0;
  for (double v : e) var += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted = e;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  const std::size_t m = sorted.size() / 2;
  s.median = sorted.size() % 2 ? sorted[m] : 0.5 * (sorted[m - 1] + sorted[m]);
  return s;
}

AteResult computeAte(const std::vector<StampedPose>& ref, const std::vector<StampedPose>& est, AlignMode align,
                     TimeNs max_dt_ns) {
  AteResult r;
  r.pairs = associate(ref, est, max_dt_ns);
  if (r.pairs.empty()) throw std::invalid_argument("no matching time stamps between reference and estimate");
  const auto n = static_cast<Eigen::Index>(r.pairs.size());
  Eigen::Matrix3Xd P(3, n), Q(3, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Q.col(k) = ref[r.pairs[k].first].p_w_b;
    P.col(k) = est[r.pairs[k].second].p_w_b;
  }
  switch (align) {
    case AlignMode::kSe3:
      r.alignment = umeyama(P, Q, false);
      break;
    case AlignMode::kSim3:
      r.alignment = umeyama(P, Q, true);
      break;
    case AlignMode::kPosYaw:
      r.alignment = alignPositionYaw(P, Q);
      break;
    case AlignMode::kNone:
      break;
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    r.errors.push_back((r.alignment.apply(P.col(k)) - Q.col(k)).norm());
    r.stamps.push_back(ref[r.pairs[k].first].t_ns);
  }
  r.stats = computeStats(r.errors);
  return r;
}

ErrorStats computeRpe(const std::vector<StampedPose>& ref, const std::vector<StampedPose>& est, double delta_m) {
  if (ref.size() != est.size()) throw std::invalid_argument("RPE: trajectories must be associated");
  // Consecutive pairs by path length on the estimate (evo's filter_pairs_by_path).
  std::vector<std::size_t> ids;
  double path = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    if (i > 0) path += (est[i].p_w_b - est[i - 1].p_w_b).norm();
    if (path >= delta_m) {
      ids.push_back(i);
      path = 0;
    }
  }
  std::vector<double> errors;
  const auto pose = [](const StampedPose& p) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = p.q_w_b.toRotationMatrix();
    T.translation() = p.p_w_b;
    return T;
  };
  for (std::size_t k = 1; k < ids.size(); ++k) {
    const std::size_t i = ids[k - 1], j = ids[k];
    const Eigen::Isometry3d Q_rel = pose(ref[i]).inverse() * pose(ref[j]);
    const Eigen::Isometry3d P_rel = pose(est[i]).inverse() * pose(est[j]);
    errors.push_back((Q_rel.inverse() * P_rel).translation().norm());
  }
  return computeStats(errors);
}

double pathLength(const std::vector<StampedPose>& poses) {
  double len = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) len += (poses[i].p_w_b - poses[i - 1].p_w_b).norm();
  return len;
}

}  // namespace idyvins::eval
