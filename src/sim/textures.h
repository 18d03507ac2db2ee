#pragma once
// Procedural, deterministic textures with mipmaps, sampled trilinearly so that
// rendered images neither alias nor blur more than the pixel footprint requires.

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace idyvins::sim {

/// Kinds of texture the world uses.
enum class TextureKind { kFacade, kGround, kVehicle, kConcrete, kChecker };

/// Families of materials: the tuning suites' (shapes on smooth noise, window grids) and
/// the validation suite's (bricks, fractal noise, cracks, painted lines, plainer vehicles).
enum class TextureStyle { kStandard, kValidation };

/// One texture: a square 8-bit image and its mip pyramid (level 0 = full size).
struct Texture {
  std::vector<cv::Mat> levels;  ///< CV_8UC1, sizes N, N/2, ...
  double texel_m = 0.01;        ///< metres per level-0 texel
};

/// A bank of textures generated from a seed; read-only once built (thread-safe sampling).
class TextureBank {
 public:
  /// Builds `per_kind` textures of each kind (plus one checkerboard) of size 2^log2_size.
  TextureBank(std::uint64_t seed, int per_kind = 3, int log2_size = 10, TextureStyle style = TextureStyle::kStandard);

  /// Index of the i-th texture of a kind (i wraps).
  int index(TextureKind kind, int i) const;
  /// Trilinear sample at texture coordinates (s, t) in metres for a pixel footprint in metres.
  float sample(int texture, double s_m, double t_m, double footprint_m) const;
  const Texture& texture(int i) const { return textures_[i]; }
  /// Size of a checker square in metres (checker textures: 8x8 squares per tile).
  double checkerSquare() const;

 private:
  std::vector<Texture> textures_;
  std::vector<std::vector<int>> by_kind_;
};

}  // namespace idyvins::sim
