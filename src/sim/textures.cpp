#include "sim/textures.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace idyvins::sim {
namespace {

constexpr int kCheckerSquares = 8;

/// Smooth random background: low-frequency value noise.
cv::Mat background(cv::RNG& rng, int n, double mean, double amplitude, int cells) {
  cv::Mat small(cells, cells, CV_32F);
  rng.fill(small, cv::RNG::UNIFORM, mean - amplitude, mean + amplitude);
  cv::Mat big;
  cv::resize(small, big, cv::Size(n, n), 0, 0, cv::INTER_CUBIC);
  return big;
}

void randomShapes(cv::Mat& img, cv::RNG& rng, int rects, int circles, int lines, int min_size, int max_size) {
  const int n = img.cols;
  for (int i = 0; i < rects; ++i) {
    const int w = rng.uniform(min_size, max_size), h = rng.uniform(min_size, max_size);
    const int x = rng.uniform(0, n), y = rng.uniform(0, n);
    cv::rectangle(img, cv::Rect(x, y, w, h), cv::Scalar(rng.uniform(10, 245)), cv::FILLED);
  }
  for (int i = 0; i < circles; ++i) {
    cv::circle(img, cv::Point(rng.uniform(0, n), rng.uniform(0, n)), rng.uniform(min_size / 2, max_size / 2),
               cv::Scalar(rng.uniform(10, 245)), cv::FILLED, cv::LINE_AA);
  }
  for (int i = 0; i < lines; ++i) {
    cv::line(img, cv::Point(rng.uniform(0, n), rng.uniform(0, n)), cv::Point(rng.uniform(0, n), rng.uniform(0, n)),
             cv::Scalar(rng.uniform(10, 245)), rng.uniform(1, 4), cv::LINE_AA);
  }
}

cv::Mat makeTexture(TextureKind kind, cv::RNG& rng, int n) {
  cv::Mat f;
  switch (kind) {
    case TextureKind::kFacade: {
      f = background(rng, n, 130, 50, 8);
      randomShapes(f, rng, 500, 120, 60, n / 128, n / 16);
      // Windows: a regular grid of dark panes with frames.
      const int cols = rng.uniform(5, 9), rows = rng.uniform(4, 7);
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
          const int cw = n / cols, ch = n / rows;
          const cv::Rect outer(c * cw + cw / 6, r * ch + ch / 5, cw * 2 / 3, ch * 3 / 5);
          cv::rectangle(f, outer, cv::Scalar(rng.uniform(20, 70)), cv::FILLED);
          cv::rectangle(f, outer, cv::Scalar(rng.uniform(180, 240)), std::max(2, n / 256));
          cv::line(f, {outer.x + outer.width / 2, outer.y}, {outer.x + outer.width / 2, outer.y + outer.height},
                   cv::Scalar(rng.uniform(160, 230)), std::max(2, n / 512));
        }
      break;
    }
    case TextureKind::kGround:
      f = background(rng, n, 110, 35, 16);
      randomShapes(f, rng, 700, 250, 40, n / 256, n / 24);
      break;
    case TextureKind::kVehicle:
      f = background(rng, n, 120, 60, 6);
      randomShapes(f, rng, 600, 200, 80, n / 128, n / 12);
      break;
    case TextureKind::kConcrete:
      f = background(rng, n, 140, 40, 12);
      randomShapes(f, rng, 600, 150, 100, n / 160, n / 14);
      break;
    case TextureKind::kChecker: {
      f = cv::Mat(n, n, CV_32F);
      const int sq = n / kCheckerSquares;
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) f.at<float>(y, x) = ((x / sq + y / sq) % 2) ? 230.f : 25.f;
      break;
    }
  }
  if (kind != TextureKind::kChecker) cv::GaussianBlur(f, f, cv::Size(0, 0), 0.8);
  cv::Mat out;
  f.convertTo(out, CV_8U);
  return out;
}

/// Fractal value noise: octaves of `base_cells`, 2 base_cells, ... cells, each half the
/// amplitude of the one before, around `mean`.
cv::Mat fractalNoise(cv::RNG& rng, int n, double mean, double amplitude, int base_cells, int octaves) {
  cv::Mat f(n, n, CV_32F, cv::Scalar(mean));
  double amp = amplitude;
  for (int o = 0, cells = base_cells; o < octaves && cells <= n; ++o, cells *= 2, amp *= 0.5)
    f += background(rng, n, 0.0, amp, cells);
  return f;
}

/// Rows of bricks of random shade with mortar joints (a validation facade).
void bricks(cv::Mat& f, cv::RNG& rng, int n) {
  const int row_h = rng.uniform(n / 48, n / 28), joint = std::max(2, row_h / 8);
  for (int y = 0, row = 0; y < n; y += row_h, ++row) {
    int x = row % 2 ? -rng.uniform(row_h, 2 * row_h) : 0;
    while (x < n) {
      const int w = rng.uniform(2 * row_h, 4 * row_h);
      const cv::Rect brick = cv::Rect(x + joint / 2, y + joint / 2, w - joint, row_h - joint) & cv::Rect(0, 0, n, n);
      const double shade = rng.gaussian(22.0);
      if (!brick.empty()) f(brick) += cv::Scalar(shade);
      x += w;
    }
    cv::line(f, {0, y}, {n, y}, cv::Scalar(rng.uniform(170, 205)), joint);
  }
}

/// Dark random-walk cracks (a validation concrete).
void cracks(cv::Mat& f, cv::RNG& rng, int n, int count) {
  for (int i = 0; i < count; ++i) {
    cv::Point p(rng.uniform(0, n), rng.uniform(0, n));
    double heading = rng.uniform(0.0, 2.0 * CV_PI);
    const int segments = rng.uniform(6, 20);
    for (int k = 0; k < segments; ++k) {
      heading += rng.gaussian(0.6);
      const int len = rng.uniform(n / 100, n / 30);
      const cv::Point q(p.x + static_cast<int>(len * std::cos(heading)),
                        p.y + static_cast<int>(len * std::sin(heading)));
      cv::line(f, p, q, cv::Scalar(rng.uniform(30, 70)), rng.uniform(1, 3), cv::LINE_AA);
      p = q;
    }
  }
}

/// Materials of the validation suite: other generators than makeTexture's, so that a
/// front end tuned on those meets surfaces it was not tuned on.
/// Bricks with a few plain doors, shutters and signs.
cv::Mat validationFacade(cv::RNG& rng, int n) {
  cv::Mat f = fractalNoise(rng, n, 125, 18, 8, 4);
  bricks(f, rng, n);
  // A few doors, shutters and signs: plain dark or light panels with a frame.
  for (int i = 0, count = rng.uniform(3, 8); i < count; ++i) {
    const cv::Rect r(rng.uniform(0, n), rng.uniform(0, n), rng.uniform(n / 16, n / 6), rng.uniform(n / 12, n / 5));
    cv::rectangle(f, r, cv::Scalar(rng.uniform(35, 225)), cv::FILLED);
    cv::rectangle(f, r, cv::Scalar(rng.uniform(60, 200)), std::max(2, n / 300));
  }
  return f;
}

/// Asphalt: grain at every scale, aggregate speckles, worn painted lines.
cv::Mat validationAsphalt(cv::RNG& rng, int n) {
  cv::Mat f = fractalNoise(rng, n, 95, 30, 8, 6);
  for (int i = 0; i < 3000; ++i)
    cv::circle(f, cv::Point(rng.uniform(0, n), rng.uniform(0, n)), rng.uniform(1, 3), cv::Scalar(rng.uniform(40, 200)),
               cv::FILLED);
  for (int i = 0; i < 6; ++i) {
    const int x = rng.uniform(0, n);
    cv::line(f, {x, 0}, {x + rng.uniform(-n / 8, n / 8), n}, cv::Scalar(rng.uniform(170, 220)), std::max(3, n / 80));
  }
  return f;
}

/// Paint with few features: smooth shading, panel seams, a few badges and windows.
cv::Mat validationVehicle(cv::RNG& rng, int n) {
  cv::Mat f = background(rng, n, rng.uniform(60, 190), 25, 3);
  for (int i = 0; i < 14; ++i) {
    const int a = rng.uniform(0, n);
    if (i % 2)
      cv::line(f, {a, 0}, {a, n}, cv::Scalar(rng.uniform(20, 80)), 2, cv::LINE_AA);
    else
      cv::line(f, {0, a}, {n, a}, cv::Scalar(rng.uniform(20, 80)), 2, cv::LINE_AA);
  }
  for (int i = 0; i < 10; ++i)
    cv::ellipse(f, cv::Point(rng.uniform(0, n), rng.uniform(0, n)),
                cv::Size(rng.uniform(n / 64, n / 16), rng.uniform(n / 64, n / 24)), rng.uniform(0, 180), 0, 360,
                cv::Scalar(rng.uniform(10, 245)), cv::FILLED, cv::LINE_AA);
  for (int i = 0; i < 4; ++i)
    cv::rectangle(f, cv::Rect(rng.uniform(0, n), rng.uniform(0, n), rng.uniform(n / 10, n / 4), n / 10),
                  cv::Scalar(rng.uniform(15, 60)), cv::FILLED);
  return f;
}

/// Stained, cracked concrete.
cv::Mat validationConcrete(cv::RNG& rng, int n) {
  cv::Mat f = fractalNoise(rng, n, 135, 22, 6, 6);
  for (int i = 0; i < 40; ++i)  // stains
    cv::circle(f, cv::Point(rng.uniform(0, n), rng.uniform(0, n)), rng.uniform(n / 60, n / 12),
               cv::Scalar(rng.uniform(90, 170)), cv::FILLED, cv::LINE_AA);
  cv::GaussianBlur(f, f, cv::Size(0, 0), 2.0);
  f += fractalNoise(rng, n, 0, 10, 64, 3);
  cracks(f, rng, n, 60);
  return f;
}

cv::Mat makeValidationTexture(TextureKind kind, cv::RNG& rng, int n) {
  cv::Mat f;
  switch (kind) {
    case TextureKind::kFacade:
      f = validationFacade(rng, n);
      break;
    case TextureKind::kGround:
      f = validationAsphalt(rng, n);
      break;
    case TextureKind::kVehicle:
      f = validationVehicle(rng, n);
      break;
    case TextureKind::kConcrete:
      f = validationConcrete(rng, n);
      break;
    case TextureKind::kChecker:
      return makeTexture(kind, rng, n);
  }
  cv::GaussianBlur(f, f, cv::Size(0, 0), 1.0);
  cv::Mat out;
  f.convertTo(out, CV_8U);
  return out;
}

float bilinear(const cv::Mat& img, double x, double y) {
  // Wrapping (tiled) bilinear lookup; texel centres at integer + 0.5.
  const int n = img.cols;
  x -= 0.5;
  y -= 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
  const int x0 = ((static_cast<int>(fx) % n) + n) % n, y0 = ((static_cast<int>(fy) % n) + n) % n;
  const int x1 = (x0 + 1) % n, y1 = (y0 + 1) % n;
  const std::uint8_t* r0 = img.ptr<std::uint8_t>(y0);
  const std::uint8_t* r1 = img.ptr<std::uint8_t>(y1);
  const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
  const float bot = r1[x0] + ax * (r1[x1] - r1[x0]);
  return top + ay * (bot - top);
}

}  // namespace

TextureBank::TextureBank(std::uint64_t seed, int per_kind, int log2_size, TextureStyle style) {
  const bool validation = style == TextureStyle::kValidation;
  cv::RNG rng(seed * 2654435761ull + (validation ? 9973 : 17));
  const int n = 1 << log2_size;
  const TextureKind kinds[] = {TextureKind::kFacade, TextureKind::kGround, TextureKind::kVehicle,
                               TextureKind::kConcrete, TextureKind::kChecker};
  const double standard_texel[] = {0.015, 0.01, 0.006, 0.012, 0.6 / (n / kCheckerSquares)};
  const double validation_texel[] = {0.012, 0.008, 0.008, 0.01, 0.6 / (n / kCheckerSquares)};
  const double* texel = validation ? validation_texel : standard_texel;
  by_kind_.resize(5);
  for (int k = 0; k < 5; ++k) {
    const int count = kinds[k] == TextureKind::kChecker ? 1 : per_kind;
    for (int i = 0; i < count; ++i) {
      Texture t;
      t.texel_m = texel[k];
      t.levels.push_back(validation ? makeValidationTexture(kinds[k], rng, n) : makeTexture(kinds[k], rng, n));
      while (t.levels.back().cols > 1) {
        cv::Mat half;
        cv::resize(t.levels.back(), half, cv::Size(t.levels.back().cols / 2, t.levels.back().rows / 2), 0, 0,
                   cv::INTER_AREA);
        t.levels.push_back(half);
      }
      by_kind_[k].push_back(static_cast<int>(textures_.size()));
      textures_.push_back(std::move(t));
    }
  }
}

int TextureBank::index(TextureKind kind, int i) const {
  const auto& list = by_kind_[static_cast<int>(kind)];
  return list[static_cast<std::size_t>(i) % list.size()];
}

double TextureBank::checkerSquare() const {
  const Texture& t = textures_[index(TextureKind::kChecker, 0)];
  return t.texel_m * (t.levels[0].cols / kCheckerSquares);
}

float TextureBank::sample(int texture, double s_m, double t_m, double footprint_m) const {
  const Texture& tex = textures_[texture];
  const double texels = std::max(footprint_m / tex.texel_m, 1e-6);
  const double level = std::max(0.0, std::log2(texels));
  const int max_level = static_cast<int>(tex.levels.size()) - 1;
  const int l0 = std::min(static_cast<int>(level), max_level);
  const int l1 = std::min(l0 + 1, max_level);
  const double frac = std::min(1.0, level - l0);
  const double u = s_m / tex.texel_m, v = t_m / tex.texel_m;
  const float a = bilinear(tex.levels[l0], u / (1 << l0), v / (1 << l0));
  if (frac < 1e-3 || l0 == l1) return a;
  const float b = bilinear(tex.levels[l1], u / (1 << l1), v / (1 << l1));
  return static_cast<float>(a + frac * (b - a));
}

}  // namespace idyvins::sim
