// The rig in the order the system runs it: the left camera first (config.h, leftFirst).

#include "config/config.h"

namespace idyvins {

Config leftFirst(const Config& config) {
  Config c = config;
  if (!c.cam0_right) return c;
  std::swap(c.cams[0], c.cams[1]);
  std::swap(c.cam_paths[0], c.cam_paths[1]);
  std::swap(c.T_b_c[0], c.T_b_c[1]);
  c.cam0_right = false;
  return c;
}

}  // namespace idyvins
