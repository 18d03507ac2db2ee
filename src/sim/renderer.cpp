#include "sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace idyvins::sim {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
constexpr double kNear = 0.05;  // m

/// Clips a polygon (camera frame) against z >= near.
std::vector<Vector3d> clipNear(const std::vector<Vector3d>& poly) {
  std::vector<Vector3d> out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vector3d& a = poly[i];
    const Vector3d& b = poly[(i + 1) % poly.size()];
    const bool ina = a.z() >= kNear, inb = b.z() >= kNear;
    if (ina) out.push_back(a);
    if (ina != inb) out.push_back(a + (b - a) * ((kNear - a.z()) / (b.z() - a.z())));
  }
  return out;
}
}  // namespace

Renderer::Renderer(const camera::CameraParams& params, const TextureBank& textures, double max_ray_angle_rad)
    : params_(params), model_(camera::makeCamera(params)), textures_(textures) {
  rays_.resize(static_cast<std::size_t>(params.width) * params.height);
  const bool pinhole = params.type == camera::ModelType::kPinhole;
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  for (int v = 0; v < params.height; ++v)
    for (int u = 0; u < params.width; ++u) {
      Vector2d xy;
      Vector3d ray;
      Eigen::Vector3f& r = rays_[static_cast<std::size_t>(v) * params.width + u];
      if (model_->liftToNormalized(Vector2d(u, v), xy)) {
        r = std::atan(xy.norm()) <= max_ray_angle_rad ? Eigen::Vector3f(xy.x(), xy.y(), 1.0f) : none;
      } else if (pinhole) {
        throw std::runtime_error("renderer: camera model cannot lift every pixel");
      } else if (model_->liftToRay(Vector2d(u, v), ray) &&
                 std::acos(std::clamp(ray.z(), -1.0, 1.0)) <= max_ray_angle_rad) {
        r = ray.cast<float>();  // past 90 degrees
        past_90_deg_ = true;
      } else {
        r = none;  // outside the lens: dark
      }
      if (!pinhole) continue;  // pixelBox projects the edges
      const Vector2d pin(params.fx * xy.x() + params.cx, params.fy * xy.y() + params.cy);
      max_distortion_px_ = std::max(max_distortion_px_, (pin - Vector2d(u, v)).norm());
    }
  // Past 90 degrees every ray is a unit one, so the near test is on distance: near 90 degrees
  // a surface's depth goes to 0 (the ground beside the camera would be cut off as too near).
  if (past_90_deg_)
    for (Eigen::Vector3f& r : rays_)
      if (r.allFinite()) r.normalize();
}

RenderOutput Renderer::render(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c, bool sky,
                              double noise_sigma, std::uint64_t noise_seed) const {
  RenderOutput out = renderRadiance(quads, T_w_c, sky);
  const int W = params_.width, H = params_.height;
  const cv::Mat radiance = out.image;
  out.image = cv::Mat(H, W, CV_8UC1);
  cv::Mat noise(H, W, CV_32F, cv::Scalar(0));
  if (noise_sigma > 0) {
    cv::RNG rng(noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
  }
  for (int py = 0; py < H; ++py) {
    std::uint8_t* img = out.image.ptr<std::uint8_t>(py);
    const float* rad = radiance.ptr<float>(py);
    const float* nz = noise.ptr<float>(py);
    for (int px = 0; px < W; ++px) img[px] = cv::saturate_cast<std::uint8_t>(rad[px] + nz[px]);
  }
  return out;
}

void Renderer::pixelBox(const std::vector<Vector3d>& poly, double margin, int& u0, int& u1, int& v0, int& v1) const {
  const int W = params_.width, H = params_.height;
  double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
  if (params_.type == camera::ModelType::kPinhole) {  // the normalized box, widened by the distortion
    for (const auto& p : poly) {
      xmin = std::min(xmin, p.x() / p.z());
      xmax = std::max(xmax, p.x() / p.z());
      ymin = std::min(ymin, p.y() / p.z());
      ymax = std::max(ymax, p.y() / p.z());
    }
    xmin = params_.fx * xmin + params_.cx - margin, xmax = params_.fx * xmax + params_.cx + margin;
    ymin = params_.fy * ymin + params_.cy - margin, ymax = params_.fy * ymax + params_.cy + margin;
  } else {  // a wide lens bends the edges: the box of the projected edges, finely sampled
    constexpr int kSamples = 64;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vector3d& a = poly[i];
      const Vector3d& b = poly[(i + 1) % poly.size()];
      for (int k = 0; k < kSamples; ++k) {
        Vector2d uv;
        if (!model_->project(a + (b - a) * (static_cast<double>(k) / kSamples), uv)) {
          u0 = v0 = 0, u1 = W - 1, v1 = H - 1;  // beyond the lens model: every pixel is tried
          return;
        }
        xmin = std::min(xmin, uv.x()), xmax = std::max(xmax, uv.x());
        ymin = std::min(ymin, uv.y()), ymax = std::max(ymax, uv.y());
      }
    }
    xmin -= 4.0, xmax += 4.0, ymin -= 4.0, ymax += 4.0;  // the curve between samples
  }
  u0 = std::max(0, static_cast<int>(std::floor(xmin)));
  u1 = std::min(W - 1, static_cast<int>(std::ceil(xmax)));
  v0 = std::max(0, static_cast<int>(std::floor(ymin)));
  v1 = std::min(H - 1, static_cast<int>(std::ceil(ymax)));
}

Renderer::Hits Renderer::rasterize(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c) const {
  const int W = params_.width, H = params_.height;
  const std::size_t N = static_cast<std::size_t>(W) * H;
  Hits h{std::vector<float>(N, std::numeric_limits<float>::infinity()), std::vector<int>(N, -1), std::vector<float>(N),
         std::vector<float>(N), std::vector<float>(N)};
  std::vector<float>& zbuf = h.zbuf;
  std::vector<int>& hit = h.quad;
  std::vector<float>&hs = h.s, &ht = h.t, &hfoot = h.footprint;
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  const double f = model_->focal();
  const double margin = max_distortion_px_ + 2.0;

  for (int qi = 0; qi < static_cast<int>(quads.size()); ++qi) {
    const Quad& q = quads[qi];
    const Vector3d o = T_c_w * q.origin;
    const Vector3d u = T_c_w.linear() * q.u, v = T_c_w.linear() * q.v;
    const Vector3d n = u.cross(v);
    const double n_dot_o = n.dot(o);
    if (!q.two_sided && n_dot_o >= 0) continue;  // back face (camera behind the plane)
    const std::vector<Vector3d> corners = {o, o + u * q.width, o + u * q.width + v * q.height, o + v * q.height};
    const std::vector<Vector3d> poly = past_90_deg_ ? corners : clipNear(corners);
    if (poly.size() < 3) continue;
    int u0, u1, v0, v1;
    pixelBox(poly, margin, u0, u1, v0, v1);
    if (u0 > u1 || v0 > v1) continue;
    for (int py = v0; py <= v1; ++py) {
      for (int px = u0; px <= u1; ++px) {
        const std::size_t idx = static_cast<std::size_t>(py) * W + px;
        const Eigen::Vector3f& r = rays_[idx];
        const Vector3d d = r.cast<double>();
        const double n_dot_d = n.dot(d);
        if (std::abs(n_dot_d) < 1e-12 || !r.allFinite()) continue;  // no ray: outside the lens
        const double z = n_dot_o / n_dot_d;                         // the ray parameter: the depth where d.z = 1
        if (z < kNear || z >= zbuf[idx]) continue;
        const Vector3d rel = d * z - o;
        const double s = rel.dot(u), t = rel.dot(v);
        if (s < 0 || s > q.width || t < 0 || t > q.height) continue;
        zbuf[idx] = static_cast<float>(z);
        hit[idx] = qi;
        hs[idx] = static_cast<float>(s);
        ht[idx] = static_cast<float>(t);
        // Footprint of a pixel on the surface: z |d|² / (f |n·d|).
        hfoot[idx] = static_cast<float>(z * d.squaredNorm() / (f * std::abs(n_dot_d)));
      }
    }
  }
  return h;
}

RenderOutput Renderer::shade(const std::vector<Quad>& quads, const Hits& h, bool sky) const {
  const int W = params_.width, H = params_.height;
  const std::vector<float>& zbuf = h.zbuf;
  const std::vector<int>& hit = h.quad;
  const std::vector<float>&hs = h.s, &ht = h.t, &hfoot = h.footprint;
  RenderOutput out;
  out.image = cv::Mat(H, W, CV_32F);
  out.mask = cv::Mat::zeros(H, W, CV_8UC1);
  out.depth = cv::Mat::zeros(H, W, CV_32F);
  for (int py = 0; py < H; ++py) {
    float* img = out.image.ptr<float>(py);
    std::uint8_t* msk = out.mask.ptr<std::uint8_t>(py);
    float* dep = out.depth.ptr<float>(py);
    for (int px = 0; px < W; ++px) {
      const std::size_t idx = static_cast<std::size_t>(py) * W + px;
      float value;
      if (hit[idx] < 0) {  // the sky, or dark outside the lens
        value = sky && rays_[idx].allFinite() ? 215.0f - 25.0f * static_cast<float>(py) / H : 20.0f;
      } else {
        const Quad& q = quads[hit[idx]];
        const float tex = textures_.sample(q.texture, hs[idx] + q.tex_offset_s, ht[idx] + q.tex_offset_t, hfoot[idx]);
        if (q.contrast == 1.0f) {
          value = q.albedo * tex;
        } else {
          const float mean = textures_.texture(q.texture).levels.back().at<std::uint8_t>(0, 0);
          value = q.albedo * (mean + q.contrast * (tex - mean));
        }
        msk[px] = q.object_id;
        dep[px] = zbuf[idx] * rays_[idx].z();
      }
      img[px] = value;
    }
  }
  return out;
}

RenderOutput Renderer::renderRadiance(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c, bool sky) const {
  return shade(quads, rasterize(quads, T_w_c), sky);
}

}  // namespace idyvins::sim
