#pragma once
// Intrinsic calibration of one camera, as read from a camodocal camera file.

#include <array>
#include <string>

namespace idyvins::camera {

/// Supported projection models.
enum class ModelType {
  kPinhole,        ///< pinhole + radial-tangential (k1 k2 p1 p2), camodocal PINHOLE
  kKannalaBrandt,  ///< equidistant fisheye (k2 k3 k4 k5), camodocal KANNALA_BRANDT
  kMei             ///< unified (Mei) omnidirectional, mirror ξ + radtan (k1 k2 p1 p2), camodocal MEI
};

/// Camera intrinsics. For KANNALA_BRANDT, fx fy cx cy hold mu mv u0 v0; for MEI gamma1 gamma2 u0 v0.
struct CameraParams {
  ModelType type = ModelType::kPinhole;
  std::string name;
  int width = 0;   ///< pixels
  int height = 0;  ///< pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;
  /// PINHOLE and MEI: k1 k2 p1 p2; KANNALA_BRANDT: k2 k3 k4 k5.
  std::array<double, 4> dist{0, 0, 0, 0};
  /// MEI only: the mirror parameter ξ (0 is a pinhole, 1 a parabolic mirror).
  double xi = 0;
};

/// "PINHOLE", "KANNALA_BRANDT" or "MEI".
const char* toString(ModelType type);

/// Pixels per unit of the normalized plane (x/z, y/z) at the principal point, per axis: fx and
/// fy for PINHOLE; their mean for the wide-angle models, whose scale changes across the image
/// (MEI: γ / (1 + ξ)). Thresholds in pixels on normalized errors use these.
std::array<double, 2> pixelsPerNormalized(const CameraParams& params);

}  // namespace idyvins::camera
