#include "backend/feature_manager.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <cmath>

#include "core/so3.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
constexpr double kMinDepth = 0.1, kMaxDepth = 80.0;
constexpr double kReanchorHuberPx = 1.5;  ///< px, Huber threshold of a re-anchored landmark's multi-view triangulation

/// One Gauss-Newton step of triangulateViews (errors above `huber` down-weighted, 0: none);
/// false when a view sees the point behind it.
bool refineStep(const std::vector<Isometry3d>& T_w_c, const std::vector<Vector2d>& xy, double huber, Vector3d& p_w) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Vector3d g = Vector3d::Zero();
  for (std::size_t k = 0; k < T_w_c.size(); ++k) {
    const Vector3d p = T_w_c[k].inverse() * p_w;
    if (p.z() < kMinDepth) return false;
    Eigen::Matrix<double, 2, 3> d_proj;
    d_proj << 1.0 / p.z(), 0, -p.x() / (p.z() * p.z()), 0, 1.0 / p.z(), -p.y() / (p.z() * p.z());
    const Eigen::Matrix<double, 2, 3> J = d_proj * T_w_c[k].linear().transpose();
    const Vector2d r = p.head<2>() / p.z() - xy[k];
    const double w = huber > 0 && r.norm() > huber ? huber / r.norm() : 1.0;
    H += w * J.transpose() * J;
    g += w * J.transpose() * r;
  }
  const Vector3d step = H.ldlt().solve(-g);
  if (!step.allFinite()) return false;
  p_w += step;
  return true;
}

/// triangulateViews over every observation of a landmark in the window, left and right.
std::optional<Vector3d> triangulateWindow(const Landmark& lm, const std::vector<Isometry3d>& T_w_b, const Rig& rig,
                                          const Vector3d& start) {
  std::vector<Isometry3d> T_w_c;
  std::vector<Vector2d> xy;
  for (std::size_t k = 0; k < lm.obs.size() && lm.start_frame + k < T_w_b.size(); ++k) {
    const Isometry3d& T = T_w_b[lm.start_frame + k];
    T_w_c.push_back(cameraPose(T, rig.T_b_c0));
    xy.push_back(lm.obs[k].xy);
    if (!rig.stereo || !lm.obs[k].has_right) continue;
    T_w_c.push_back(cameraPose(T, rig.T_b_c1));
    xy.push_back(lm.obs[k].xy_right);
  }
  return triangulateViews(T_w_c, xy, start, kReanchorHuberPx / rig.focal_px);
}
}  // namespace

std::optional<Vector3d> triangulateViews(const std::vector<Isometry3d>& T_w_c, const std::vector<Vector2d>& xy,
                                         const std::optional<Vector3d>& start, double huber) {
  if (T_w_c.size() < 2 || T_w_c.size() != xy.size()) return std::nullopt;
  // Linear: each view says hat(x) R_c_w (p_w - t_w_c) = 0.
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  for (std::size_t k = 0; k < T_w_c.size(); ++k) {
    const Eigen::Matrix3d M = hat(Vector3d(xy[k].x(), xy[k].y(), 1.0)) * T_w_c[k].linear().transpose();
    A += M.transpose() * M;
    b += M.transpose() * (M * T_w_c[k].translation());
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-12) return std::nullopt;
  Vector3d p_w = start ? *start : Vector3d(ldlt.solve(b));
  for (int iteration = 0; iteration < 5; ++iteration) {
    const Vector3d before = p_w;
    if (!p_w.allFinite() || !refineStep(T_w_c, xy, huber, p_w)) return std::nullopt;
    if ((p_w - before).norm() < 1e-9 * p_w.norm()) break;
  }
  return p_w;
}

Isometry3d cameraPose(const Isometry3d& T_w_b, const Extrinsic& e) {
  Isometry3d T_b_c = Isometry3d::Identity();
  T_b_c.linear() = e.q_b_c.toRotationMatrix();
  T_b_c.translation() = e.t_b_c;
  return T_w_b * T_b_c;
}

Vector3d triangulateTwoViews(const Isometry3d& T_w_c0, const Vector2d& xy0, const Isometry3d& T_w_c1,
                             const Vector2d& xy1) {
  const Eigen::Matrix<double, 3, 4> P0 = T_w_c0.inverse().matrix().topRows<3>();
  const Eigen::Matrix<double, 3, 4> P1 = T_w_c1.inverse().matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = xy0.x() * P0.row(2) - P0.row(0);
  A.row(1) = xy0.y() * P0.row(2) - P0.row(1);
  A.row(2) = xy1.x() * P1.row(2) - P1.row(0);
  A.row(3) = xy1.y() * P1.row(2) - P1.row(1);
  const Eigen::Vector4d X = Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
  return X.head<3>() / X(3);
}

bool FeatureManager::addFrame(int frame, const frontend::FeatureFrame& ff, double keyframe_parallax_px, double focal_px,
                              const std::set<std::uint64_t>& excluded) {
  int tracked = 0, new_features = 0, long_tracks = 0;
  for (const auto& f : ff.features) {
    if (excluded.count(f.id)) continue;
    Observation o;
    o.xy = f.xy;
    o.uv = f.uv;
    o.has_right = f.hasAnyRight();  // the estimator uses both kinds of right match
    o.xy_right = f.xy_right;
    o.velocity = f.velocity_xy;
    o.velocity_right = f.velocity_xy_right;
    o.td_s = ff.td_s;
    auto it = landmarks_.find(f.id);
    if (it == landmarks_.end() || it->second.endFrame() != frame - 1) {
      if (it != landmarks_.end()) landmarks_.erase(it);  // a gap: start over
      Landmark lm;
      lm.id = f.id;
      lm.start_frame = frame;
      lm.obs.push_back(o);
      lm.label = f.label;
      lm.candidate_obs = f.label == FeatureLabel::kCandidate ? 1 : 0;
      landmarks_.emplace(f.id, lm);
      ++new_features;
    } else {
      Landmark& lm = it->second;
      lm.obs.push_back(o);
      if (f.label == FeatureLabel::kCandidate && lm.label != FeatureLabel::kCandidate) {
        lm.label = f.label;  // sticky until post-processing decides
        lm.candidate_obs = 0;
      }
      if (lm.label == FeatureLabel::kCandidate) ++lm.candidate_obs;
      ++tracked;
      if (lm.obs.size() >= 4) ++long_tracks;
    }
  }
  if (frame < 2 || tracked < 20 || long_tracks < 40 || new_features > 0.5 * tracked) return true;
  // Mean parallax between frames frame-2 and frame-1 of landmarks seen in both (and now).
  double sum = 0;
  int n = 0;
  for (const auto& [id, lm] : landmarks_) {
    if (lm.start_frame <= frame - 2 && lm.endFrame() >= frame - 1) {
      const Vector2d& a = lm.obs[frame - 2 - lm.start_frame].xy;
      const Vector2d& b = lm.obs[frame - 1 - lm.start_frame].xy;
      sum += (a - b).norm();
      ++n;
    }
  }
  if (n == 0) return true;
  return sum / n * focal_px >= keyframe_parallax_px;
}

void FeatureManager::triangulate(const std::vector<Isometry3d>& T_w_b, const Rig& rig) {
  for (auto& [id, lm] : landmarks_) {
    if (lm.inv_depth > 0) continue;
    const Isometry3d T_w_c = cameraPose(T_w_b[lm.start_frame], rig.T_b_c0);
    Vector3d p_w;
    bool ok = false;
    const Observation& o0 = lm.obs.front();
    if (rig.stereo && o0.has_right) {
      p_w = triangulateTwoViews(T_w_c, o0.xy, cameraPose(T_w_b[lm.start_frame], rig.T_b_c1), o0.xy_right);
      ok = true;
    } else if (lm.obs.size() >= 2) {
      const int j = lm.endFrame();
      const Isometry3d T_w_cj = cameraPose(T_w_b[j], rig.T_b_c0);
      if ((T_w_cj.translation() - T_w_c.translation()).norm() > 0.05) {
        p_w = triangulateTwoViews(T_w_c, o0.xy, T_w_cj, lm.obs.back().xy);
        ok = true;
      }
    }
    if (!ok) continue;
    const double z = (T_w_c.inverse() * p_w).z();
    if (z > kMinDepth && z < kMaxDepth) lm.inv_depth = 1.0 / z;
  }
}

void FeatureManager::removeOldest(const std::vector<Isometry3d>& T_w_b, const Rig& rig, bool retriangulate,
                                  bool ray_estimates) {
  const Isometry3d T_w_c0 = cameraPose(T_w_b.at(0), rig.T_b_c0), T_w_c1 = cameraPose(T_w_b.at(1), rig.T_b_c0);
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    Landmark& lm = it->second;
    if (lm.start_frame != 0) {
      --lm.start_frame;
      ++it;
      continue;
    }
    if (!lm.livesOnReanchored()) {
      it = landmarks_.erase(it);
      continue;
    }
    if (lm.inv_depth > 0) {
      const Vector3d p_c0 = lm.anchorPoint();
      Vector3d p_c1 = T_w_c1.inverse() * (T_w_c0 * p_c0);
      if (retriangulate) {
        const std::optional<Vector3d> p_w = triangulateWindow(lm, T_w_b, rig, T_w_c0 * p_c0);
        const Vector3d p = p_w ? Vector3d(T_w_c1.inverse() * *p_w) : Vector3d::Zero();
        if (p.z() > kMinDepth && p.z() < kMaxDepth) {
          p_c1 = p;
          lm.obs[1].xy = p.head<2>() / p.z();  // the new anchor ray: the estimate, not the measurement
        }
      }
      lm.inv_depth = p_c1.z() > kMinDepth ? 1.0 / p_c1.z() : -1.0;
      lm.ray_estimated = ray_estimates && lm.inv_depth > 0;
      if (lm.ray_estimated) lm.ray_xy = p_c1.head<2>() / p_c1.z();
    } else {
      lm.ray_estimated = false;
    }
    lm.obs.erase(lm.obs.begin());
    ++it;
  }
}

void FeatureManager::removeFrame(int frame) {
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    Landmark& lm = it->second;
    if (lm.start_frame == frame) {
      // Anchored in the dropped frame: keep it only if the newest frame continues it.
      if (lm.obs.size() < 2) {
        it = landmarks_.erase(it);
        continue;
      }
      lm.obs.erase(lm.obs.begin());  // the newest frame (index frame + 1) becomes index frame
      lm.inv_depth = -1.0;           // re-triangulate in the new anchor
      lm.ray_estimated = false;
    } else if (lm.start_frame < frame && lm.endFrame() >= frame) {
      lm.obs.erase(lm.obs.begin() + (frame - lm.start_frame));
    } else if (lm.start_frame > frame) {
      --lm.start_frame;
    }
    ++it;
  }
}

void FeatureManager::remove(const std::vector<std::uint64_t>& ids) {
  for (auto id : ids) landmarks_.erase(id);
}

void FeatureManager::removeFailures() {
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    if (it->second.inv_depth > 0 && (it->second.inv_depth < 1.0 / kMaxDepth || it->second.inv_depth > 1.0 / kMinDepth))
      it = landmarks_.erase(it);
    else
      ++it;
  }
}

int FeatureManager::trackedIn(int frame) const {
  int n = 0;
  for (const auto& [id, lm] : landmarks_)
    if (lm.usable() && lm.start_frame <= frame && lm.endFrame() >= frame) ++n;
  return n;
}

}  // namespace idyvins::backend
