#include "backend/mono_init.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Dense>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "backend/feature_manager.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

/// The SfM's state while it is built: camera poses (known or not) and track points.
struct Sfm {
  const std::vector<MonoTrack>& tracks;
  std::vector<std::optional<Isometry3d>> T_w_c;
  std::vector<std::optional<Vector3d>> p_w;

  const Vector2d* obs(std::size_t k, int frame) const {
    const MonoTrack& t = tracks[k];
    const int i = frame - t.start_frame;
    return i >= 0 && i < static_cast<int>(t.xy.size()) ? &t.xy[static_cast<std::size_t>(i)] : nullptr;
  }
  /// The tracks seen in both frames without a point yet, triangulated in front of both.
  void triangulate(int a, int b) {
    for (std::size_t k = 0; k < tracks.size(); ++k) {
      const Vector2d *xa = obs(k, a), *xb = obs(k, b);
      if (p_w[k] || !xa || !xb) continue;
      const Vector3d p = triangulateTwoViews(*T_w_c[a], *xa, *T_w_c[b], *xb);
      if ((T_w_c[a]->inverse() * p).z() > 0 && (T_w_c[b]->inverse() * p).z() > 0 && p.allFinite()) p_w[k] = p;
    }
  }
  /// Frame `frame`'s pose by PnP against the points, from the guess; false when too few.
  bool pnp(int frame, const Isometry3d& guess, int min_points) {
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;
    for (std::size_t k = 0; k < tracks.size(); ++k)
      if (const Vector2d* x = obs(k, frame); x && p_w[k]) {
        obj.emplace_back(p_w[k]->x(), p_w[k]->y(), p_w[k]->z());
        img.emplace_back(x->x(), x->y());
      }
    if (static_cast<int>(obj.size()) < min_points) return false;
    const Isometry3d T_c_w = guess.inverse();
    cv::Mat R_cv, rvec, tvec;
    cv::eigen2cv(Matrix3d(T_c_w.linear()), R_cv);
    cv::Rodrigues(R_cv, rvec);
    cv::eigen2cv(Vector3d(T_c_w.translation()), tvec);
    if (!cv::solvePnP(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, true)) return false;
    cv::Rodrigues(rvec, R_cv);
    Matrix3d R;
    Vector3d t;
    cv::cv2eigen(R_cv, R);
    cv::cv2eigen(tvec, t);
    Isometry3d T = Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t;
    if (!T.matrix().allFinite()) return false;
    T_w_c[frame] = T.inverse();
    return true;
  }
};

/// Normalized-plane reprojection error of a world point in a camera (q_c_w, t_c_w).
struct ReprojectionError {
  Vector2d xy;
  template <typename T>
  bool operator()(const T* q, const T* t, const T* p, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_c_w(q);
    const Eigen::Matrix<T, 3, 1> p_c =
        q_c_w * Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p) + Eigen::Map<const Eigen::Matrix<T, 3, 1>>(t);
    r[0] = p_c.x() / p_c.z() - T(xy.x());
    r[1] = p_c.y() / p_c.z() - T(xy.y());
    return true;
  }
};

/// The relative rotation of two cameras (q_c_w each) against the gyroscope's, per axis, in
/// the reprojection errors' unit (normalized plane, 1 px ~ 1 / focal): · 1 / (focal σ).
struct RelativeRotationError {
  Eigen::Quaterniond q_prev_c;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* qa, const T* qb, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_a_w(qa), q_b_w(qb);
    const Eigen::Quaternion<T> e = q_prev_c.cast<T>().conjugate() * (q_a_w * q_b_w.conjugate());
    const T s = e.w() < T(0) ? T(-2.0 * inv_sigma) : T(2.0 * inv_sigma);
    r[0] = s * e.x();
    r[1] = s * e.y();
    r[2] = s * e.z();
    return true;
  }
};

/// The gyroscope's frame-to-frame rotations as residuals between the cameras q (q_c_w).
void addRotationPrior(ceres::Problem& problem, std::vector<Eigen::Quaterniond>& q, const MonoRotationPrior& prior,
                      double focal_px) {
  for (std::size_t i = 1; i < q.size(); ++i)
    if (problem.HasParameterBlock(q[i - 1].coeffs().data()) && problem.HasParameterBlock(q[i].coeffs().data()))
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RelativeRotationError, 3, 4, 4>(
                                   new RelativeRotationError{prior.q_prev_c[i], 1.0 / (focal_px * prior.sigma_rad)}),
                               nullptr, q[i - 1].coeffs().data(), q[i].coeffs().data());
}

/// Bundle adjustment of every pose and point; the reference pose and the newest camera's
/// translation held (the gauge and the unit scale); with a prior, consecutive rotations held
/// to the gyroscope's. Returns the RMS error (px).
double bundleAdjust(Sfm& s, int reference, double focal_px, const MonoRotationPrior* prior) {
  const int frames = static_cast<int>(s.T_w_c.size());
  std::vector<Eigen::Quaterniond> q(static_cast<std::size_t>(frames));
  std::vector<Vector3d> t(static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    const Isometry3d T_c_w = s.T_w_c[i]->inverse();
    q[i] = Eigen::Quaterniond(T_c_w.linear()).normalized();
    t[i] = T_c_w.translation();
  }
  ceres::EigenQuaternionManifold quaternion;  // outlives the problem, which does not own it
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  int residuals = 0;
  for (std::size_t k = 0; k < s.tracks.size(); ++k) {
    if (!s.p_w[k]) continue;
    for (std::size_t j = 0; j < s.tracks[k].xy.size(); ++j) {
      const int i = s.tracks[k].start_frame + static_cast<int>(j);
      auto* cost =
          new ceres::AutoDiffCostFunction<ReprojectionError, 2, 4, 3, 3>(new ReprojectionError{s.tracks[k].xy[j]});
      problem.AddResidualBlock(cost, new ceres::HuberLoss(1.0 / focal_px), q[i].coeffs().data(), t[i].data(),
                               s.p_w[k]->data());
      ++residuals;
    }
  }
  if (prior) addRotationPrior(problem, q, *prior, focal_px);
  for (int i = 0; i < frames; ++i)
    if (problem.HasParameterBlock(q[i].coeffs().data())) problem.SetManifold(q[i].coeffs().data(), &quaternion);
  const int newest = frames - 1;
  if (problem.HasParameterBlock(q[reference].coeffs().data())) {
    problem.SetParameterBlockConstant(q[reference].coeffs().data());
    problem.SetParameterBlockConstant(t[reference].data());
  }
  if (problem.HasParameterBlock(t[newest].data())) problem.SetParameterBlockConstant(t[newest].data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 20;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (int i = 0; i < frames; ++i) {
    Isometry3d T_c_w = Isometry3d::Identity();
    T_c_w.linear() = q[i].normalized().toRotationMatrix();
    T_c_w.translation() = t[i];
    s.T_w_c[i] = T_c_w.inverse();
  }
  double sum = 0;
  for (std::size_t k = 0; k < s.tracks.size(); ++k) {
    if (!s.p_w[k]) continue;
    for (std::size_t j = 0; j < s.tracks[k].xy.size(); ++j) {
      const Vector3d p_c = s.T_w_c[s.tracks[k].start_frame + static_cast<int>(j)]->inverse() * *s.p_w[k];
      sum += (p_c.head<2>() / p_c.z() - s.tracks[k].xy[j]).squaredNorm();
    }
  }
  return residuals > 0 ? focal_px * std::sqrt(sum / residuals) : 0.0;
}

/// The relative pose of frame `a` to the newest from the essential matrix: T_w_c of the newest
/// with the world at `a`, |t| = 1; nullopt with too few inliers.
std::optional<Isometry3d> relativePose(const Sfm& s, int a, int newest, double focal_px, const MonoSfmOptions& o) {
  std::vector<cv::Point2d> pa, pb;
  double parallax = 0;
  for (std::size_t k = 0; k < s.tracks.size(); ++k)
    if (const Vector2d* xa = s.obs(k, a), *xb = s.obs(k, newest); xa && xb) {
      pa.emplace_back(xa->x(), xa->y());
      pb.emplace_back(xb->x(), xb->y());
      parallax += (*xa - *xb).norm();
    }
  if (static_cast<int>(pa.size()) < o.min_pair_tracks || parallax / pa.size() * focal_px < o.min_parallax_px)
    return std::nullopt;
  cv::Mat mask;
  const cv::Mat E =
      cv::findEssentialMat(pa, pb, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.99, o.ransac_px / focal_px, mask);
  if (E.rows != 3 || E.cols != 3) return std::nullopt;
  cv::Mat R_cv, t_cv;
  const int inliers = cv::recoverPose(E, pa, pb, R_cv, t_cv, 1.0, cv::Point2d(0, 0), mask);
  if (inliers < o.min_pair_inliers) return std::nullopt;
  Matrix3d R;
  Vector3d t;
  cv::cv2eigen(R_cv, R);
  cv::cv2eigen(t_cv, t);
  Isometry3d T_b_a = Isometry3d::Identity();  // points of camera a into the newest camera
  T_b_a.linear() = R;
  T_b_a.translation() = t.normalized();
  return T_b_a.inverse();
}

}  // namespace

std::optional<MonoStructure> monocularStructure(const std::vector<MonoTrack>& tracks, int frames, double focal_px,
                                                const MonoSfmOptions& o, std::string& why,
                                                const MonoRotationPrior* prior) {
  const int newest = frames - 1;
  Sfm s{tracks, std::vector<std::optional<Isometry3d>>(static_cast<std::size_t>(frames)),
        std::vector<std::optional<Vector3d>>(tracks.size())};
  int l = 0;
  std::optional<Isometry3d> T_w_cn;
  for (; l < newest && !T_w_cn; ++l) T_w_cn = relativePose(s, l, newest, focal_px, o);
  if (!T_w_cn) {
    why = "no frame with " + std::to_string(static_cast<int>(o.min_parallax_px)) + " px of parallax to the newest";
    return std::nullopt;
  }
  --l;
  s.T_w_c[l] = Isometry3d::Identity();
  s.T_w_c[newest] = *T_w_cn;
  s.triangulate(l, newest);
  for (int i = l + 1; i < newest; ++i) {
    if (!s.pnp(i, *s.T_w_c[i - 1], o.min_pnp_points)) {
      why = "PnP of frame " + std::to_string(i) + " failed";
      return std::nullopt;
    }
    s.triangulate(i, newest);
  }
  for (int i = l + 1; i < newest; ++i) s.triangulate(l, i);
  for (int i = l - 1; i >= 0; --i) {
    if (!s.pnp(i, *s.T_w_c[i + 1], o.min_pnp_points)) {
      why = "PnP of frame " + std::to_string(i) + " failed";
      return std::nullopt;
    }
    s.triangulate(i, l);
  }
  for (std::size_t k = 0; k < tracks.size(); ++k)
    if (tracks[k].xy.size() >= 2) {
      const int a = tracks[k].start_frame, b = a + static_cast<int>(tracks[k].xy.size()) - 1;
      s.triangulate(a, b);
    }
  MonoStructure out;
  out.reference = l;
  out.rms_px = bundleAdjust(s, l, focal_px, prior && prior->sigma_rad > 0 ? prior : nullptr);
  for (const auto& p : s.p_w) out.points += p ? 1 : 0;
  for (const auto& T : s.T_w_c) out.T_w_c.push_back(*T);
  if (!(out.rms_px <= o.max_rms_px)) {
    why = "bundle adjustment left " + std::to_string(out.rms_px) + " px";
    return std::nullopt;
  }
  return out;
}

namespace {

/// The linear alignment's solution x = [v_0 … v_{n−1}, w, s] with gravity g = g0 + G w (G: 3×k);
/// `s_sigma`, when given: the standard deviation of s from the residuals' spread.
Eigen::VectorXd solveScaled(const std::vector<Eigen::Quaterniond>& q, const std::vector<Vector3d>& a,
                            const Vector3d& t_b_c, const std::vector<const imu::Preintegration*>& pre,
                            const Vector3d& g0, const Eigen::MatrixXd& G, double* s_sigma = nullptr) {
  const int n = static_cast<int>(q.size()), k = static_cast<int>(G.cols());
  const int d = 3 * n + k + 1;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(d, d);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(d);
  double zz = 0;
  for (int j = 1; j < n; ++j) {
    const int i = j - 1;
    const double dt = pre[j]->sumDt();
    const Matrix3d Ri = q[i].toRotationMatrix(), Rj = q[j].toRotationMatrix(), Ri_T = Ri.transpose();
    // α = Ri_T (s (aj − ai) − (Rj − Ri) t_b_c − vi dt + ½ g dt²);  β = Ri_T (vj − vi + g dt).
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6, d);
    Eigen::VectorXd z(6);
    H.block(0, 3 * i, 3, 3) = -Ri_T * dt;
    H.block(3, 3 * i, 3, 3) = -Ri_T;
    H.block(3, 3 * j, 3, 3) = Ri_T;
    H.block(0, 3 * n, 3, k) = 0.5 * Ri_T * G * dt * dt;
    H.block(3, 3 * n, 3, k) = Ri_T * G * dt;
    H.block(0, d - 1, 3, 1) = Ri_T * (a[j] - a[i]);
    z.head<3>() = pre[j]->deltaP() + Ri_T * (Rj - Ri) * t_b_c - 0.5 * Ri_T * g0 * dt * dt;
    z.tail<3>() = pre[j]->deltaV() - Ri_T * g0 * dt;
    A += H.transpose() * H;
    b += H.transpose() * z;
    zz += z.squaredNorm();
  }
  const Eigen::VectorXd x = A.ldlt().solve(b);
  if (s_sigma) {
    // Σ‖z − H x‖² = zᵀz − 2 xᵀb + xᵀA x, over the rows left after the unknowns.
    const double rows = 6.0 * (n - 1), sse = std::max(0.0, zz - 2.0 * x.dot(b) + x.dot(A * x));
    const Eigen::MatrixXd cov = A.inverse() * (sse / std::max(1.0, rows - d));
    *s_sigma = std::sqrt(std::max(0.0, cov(d - 1, d - 1)));
  }
  return x;
}

}  // namespace

ScaledAlignment alignWithScale(const std::vector<Eigen::Quaterniond>& q, const std::vector<Vector3d>& p_w_c,
                               const Vector3d& t_b_c, const std::vector<const imu::Preintegration*>& pre,
                               double g_norm) {
  ScaledAlignment out;
  const int n = static_cast<int>(q.size());
  if (n < 3 || p_w_c.size() != q.size() || pre.size() != q.size()) return out;
  Eigen::VectorXd x = solveScaled(q, p_w_c, t_b_c, pre, Vector3d::Zero(), Matrix3d::Identity());
  Vector3d g = x.segment<3>(3 * n);
  out.g_norm_estimated = g.norm();
  if (!(std::abs(g.norm() - g_norm) < 0.1 * g_norm) || !(x(x.size() - 1) > 0)) return out;
  // Gravity on its sphere: two tangent directions per step (VINS-Mono's RefineGravity).
  g = g.normalized() * g_norm;
  for (int it = 0; it < 4; ++it) {
    const Vector3d u = g.normalized();
    const Vector3d ref = std::abs(u.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
    Eigen::Matrix<double, 3, 2> B;
    B.col(0) = (ref - u * u.dot(ref)).normalized();
    B.col(1) = u.cross(B.col(0));
    x = solveScaled(q, p_w_c, t_b_c, pre, g, B, &out.scale_sigma);
    g = (g + B * x.segment<2>(3 * n)).normalized() * g_norm;
  }
  out.scale = x(x.size() - 1);
  out.scale_sigma /= std::max(out.scale, 1e-12);
  out.g_w = g;
  for (int i = 0; i < n; ++i) out.v_w.push_back(x.segment<3>(3 * i));
  out.ok = out.scale > 0 && x.allFinite();
  return out;
}

}  // namespace idyvins::backend
