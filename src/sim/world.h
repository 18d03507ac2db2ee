#pragma once
// The simulated world: textured rectangles (static scenery), vehicles (textured
// boxes moving along lanes) and checkerboard markers with known corners.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "sim/textures.h"

namespace idyvins::sim {

/// A textured rectangle: corner `origin`, unit edge directions `u`, `v` (normal u×v
/// faces the viewer), extents in metres, and texture coordinate offsets.
struct Quad {
  Eigen::Vector3d origin, u, v;
  double width = 1, height = 1;
  int texture = 0;
  double tex_offset_s = 0, tex_offset_t = 0;
  float albedo = 1.0f;  ///< brightness factor
  /// Texture contrast around the texture's mean (1: as generated; < 1: plainer material,
  /// simulate --realism).
  float contrast = 1.0f;
  std::uint8_t object_id = 0;  ///< 0 = static world, k = moving object k
  bool two_sided = false;
};

/// A box-shaped vehicle driving along a straight lane (wrapping around) or around
/// an elliptic loop (centre lane_start, semi-axes ellipse_a/b along x/y).
struct Vehicle {
  int id = 1;                                            ///< object id in masks (1..255)
  std::string type;                                      ///< car, van, truck
  Eigen::Vector3d size = Eigen::Vector3d::Zero();        ///< length, width, height (m)
  Eigen::Vector3d lane_start = Eigen::Vector3d::Zero();  ///< lane start (ground point)
  Eigen::Vector3d lane_dir = Eigen::Vector3d::Zero();    ///< unit direction of travel (zero on loops)
  double lane_length = 100;                              ///< the vehicle wraps after this distance
  double speed = 5;                                      ///< m/s
  double offset = 0;                                     ///< position along the lane at t = 0 (m)
  int texture = 0;
  float albedo = 1.0f;
  bool ellipse = false;  ///< elliptic loop instead of a straight lane
  double ellipse_a = 0, ellipse_b = 0;
  double direction = 1.0;  ///< +1 counter-clockwise, -1 clockwise (loops)
  /// Centre of the box's bottom face at time t.
  Eigen::Vector3d position(double t) const;
  /// Unit direction of travel at time t.
  Eigen::Vector3d heading(double t) const;
  /// The 5 visible faces (4 sides + roof) at time t.
  std::vector<Quad> faces(double t) const;
};

/// A planar checkerboard marker: its quad and its inner corners in the world.
struct Marker {
  Quad quad;
  std::vector<Eigen::Vector3d> corners_w;
};

/// Everything that can be seen.
struct World {
  std::string scene;
  std::vector<Quad> statics;
  std::vector<Vehicle> vehicles;
  std::vector<Marker> markers;
  bool sky = false;  ///< outdoor: rays that hit nothing see the sky
  /// Temporarily parked cars (SceneOptions::parked), also in `statics`: corners of their boxes.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> parked;
  /// All quads at time t (statics, markers, vehicle faces).
  std::vector<Quad> quadsAt(double t) const;
};

/// Dynamic levels, like VIODE's.
enum class Level { kNone, kLow, kMid, kHigh };
bool parseLevel(const std::string& text, Level& level);
const char* toString(Level level);

/// Where the rig goes through the scene.
enum class Route {
  kDefault,  ///< city: along the street; parking_lot: laps of the ellipse (about 33 s each)
  kBlock,    ///< city only: laps around a block (main street, cross street, back street, cross street)
};
bool parseRoute(const std::string& text, Route& route);
const char* toString(Route route);

/// Options for building a scene.
struct SceneOptions {
  std::string scene = "city";  ///< city | parking_lot
  Level level = Level::kNone;
  /// The place: layout, textures, materials, permanently parked cars.
  std::uint64_t seed = 1;
  /// The run through the place: traffic, temporarily parked cars, the trajectory's phases
  /// and start, sensor noise. 0: the same as `seed` (the data of a single-seed run).
  std::uint64_t traffic_seed = 0;
  /// Temporarily parked cars (static within the run, placed from the traffic seed: present in
  /// one run, gone or elsewhere in another): slots in the garage's centre, on the back street
  /// of the city block.
  int parked = 0;
  Route route = Route::kDefault;
  bool opening_vehicle = false;  ///< a vehicle passes close in front during the first seconds
  /// The seed of the run (traffic_seed, or seed when it is 0).
  std::uint64_t runSeed() const { return traffic_seed != 0 ? traffic_seed : seed; }
};

/// Builds a scene. Throws std::invalid_argument for an unknown scene name.
World buildWorld(const SceneOptions& options, const TextureBank& textures);

/// Axis-aligned textured box (5 or 6 faces facing outwards, or inwards for rooms).
void addBox(std::vector<Quad>& quads, const Eigen::Vector3d& min, const Eigen::Vector3d& max, int texture, float albedo,
            bool inward, bool with_bottom, std::uint8_t object_id = 0);

}  // namespace idyvins::sim
