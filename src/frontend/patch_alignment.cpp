#include "frontend/patch_alignment.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace idyvins::frontend {

cv::Mat matchBrightness(const cv::Mat& image, const cv::Mat& reference, double tolerance) {
  cv::Scalar mean_i, std_i, mean_r, std_r;
  cv::meanStdDev(image, mean_i, std_i);
  cv::meanStdDev(reference, mean_r, std_r);
  if (std_i[0] < 1e-6 || mean_r[0] < 1e-6) return image;  // flat image: nothing to match
  const double a = std_r[0] / std_i[0], b = mean_r[0] - a * mean_i[0];
  if (std::abs(a - 1.0) <= tolerance && std::abs(mean_i[0] / mean_r[0] - 1.0) <= tolerance) return image;
  cv::Mat out;
  image.convertTo(out, CV_8U, a, b);
  return out;
}

namespace {

/// Bilinear intensity of a CV_8UC1 image; false when (u, v) has no 2x2 neighbourhood.
inline bool sample(const cv::Mat& image, double u, double v, float& out) {
  if (!(u >= 0.0 && v >= 0.0 && u < image.cols - 1 && v < image.rows - 1)) return false;
  const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
  const float ax = static_cast<float>(u - x0), ay = static_cast<float>(v - y0);
  const uchar* r0 = image.ptr<uchar>(y0) + x0;
  const uchar* r1 = image.ptr<uchar>(y0 + 1) + x0;
  out = (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
  return true;
}

/// Zero mean, unit norm in place; false when the patch is (almost) flat.
bool normalize(std::vector<float>& v) {
  double mean = 0;
  for (float x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0;
  for (float& x : v) {
    x = static_cast<float>(x - mean);
    ss += static_cast<double>(x) * x;
  }
  // Below ~1 gray level of standard deviation there is nothing to align.
  if (ss < static_cast<double>(v.size())) return false;
  const float s = static_cast<float>(1.0 / std::sqrt(ss));
  for (float& x : v) x *= s;
  return true;
}

}  // namespace

namespace {

/// ZNCC from the sums over `count` pixel pairs; -1 when either side is (almost) flat.
double znccFromSums(double sa, double sb, double saa, double sbb, double sab, int count) {
  const double va = saa - sa * sa / count, vb = sbb - sb * sb / count;
  // Below ~1 gray level of standard deviation there is nothing to correlate (as normalize()).
  if (va < count || vb < count) return -1.0;
  return (sab - sa * sb / count) / std::sqrt(va * vb);
}

/// patchZncc over the offsets at which both points lie in their images (bilinear).
double patchZnccAtBorder(const cv::Mat& a, const Eigen::Vector2d& uv_a, const cv::Mat& b, const Eigen::Vector2d& uv_b,
                         int half, double min_inside) {
  const int n = 2 * half + 1;
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int count = 0;
  for (int dy = -half; dy <= half; ++dy)
    for (int dx = -half; dx <= half; ++dx) {
      float xa, xb;
      if (!sample(a, uv_a.x() + dx, uv_a.y() + dy, xa) || !sample(b, uv_b.x() + dx, uv_b.y() + dy, xb)) continue;
      sa += xa;
      sb += xb;
      saa += static_cast<double>(xa) * xa;
      sbb += static_cast<double>(xb) * xb;
      sab += static_cast<double>(xa) * xb;
      ++count;
    }
  if (count < min_inside * n * n) return -1.0;
  return znccFromSums(sa, sb, saa, sbb, sab, count);
}

}  // namespace

double patchZncc(const cv::Mat& a, const Eigen::Vector2d& uv_a, const cv::Mat& b, const Eigen::Vector2d& uv_b, int half,
                 double min_inside) {
  const auto inside = [half](const cv::Mat& m, const Eigen::Vector2d& uv) {
    return uv.x() - half >= 0.0 && uv.y() - half >= 0.0 && uv.x() + half < m.cols - 1 && uv.y() + half < m.rows - 1;
  };
  if (!inside(a, uv_a) || !inside(b, uv_b))
    return min_inside < 1.0 ? patchZnccAtBorder(a, uv_a, b, uv_b, half, min_inside) : -1.0;
  const int n = 2 * half + 1;
  cv::Mat pa, pb;  // bilinear patches centred on the points (OpenCV's vectorized resampling)
  cv::getRectSubPix(a, cv::Size(n, n), cv::Point2f(static_cast<float>(uv_a.x()), static_cast<float>(uv_a.y())), pa,
                    CV_32F);
  cv::getRectSubPix(b, cv::Size(n, n), cv::Point2f(static_cast<float>(uv_b.x()), static_cast<float>(uv_b.y())), pb,
                    CV_32F);
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const float* xa = pa.ptr<float>();
  const float* xb = pb.ptr<float>();
  const int count = n * n;
  for (int k = 0; k < count; ++k) {
    sa += xa[k];
    sb += xb[k];
    saa += static_cast<double>(xa[k]) * xa[k];
    sbb += static_cast<double>(xb[k]) * xb[k];
    sab += static_cast<double>(xa[k]) * xb[k];
  }
  return znccFromSums(sa, sb, saa, sbb, sab, count);
}

namespace {

/// Whether an LDLT factorization of a Gauss-Newton Hessian is usable (texture in both directions).
bool wellConditioned(const Eigen::LDLT<Eigen::Matrix<double, 6, 6>>& ldlt) {
  return ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 1e-9 * ldlt.vectorD().maxCoeff();
}

}  // namespace

namespace {

/// The template's steepest-descent images (6 per kept pixel, affine warp, gradients of the
/// (2 half + 3)² samples `big` scaled by `scale`) into `sd`; returns their Gauss-Newton Hessian.
Eigen::Matrix<double, 6, 6> steepestDescent(const std::vector<float>& big, const std::vector<unsigned char>& inside,
                                            int half, double scale, std::vector<float>& sd) {
  const int n = 2 * half + 1, m = n + 2;
  sd.assign(6 * static_cast<std::size_t>(n) * n, 0.f);
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      if (!inside[r * n + c]) continue;
      const double gx = 0.5 * scale * (big[(r + 1) * m + c + 2] - big[(r + 1) * m + c]);
      const double gy = 0.5 * scale * (big[(r + 2) * m + c + 1] - big[r * m + c + 1]);
      const double x = c - half, y = r - half;
      Eigen::Matrix<double, 6, 1> s;
      s << gx * x, gx * y, gy * x, gy * y, gx, gy;
      H.noalias() += s * s.transpose();
      for (int k = 0; k < 6; ++k) sd[6 * (r * n + c) + k] = static_cast<float>(s[k]);
    }
  return H;
}

}  // namespace

PatchTemplate makePatchTemplate(const cv::Mat& image, const Eigen::Vector2d& uv_center, int half, double min_inside) {
  PatchTemplate tmpl;
  tmpl.half = half;
  const int n = 2 * half + 1, m = n + 2;  // with a 1 px margin for the gradients
  std::vector<float> big(static_cast<std::size_t>(m) * m);
  std::vector<unsigned char> got(big.size(), 1);
  bool whole = true;
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c)
      if (!sample(image, uv_center.x() + c - half - 1, uv_center.y() + r - half - 1, big[r * m + c])) {
        got[r * m + c] = 0;
        whole = false;
      }
  // A pixel is kept when its value and the four neighbours of its gradient are in the image.
  const std::size_t count = static_cast<std::size_t>(n) * n;
  std::vector<unsigned char> inside(count, 1);
  std::size_t kept = count;
  if (!whole) {
    kept = 0;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const int k = (r + 1) * m + c + 1;
        inside[r * n + c] = got[k] && got[k - 1] && got[k + 1] && got[k - m] && got[k + m];
        kept += inside[r * n + c];
      }
    if (min_inside >= 1.0 || kept < min_inside * count) return tmpl;
    tmpl.inside = inside;
    tmpl.min_inside = min_inside;
  }
  tmpl.values.assign(count, 0.f);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      if (inside[r * n + c]) tmpl.values[r * n + c] = big[(r + 1) * m + c + 1];
  // Zero mean and unit norm over the pixels kept; the normalization is affine in the
  // intensities: the same scale applies to the gradients.
  double mean = 0, ss = 0;
  for (std::size_t k = 0; k < count; ++k) mean += tmpl.values[k];
  mean /= static_cast<double>(kept);
  for (std::size_t k = 0; k < count; ++k)
    if (inside[k]) ss += (tmpl.values[k] - mean) * (tmpl.values[k] - mean);
  if (whole) {
    if (!normalize(tmpl.values)) return tmpl;
  } else {
    // Below ~1 gray level of standard deviation there is nothing to align (as normalize()).
    if (ss < static_cast<double>(kept)) return tmpl;
    for (std::size_t k = 0; k < count; ++k)
      tmpl.values[k] = inside[k] ? static_cast<float>((tmpl.values[k] - mean) / std::sqrt(ss)) : 0.f;
  }
  const double scale = 1.0 / std::sqrt(ss);
  const Eigen::Matrix<double, 6, 6> H = steepestDescent(big, inside, half, scale, tmpl.sd);
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
  if (!wellConditioned(ldlt)) return tmpl;
  tmpl.H_inv = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  tmpl.H_translation_inv = H.bottomRightCorner<2, 2>().inverse();
  tmpl.valid = true;
  return tmpl;
}

namespace {

/// Singular values of a 2x2 matrix, largest first (closed form).
Eigen::Vector2d singularValues2(const Eigen::Matrix2d& A) {
  const double e = A.squaredNorm(), d = std::abs(A.determinant());
  const double root = std::sqrt(std::max(0.0, e * e - 4.0 * d * d));
  const double s0 = std::sqrt(0.5 * (e + root));
  return {s0, s0 > 0.0 ? d / s0 : 0.0};
}

/// The image under the warp at the template's pixels, in float (row-major, n x n);
/// false when a pixel has no 2x2 neighbourhood. The warped patch is a parallelogram:
/// inside the image when its four corners are.
bool warpPatch(const cv::Mat& image, const AffineWarp& warp, int half, std::vector<float>& out) {
  const int n = 2 * half + 1;
  const double lim_u = image.cols - 1, lim_v = image.rows - 1;
  for (const double cx : {-half, half})
    for (const double cy : {-half, half}) {
      const Eigen::Vector2d uv = warp.A * Eigen::Vector2d(cx, cy) + warp.t;
      if (!(uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() < lim_u && uv.y() < lim_v)) return false;
    }
  const double a00 = warp.A(0, 0), a01 = warp.A(0, 1), a10 = warp.A(1, 0), a11 = warp.A(1, 1);
  const std::size_t step = image.step1();
  const uchar* data = image.ptr<uchar>();
  for (int r = 0; r < n; ++r) {
    const double y = r - half;
    double u = warp.t.x() + a01 * y - a00 * half, v = warp.t.y() + a11 * y - a10 * half;
    float* dst = out.data() + static_cast<std::size_t>(r) * n;
    for (int c = 0; c < n; ++c, u += a00, v += a10) {
      // The corners bound every pixel, but the running sums may round across the edge.
      const double uc = std::min(std::max(u, 0.0), lim_u - 1e-9), vc = std::min(std::max(v, 0.0), lim_v - 1e-9);
      const int x0 = static_cast<int>(uc), y0 = static_cast<int>(vc);
      const float ax = static_cast<float>(uc - x0), ay = static_cast<float>(vc - y0);
      const uchar* p0 = data + static_cast<std::size_t>(y0) * step + x0;
      const uchar* p1 = p0 + step;
      dst[c] = (1 - ay) * ((1 - ax) * p0[0] + ax * p0[1]) + ay * ((1 - ax) * p1[0] + ax * p1[1]);
    }
  }
  return true;
}

/// One Gauss-Newton step of a whole template whose warped patch lies in the image (the
/// precomputed inverse Hessian): false when the warped patch is flat.
bool stepWhole(const PatchTemplate& tmpl, WarpModel model, std::vector<float>& warped, Eigen::Matrix<double, 6, 1>& dp,
               double& zncc_out) {
  const std::size_t count = tmpl.values.size();
  // Normalize (zero mean, unit norm), then the error against the template and the
  // steepest-descent sums, in one pass over the normalized values.
  float sum = 0.f;
  for (float x : warped) sum += x;
  const float mean = sum / static_cast<float>(count);
  float ss = 0.f;
  for (float& x : warped) {
    x -= mean;
    ss += x * x;
  }
  // Below ~1 gray level of standard deviation there is nothing to align.
  if (ss < static_cast<float>(count)) return false;
  const float scale = 1.f / std::sqrt(ss);
  float b[6] = {0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  float zncc = 0.f;
  const float* t = tmpl.values.data();
  const float* sd = tmpl.sd.data();
  for (std::size_t i = 0; i < count; ++i, sd += 6) {
    const float w = warped[i] * scale;
    const float e = w - t[i];
    zncc += w * t[i];
    for (int k = 0; k < 6; ++k) b[k] += sd[k] * e;
  }
  zncc_out = zncc;
  const Eigen::Matrix<double, 6, 1> bd = Eigen::Map<const Eigen::Matrix<float, 6, 1>>(b).cast<double>();
  if (model == WarpModel::kTranslation) {
    dp.setZero();
    dp.tail<2>() = tmpl.H_translation_inv * bd.tail<2>();
  } else {
    dp = tmpl.H_inv * bd;
  }
  return true;
}

/// The Gauss-Newton step of `model` from the normal equations H dp = b (the affine
/// parameters then the translation); false when H is singular in those parameters.
bool solveStep(const Eigen::Matrix<double, 6, 6>& H, const Eigen::Matrix<double, 6, 1>& b, WarpModel model,
               Eigen::Matrix<double, 6, 1>& dp) {
  if (model == WarpModel::kTranslation) {
    const Eigen::Matrix2d Ht = H.bottomRightCorner<2, 2>();
    if (!(Ht.determinant() > 1e-9 * Ht.squaredNorm())) return false;
    dp.setZero();
    dp.tail<2>() = Ht.inverse() * b.tail<2>();
    return true;
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
  if (!wellConditioned(ldlt)) return false;
  dp = ldlt.solve(b);
  return true;
}

/// One Gauss-Newton step over the template pixels that are in the template and whose
/// warped position is in the image (a patch at the border): both sides normalized over
/// those pixels, the Hessian built from them. False when too few remain or either side
/// is flat or without texture in both directions.
bool stepMasked(const PatchTemplate& tmpl, const cv::Mat& image, const AffineWarp& warp, WarpModel model,
                double min_inside, Eigen::Matrix<double, 6, 1>& dp, double& zncc_out) {
  const int half = tmpl.half, n = 2 * half + 1;
  std::vector<int> used;
  std::vector<float> w;
  used.reserve(static_cast<std::size_t>(n) * n);
  w.reserve(static_cast<std::size_t>(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int k = r * n + c;
      if (!tmpl.inside.empty() && !tmpl.inside[static_cast<std::size_t>(k)]) continue;
      const Eigen::Vector2d uv = warp.A * Eigen::Vector2d(c - half, r - half) + warp.t;
      float value;
      if (!sample(image, uv.x(), uv.y(), value)) continue;
      used.push_back(k);
      w.push_back(value);
    }
  const double kept = static_cast<double>(used.size());
  if (kept < min_inside * n * n) return false;
  double t_mean = 0, w_mean = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    t_mean += tmpl.values[static_cast<std::size_t>(used[i])];
    w_mean += w[i];
  }
  t_mean /= kept;
  w_mean /= kept;
  double t_ss = 0, w_ss = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    const double dt = tmpl.values[static_cast<std::size_t>(used[i])] - t_mean, dw = w[i] - w_mean;
    t_ss += dt * dt;
    w_ss += dw * dw;
  }
  // Below ~1 gray level of standard deviation there is nothing to align (the template's
  // values are normalized: a flat subset has almost no spread left).
  if (w_ss < kept || t_ss < 1e-6) return false;
  const double t_scale = 1.0 / std::sqrt(t_ss), w_scale = 1.0 / std::sqrt(w_ss);
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  double zncc = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    const std::size_t k = static_cast<std::size_t>(used[i]);
    const Eigen::Matrix<double, 6, 1> s =
        t_scale * Eigen::Map<const Eigen::Matrix<float, 6, 1>>(tmpl.sd.data() + 6 * k).cast<double>();
    const double tv = (tmpl.values[k] - t_mean) * t_scale, wv = (w[i] - w_mean) * w_scale;
    H.noalias() += s * s.transpose();
    b += s * (wv - tv);
    zncc += wv * tv;
  }
  zncc_out = zncc;
  return solveStep(H, b, model, dp);
}

}  // namespace

AlignResult alignAffine(const PatchTemplate& tmpl, const cv::Mat& image, AffineWarp& warp,
                        const AlignOptions& options) {
  AlignResult res;
  if (!tmpl.valid) return res;
  std::vector<float> warped(tmpl.values.size());
  const double min_inside = std::min(options.min_inside, tmpl.min_inside);
  for (res.iterations = 1; res.iterations <= options.max_iterations; ++res.iterations) {
    Eigen::Matrix<double, 6, 1> dp;
    double zncc = -1.0;
    const bool whole = tmpl.inside.empty() && warpPatch(image, warp, tmpl.half, warped);
    if (!whole && min_inside >= 1.0) return res;  // leaves the image
    if (!(whole ? stepWhole(tmpl, options.model, warped, dp, zncc)
                : stepMasked(tmpl, image, warp, options.model, min_inside, dp, zncc)))
      return res;
    res.zncc = zncc;
    Eigen::Matrix2d D;
    D << 1.0 + dp[0], dp[1], dp[2], 1.0 + dp[3];
    if (std::abs(D.determinant()) < 1e-6) return res;
    // Inverse composition: W(x) <- W(W_dp^-1(x)).
    const Eigen::Matrix2d A_new = warp.A * D.inverse();
    const Eigen::Vector2d step = A_new * dp.tail<2>();
    warp.A = A_new;
    warp.t -= step;
    const Eigen::Vector2d sv = singularValues2(warp.A);
    if (!(sv[1] > 1.0 / options.max_scale_change && sv[0] < options.max_scale_change)) return res;
    if (step.norm() < options.epsilon_px) {
      res.converged = true;
      return res;
    }
  }
  res.iterations = options.max_iterations;
  return res;
}

Eigen::Matrix2d matchShape(const cv::Mat& image, const Eigen::Vector2d& uv, int half, double max_ratio) {
  const Eigen::Matrix2d identity = Eigen::Matrix2d::Identity();
  const int u0 = static_cast<int>(std::lround(uv.x())), v0 = static_cast<int>(std::lround(uv.y()));
  if (image.empty() || image.type() != CV_8UC1 || u0 - half < 1 || v0 - half < 1 || u0 + half > image.cols - 2 ||
      v0 + half > image.rows - 2)
    return identity;
  Eigen::Matrix2d H = Eigen::Matrix2d::Zero();
  for (int v = v0 - half; v <= v0 + half; ++v) {
    const uchar* row = image.ptr<uchar>(v);
    const uchar* up = image.ptr<uchar>(v - 1);
    const uchar* down = image.ptr<uchar>(v + 1);
    for (int u = u0 - half; u <= u0 + half; ++u) {
      const double gu = 0.5 * (row[u + 1] - row[u - 1]), gv = 0.5 * (down[u] - up[u]);
      H(0, 0) += gu * gu;
      H(0, 1) += gu * gv;
      H(1, 1) += gv * gv;
    }
  }
  H(1, 0) = H(0, 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(H);
  const double l_max = eig.eigenvalues()[1];
  if (!(l_max > 1e-9)) return identity;
  const Eigen::Vector2d ratio(std::clamp(l_max / std::max(eig.eigenvalues()[0], 1e-12), 1.0, max_ratio), 1.0);
  return eig.eigenvectors() * ratio.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace idyvins::frontend
