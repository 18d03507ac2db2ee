#pragma once
// Intrinsic calibration of one camera, as read from a camodocal camera file.

#include <array>
#include <string>

namespace idyvins::camera {

/// Supported projection models.
enum class ModelType {
  kPinhole,       ///< pinhole + radial-tangential (k1 k2 p1 p2), camodocal PINHOLE
  kKannalaBrandt  ///< equidistant fisheye (k2 k3 k4 k5), camodocal KANNALA_BRANDT
};

/// Camera intrinsics. For KANNALA_BRANDT, fx fy cx cy hold mu mv u0 v0.
struct CameraParams {
  ModelType type = ModelType::kPinhole;
  std::string name;
  int width = 0;   ///< pixels
  int height = 0;  ///< pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;
  /// PINHOLE: k1 k2 p1 p2; KANNALA_BRANDT: k2 k3 k4 k5.
  std::array<double, 4> dist{0, 0, 0, 0};
};

/// "PINHOLE" or "KANNALA_BRANDT".
const char* toString(ModelType type);

}  // namespace idyvins::camera
