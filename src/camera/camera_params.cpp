#include "camera/camera_params.h"

namespace idyvins::camera {

const char* toString(ModelType type) {
  switch (type) {
    case ModelType::kPinhole:
      return "PINHOLE";
    case ModelType::kKannalaBrandt:
      return "KANNALA_BRANDT";
    case ModelType::kMei:
      return "MEI";
  }
  return "?";
}

std::array<double, 2> pixelsPerNormalized(const CameraParams& p) {
  if (p.type == ModelType::kPinhole) return {p.fx, p.fy};
  const double f = 0.5 * (p.fx + p.fy) / (p.type == ModelType::kMei ? 1.0 + p.xi : 1.0);
  return {f, f};
}

}  // namespace idyvins::camera
