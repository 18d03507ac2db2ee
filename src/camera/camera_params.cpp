#include "camera/camera_params.h"

namespace idyvins::camera {

const char* toString(ModelType type) {
  switch (type) {
    case ModelType::kPinhole:
      return "PINHOLE";
    case ModelType::kKannalaBrandt:
      return "KANNALA_BRANDT";
  }
  return "?";
}

}  // namespace idyvins::camera
