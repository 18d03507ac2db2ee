#include "frontend/patch_alignment.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace idyvins::frontend {

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

double patchZncc(const cv::Mat& a, const Eigen::Vector2d& uv_a, const cv::Mat& b, const Eigen::Vector2d& uv_b,
                 int half) {
  const auto inside = [half](const cv::Mat& m, const Eigen::Vector2d& uv) {
    return uv.x() - half >= 0.0 && uv.y() - half >= 0.0 && uv.x() + half < m.cols - 1 && uv.y() + half < m.rows - 1;
  };
  if (!inside(a, uv_a) || !inside(b, uv_b)) return -1.0;
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
  const double va = saa - sa * sa / count, vb = sbb - sb * sb / count;
  // Below ~1 gray level of standard deviation there is nothing to correlate (as normalize()).
  if (va < count || vb < count) return -1.0;
  return (sab - sa * sb / count) / std::sqrt(va * vb);
}

PatchTemplate makePatchTemplate(const cv::Mat& image, const Eigen::Vector2d& uv_center, int half) {
  PatchTemplate tmpl;
  tmpl.half = half;
  const int n = 2 * half + 1, m = n + 2;  // with a 1 px margin for the gradients
  std::vector<float> big(static_cast<std::size_t>(m) * m);
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c)
      if (!sample(image, uv_center.x() + c - half - 1, uv_center.y() + r - half - 1, big[r * m + c])) return tmpl;
  tmpl.values.resize(static_cast<std::size_t>(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) tmpl.values[r * n + c] = big[(r + 1) * m + c + 1];
  // The normalization is affine in the intensities: apply the same scale to the gradients.
  double mean = 0, ss = 0;
  for (float x : tmpl.values) mean += x;
  mean /= static_cast<double>(tmpl.values.size());
  for (float x : tmpl.values) ss += (x - mean) * (x - mean);
  if (!normalize(tmpl.values)) return tmpl;
  const double scale = 1.0 / std::sqrt(ss);
  tmpl.sd.resize(6 * tmpl.values.size());
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double gx = 0.5 * scale * (big[(r + 1) * m + c + 2] - big[(r + 1) * m + c]);
      const double gy = 0.5 * scale * (big[(r + 2) * m + c + 1] - big[r * m + c + 1]);
      const double x = c - half, y = r - half;
      Eigen::Matrix<double, 6, 1> s;
      s << gx * x, gx * y, gy * x, gy * y, gx, gy;
      H.noalias() += s * s.transpose();
      for (int k = 0; k < 6; ++k) tmpl.sd[6 * (r * n + c) + k] = static_cast<float>(s[k]);
    }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
  if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 1e-9 * ldlt.vectorD().maxCoeff()) return tmpl;
  tmpl.H_inv = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
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

}  // namespace

AlignResult alignAffine(const PatchTemplate& tmpl, const cv::Mat& image, AffineWarp& warp,
                        const AlignOptions& options) {
  AlignResult res;
  if (!tmpl.valid) return res;
  const int half = tmpl.half;
  const std::size_t count = tmpl.values.size();
  std::vector<float> warped(count);
  for (res.iterations = 1; res.iterations <= options.max_iterations; ++res.iterations) {
    if (!warpPatch(image, warp, half, warped)) return res;
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
    if (ss < static_cast<float>(count)) return res;
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
    res.zncc = zncc;
    const Eigen::Matrix<double, 6, 1> dp = tmpl.H_inv * Eigen::Map<const Eigen::Matrix<float, 6, 1>>(b).cast<double>();
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

}  // namespace idyvins::frontend
