#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace idyvins::sim {

using Eigen::Vector3d;

namespace {

/// Oriented box from a corner along unit axes ax, ay, az (right-handed), lengths l.
void addOrientedBox(std::vector<Quad>& quads, const Vector3d& c, const Vector3d& ax, const Vector3d& ay,
                    const Vector3d& az, const Vector3d& l, int texture, float albedo, bool inward, bool with_bottom,
                    std::uint8_t object_id) {
  struct Face {
    Vector3d origin, u, v;
    double w, h;
    float shade;
  };
  const Vector3d X = ax * l.x(), Y = ay * l.y(), Z = az * l.z();
  std::vector<Face> faces = {
      {c + Y, -ay, az, l.y(), l.z(), 0.85f},     // -x
      {c + X, ay, az, l.y(), l.z(), 0.95f},      // +x
      {c, ax, az, l.x(), l.z(), 0.9f},           // -y
      {c + X + Y, -ax, az, l.x(), l.z(), 0.8f},  // +y
      {c + Z, ax, ay, l.x(), l.y(), 1.05f},      // +z (top)
  };
  if (with_bottom) faces.push_back({c + Y, ax, -ay, l.x(), l.y(), 0.7f});  // -z
  for (const Face& f : faces) {
    Quad q;
    q.origin = inward ? Vector3d(f.origin + f.u * f.w) : f.origin;
    q.u = inward ? Vector3d(-f.u) : f.u;
    q.v = f.v;
    q.width = f.w;
    q.height = f.h;
    q.texture = texture;
    q.albedo = albedo * f.shade;
    q.object_id = object_id;
    q.tex_offset_s = 0.37 * (q.origin.x() + 2 * q.origin.y());
    q.tex_offset_t = 0.61 * (q.origin.z() + q.origin.y());
    quads.push_back(q);
  }
}

Quad groundQuad(double x0, double x1, double y0, double y1, double z, int texture, bool facing_up) {
  Quad q;
  q.origin = facing_up ? Vector3d(x0, y0, z) : Vector3d(x0, y1, z);
  q.u = Vector3d::UnitX();
  q.v = facing_up ? Vector3d::UnitY() : Vector3d(-Vector3d::UnitY());
  q.width = x1 - x0;
  q.height = y1 - y0;
  q.texture = texture;
  return q;
}

/// A 2.4 m checkerboard (4x4 squares of the checker texture) at `corner`, facing u × v.
Marker makeMarker(const Vector3d& corner, const Vector3d& u, const Vector3d& v, const TextureBank& tex) {
  Marker m;
  const double sq = tex.checkerSquare();
  m.quad.origin = corner;
  m.quad.u = u;
  m.quad.v = v;
  m.quad.width = m.quad.height = 4 * sq;
  m.quad.texture = tex.index(TextureKind::kChecker, 0);
  for (int i = 1; i < 4; ++i)
    for (int j = 1; j < 4; ++j) m.corners_w.push_back(corner + u * (i * sq) + v * (j * sq));
  return m;
}

struct LaneSpec {
  Vector3d start, dir;
  double length;
};

void addVehicles(World& w, const std::vector<LaneSpec>& lanes, const std::vector<int>& lane_of,
                 const std::vector<std::string>& types, const std::vector<double>& speeds,
                 const std::vector<double>& offsets, const TextureBank& tex) {
  for (std::size_t k = 0; k < lane_of.size(); ++k) {
    Vehicle v;
    v.id = static_cast<int>(w.vehicles.size()) + 1;
    v.type = types[k];
    v.size = v.type == "truck" ? Vector3d(8.0, 2.5, 3.2)
             : v.type == "van" ? Vector3d(5.0, 2.0, 2.0)
                               : Vector3d(4.5, 1.8, 1.5);
    const LaneSpec& lane = lanes[lane_of[k]];
    v.lane_start = lane.start;
    v.lane_dir = lane.dir.normalized();
    v.lane_length = lane.length;
    v.speed = speeds[k];
    v.offset = offsets[k];
    v.texture = tex.index(TextureKind::kVehicle, static_cast<int>(k));
    v.albedo = 0.8f + 0.05f * static_cast<float>(k % 5);
    w.vehicles.push_back(v);
  }
}

/// The street canyon: ground, building blocks, parked cars, markers.
void addCityStatics(World& w, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  w.statics.push_back(groundQuad(-80, 300, -80, 80, 0.0, tex.index(TextureKind::kGround, 0), true));
  const double half_street = 12.0;
  const std::vector<std::pair<double, double>> blocks = {{-60, 53}, {67, 123}, {137, 193}, {207, 250}};
  int building = 0;
  for (int side : {-1, 1}) {
    for (const auto& [bx0, bx1] : blocks) {
      double x = bx0;
      while (x < bx1 - 4) {
        const double len = std::min(bx1 - x, 10.0 + 14.0 * U(rng));
        const double setback = 1.5 * U(rng), depth = 14.0, height = 8.0 + 18.0 * U(rng);
        const double y_near = side * (half_street + setback), y_far = side * (half_street + setback + depth);
        addBox(w.statics, Vector3d(x, std::min(y_near, y_far), 0), Vector3d(x + len, std::max(y_near, y_far), height),
               tex.index(TextureKind::kFacade, building++), 0.8f + 0.4f * static_cast<float>(U(rng)), false, false);
        x += len;
      }
    }
  }
  // Buildings closing both ends of the street.
  addBox(w.statics, Vector3d(262, -40, 0), Vector3d(280, 40, 22), tex.index(TextureKind::kFacade, 1), 1.0f, false,
         false);
  addBox(w.statics, Vector3d(-95, -40, 0), Vector3d(-82, 40, 22), tex.index(TextureKind::kFacade, 2), 1.0f, false,
         false);
  // Parked cars along both curbs.
  for (int side : {-1, 1})
    for (double x = -50; x < 245; x += 6.0 + 3.0 * U(rng)) {
      if (U(rng) < 0.4 || std::abs(x - 60) < 9 || std::abs(x - 130) < 9 || std::abs(x - 200) < 9) continue;
      const double y = side * 9.8;
      addBox(w.statics, Vector3d(x, y - 0.9, 0), Vector3d(x + 4.4, y + 0.9, 1.5),
             tex.index(TextureKind::kVehicle, 7 + static_cast<int>(x)), 0.9f, false, false);
    }
  // Checkerboard markers on the street-facing facades (2 cm in front of them).
  for (double x = 10; x < 250; x += 30) {
    const int side = (static_cast<int>(x / 30) % 2) ? 1 : -1;
    const double y = side * (half_street - 0.02);
    // Facades facing the street: normal -side*y. u along ±x so that u × z = normal.
    const Vector3d u = side > 0 ? Vector3d(1, 0, 0) : Vector3d(-1, 0, 0);
    const Vector3d corner(side > 0 ? x : x + 2.4, y, 1.0);
    w.markers.push_back(makeMarker(corner, u, Vector3d::UnitZ(), tex));
  }
}

/// The street's traffic of a level (and the opening vehicle).
void addCityTraffic(World& w, const SceneOptions& o, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // Lanes: along the street (right-hand traffic) and along the three cross streets.
  std::vector<LaneSpec> lanes = {{{-90, -5.5, 0}, {1, 0, 0}, 370},
                                 {{-90, -2.5, 0}, {1, 0, 0}, 370},
                                 {{280, 2.5, 0}, {-1, 0, 0}, 370},
                                 {{280, 5.5, 0}, {-1, 0, 0}, 370}};
  for (double cx : {60.0, 130.0, 200.0}) {
    lanes.push_back({{cx - 3, -80, 0}, {0, 1, 0}, 160});
    lanes.push_back({{cx + 3, 80, 0}, {0, -1, 0}, 160});
  }
  std::vector<int> lane_of;
  std::vector<std::string> types;
  std::vector<double> speeds, offsets;
  auto add = [&](int lane, const std::string& type, double speed, double offset) {
    lane_of.push_back(lane);
    types.push_back(type);
    speeds.push_back(speed);
    offsets.push_back(offset);
  };
  auto rnd = [&](double a, double b) { return a + (b - a) * U(rng); };
  if (o.level == Level::kLow) {
    add(6, "car", rnd(4, 7), rnd(0, 160));  // cross street far ahead
    add(9, "van", rnd(4, 7), rnd(0, 160));
    add(3, "car", rnd(5, 8), rnd(60, 120));  // oncoming, outer lane, far at first
  } else if (o.level == Level::kMid) {
    for (int k = 0; k < 4; ++k) add(k % 4, k == 1 ? "van" : "car", rnd(5, 10), rnd(0, 370));
    for (int k = 0; k < 4; ++k) add(4 + k, "car", rnd(4, 9), rnd(0, 160));
  } else if (o.level == Level::kHigh) {
    // Slow trucks and vans in the near lane, a few metres apart from each other:
    // they overtake the drone slowly and fill much of the view for seconds.
    // They start behind the drone (lane start x = -90) and overtake it one after the other.
    for (int k = 0; k < 6; ++k) add(1, k % 2 ? "van" : "truck", rnd(3.0, 3.4), 82.0 - 16.0 * k + rnd(-2, 2));
    for (int k = 0; k < 5; ++k) add(2, k % 2 ? "truck" : "car", rnd(3.0, 5.0), 120 + 45.0 * k + rnd(0, 15));
    for (int k = 0; k < 4; ++k) add(k % 2 ? 0 : 3, "car", rnd(8, 12), rnd(0, 370));
    for (int k = 0; k < 6; ++k) add(4 + k, k % 3 ? "car" : "van", rnd(5, 10), rnd(0, 160));
  }
  if (o.opening_vehicle) {
    // A truck crossing 5-8 m in front of the drone during the first seconds.
    lanes.push_back({{10.0, -14.0, 0}, {0, 1, 0}, 400});
    add(static_cast<int>(lanes.size()) - 1, "truck", 3.0, 6.0);
  }
  addVehicles(w, lanes, lane_of, types, speeds, offsets, tex);
}

// The city block's back street: parallel to the main street, behind its south buildings.
constexpr double kBackStreetY = -40.0;

/// Buildings on the back street's south side and walls closing its ends (route kBlock).
void addBackStreetStatics(World& w, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const std::vector<std::pair<double, double>> blocks = {{-60, 53}, {67, 123}, {137, 193}, {207, 250}};
  int building = 40;
  for (const auto& [bx0, bx1] : blocks) {
    double x = bx0;
    while (x < bx1 - 4) {
      const double len = std::min(bx1 - x, 10.0 + 14.0 * U(rng));
      const double y_near = kBackStreetY - 12.0 - 1.5 * U(rng), height = 8.0 + 18.0 * U(rng);
      addBox(w.statics, Vector3d(x, y_near - 14.0, 0), Vector3d(x + len, y_near, height),
             tex.index(TextureKind::kFacade, building++), 0.8f + 0.4f * static_cast<float>(U(rng)), false, false);
      x += len;
    }
  }
  addBox(w.statics, Vector3d(262, -80, 0), Vector3d(280, -40, 22), tex.index(TextureKind::kFacade, 3), 1.0f, false,
         false);
  addBox(w.statics, Vector3d(-95, -80, 0), Vector3d(-82, -40, 22), tex.index(TextureKind::kFacade, 4), 1.0f, false,
         false);
}

/// Traffic of a level for laps around the block: both directions on the main and the back
/// street (slow trucks and vans in the lanes next to the rig), and on the cross streets.
void addBlockTraffic(World& w, const SceneOptions& o, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<LaneSpec> lanes;
  for (double y0 : {0.0, kBackStreetY}) {
    lanes.push_back({{-90, y0 - 5.5, 0}, {1, 0, 0}, 370});
    lanes.push_back({{-90, y0 - 2.5, 0}, {1, 0, 0}, 370});
    lanes.push_back({{280, y0 + 2.5, 0}, {-1, 0, 0}, 370});
    lanes.push_back({{280, y0 + 5.5, 0}, {-1, 0, 0}, 370});
  }
  for (double cx : {60.0, 130.0}) {
    lanes.push_back({{cx - 3, -80, 0}, {0, 1, 0}, 160});
    lanes.push_back({{cx + 3, 80, 0}, {0, -1, 0}, 160});
  }
  const int per_lane = o.level == Level::kHigh ? 6 : o.level == Level::kMid ? 3 : o.level == Level::kLow ? 1 : 0;
  std::vector<int> lane_of;
  std::vector<std::string> types;
  std::vector<double> speeds, offsets;
  auto rnd = [&](double a, double b) { return a + (b - a) * U(rng); };
  for (int lane = 0; lane < static_cast<int>(lanes.size()); ++lane) {
    const bool near = lane == 1 || lane == 6;  // next to the rig, in its direction (east on main, west on back)
    const int n = lane >= 8 ? (per_lane + 1) / 2 : per_lane;
    for (int k = 0; k < n; ++k) {
      lane_of.push_back(lane);
      types.push_back(near ? (k % 2 ? "van" : "truck") : (k % 3 ? "car" : "van"));
      speeds.push_back(near ? rnd(2.5, 3.5) : rnd(5, 10));
      offsets.push_back(lanes[lane].length * (k + rnd(0.0, 0.6)) / std::max(1, n));
    }
  }
  addVehicles(w, lanes, lane_of, types, speeds, offsets, tex);
}

/// Temporarily parked cars: `o.parked` of the scene's slots, chosen and textured from the run seed.
void addParked(World& w, const SceneOptions& o, const TextureBank& tex) {
  if (o.parked <= 0) return;
  std::vector<Vector3d> slots;  // box minimum corners; boxes 4.4 x 1.8 x 1.5 m along x
  if (o.scene == "parking_lot") {
    for (double y : {-2.2, 0.4})
      for (double x : {-9.5, -4.7, 0.1, 4.9}) slots.emplace_back(x, y, 0.0);
  } else {
    for (double y : {kBackStreetY - 10.7, kBackStreetY + 8.9})
      for (double x = 68; x < 121; x += 6.5) slots.emplace_back(x, y, 0.0);
  }
  std::mt19937_64 rng(o.runSeed() * 15485863u + 7u);
  std::shuffle(slots.begin(), slots.end(), rng);
  const std::size_t n = std::min(slots.size(), static_cast<std::size_t>(o.parked));
  for (std::size_t k = 0; k < n; ++k) {
    const Vector3d max = slots[k] + Vector3d(4.4, 1.8, 1.5);
    addBox(w.statics, slots[k], max, tex.index(TextureKind::kVehicle, 11 + static_cast<int>(rng() % 97)),
           0.85f + 0.1f * static_cast<float>(k % 3), false, false);
    w.parked.emplace_back(slots[k], max);
  }
}

World buildCity(const SceneOptions& o, const TextureBank& tex) {
  World w;
  w.scene = "city";
  w.sky = true;
  std::mt19937_64 rng(o.seed * 104729 + 11);
  addCityStatics(w, rng, tex);
  if (o.route == Route::kBlock) {
    std::mt19937_64 back(o.seed * 104729 + 17);
    addBackStreetStatics(w, back, tex);
  }
  addParked(w, o, tex);
  if (o.level == Level::kNone && !o.opening_vehicle) return w;
  // The traffic continues the layout's random stream for a single-seed run (as it always did).
  std::mt19937_64 own(o.runSeed() * 104729 + 13);
  std::mt19937_64& traffic = o.runSeed() == o.seed ? rng : own;
  if (o.route == Route::kBlock) {
    if (o.level != Level::kNone) addBlockTraffic(w, o, traffic, tex);
    if (o.opening_vehicle) throw std::invalid_argument("--opening-vehicle is for the street route only");
  } else {
    addCityTraffic(w, o, traffic, tex);
  }
  return w;
}

// Traffic loops in the garage (the drone flies the ellipse a = 14, b = 8 between them).
constexpr double kInnerA = 11.8, kInnerB = 5.8, kOuterA = 16.2, kOuterB = 10.2;

/// The garage: floor, ceiling, walls, pillars, parked cars, markers.
void addGarageStatics(World& w, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double X = 25, Y = 18, H = 3.2;
  // Floor, ceiling and walls of the garage (inward-facing box).
  addBox(w.statics, Vector3d(-X, -Y, 0), Vector3d(X, Y, H), tex.index(TextureKind::kConcrete, 0), 1.0f, true, true);
  w.statics.front().texture = tex.index(TextureKind::kConcrete, 1);
  w.statics[4].texture = tex.index(TextureKind::kConcrete, 2);  // ceiling
  w.statics[4].albedo = 0.75f;
  w.statics[5].texture = tex.index(TextureKind::kGround, 1);  // floor
  // Pillars, except near the drone's elliptic path (a = 14, b = 8).
  int k = 0;
  for (double px : {-21.0, -14.0, -7.0, 0.0, 7.0, 14.0, 21.0})
    for (double py : {-13.0, -4.5, 4.5, 13.0}) {
      double dmin = 1e9;
      for (double th = 0; th < 2 * M_PI; th += 0.01) {
        dmin = std::min(dmin, std::hypot(px - 14 * std::cos(th), py - 8 * std::sin(th)));
        dmin = std::min(dmin, std::hypot(px - kInnerA * std::cos(th), py - kInnerB * std::sin(th)));
        dmin = std::min(dmin, std::hypot(px - kOuterA * std::cos(th), py - kOuterB * std::sin(th)));
      }
      if (dmin < 2.0) continue;
      addBox(w.statics, Vector3d(px - 0.3, py - 0.3, 0), Vector3d(px + 0.3, py + 0.3, H),
             tex.index(TextureKind::kConcrete, k++), 0.9f, false, false);
    }
  // Parked cars along the long walls.
  for (int side : {-1, 1})
    for (double x = -23; x < 21; x += 2.8 + 1.5 * U(rng)) {
      if (U(rng) < 0.3) continue;
      const double y = side * (Y - 2.6);
      addBox(w.statics, Vector3d(x, y - 2.2, 0), Vector3d(x + 1.8, y + 2.2, 1.45),
             tex.index(TextureKind::kVehicle, 5 + static_cast<int>(x * 3)), 0.9f, false, false);
    }
  // Markers on the walls (2 cm in front).
  for (double x : {-15.0, 0.0, 15.0}) {
    w.markers.push_back(makeMarker(Vector3d(x, Y - 0.02, 0.4), Vector3d(1, 0, 0), Vector3d::UnitZ(), tex));
    w.markers.push_back(makeMarker(Vector3d(x + 2.4, -Y + 0.02, 0.4), Vector3d(-1, 0, 0), Vector3d::UnitZ(), tex));
  }
  for (double y : {-6.0, 6.0}) {
    w.markers.push_back(makeMarker(Vector3d(X - 0.02, y + 2.4, 0.4), Vector3d(0, -1, 0), Vector3d::UnitZ(), tex));
    w.markers.push_back(makeMarker(Vector3d(-X + 0.02, y, 0.4), Vector3d(0, 1, 0), Vector3d::UnitZ(), tex));
  }
}

/// Traffic of a level on the garage's loops (and the opening vehicle).
void addGarageTraffic(World& w, const SceneOptions& o, std::mt19937_64& rng, const TextureBank& tex) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // Traffic loops on an inner and an outer ellipse, 2.2 m from the drone's path.
  auto rnd = [&](double a, double b) { return a + (b - a) * U(rng); };
  auto add = [&](bool inner, double direction, const std::string& type, double speed, double offset) {
    Vehicle v;
    v.id = static_cast<int>(w.vehicles.size()) + 1;
    v.type = type;
    v.size = type == "van" ? Vector3d(5.0, 2.0, 1.9) : Vector3d(4.5, 1.8, 1.5);
    v.ellipse = true;
    v.lane_start = Vector3d::Zero();
    v.ellipse_a = inner ? kInnerA : kOuterA;
    v.ellipse_b = inner ? kInnerB : kOuterB;
    v.direction = direction;
    v.speed = speed;
    v.offset = offset;
    v.texture = tex.index(TextureKind::kVehicle, v.id);
    v.albedo = 0.8f + 0.05f * static_cast<float>(v.id % 5);
    w.vehicles.push_back(v);
  };
  if (o.level == Level::kLow) {
    add(false, -1, "car", rnd(3, 5), rnd(0, 90));
    add(false, -1, "car", rnd(3, 5), rnd(0, 90));
  } else if (o.level == Level::kMid) {
    for (int i = 0; i < 3; ++i) add(true, 1, i % 2 ? "van" : "car", rnd(3, 5), 15.0 * i + rnd(0, 5));
    for (int i = 0; i < 2; ++i) add(false, -1, "car", rnd(4, 7), 40.0 * i + rnd(0, 10));
  } else if (o.level == Level::kHigh) {
    // Same direction as the drone on the inner loop, overtaking it one after the other.
    for (int i = 0; i < 5; ++i) add(true, 1, i % 2 ? "van" : "car", rnd(3.0, 3.6), 9.0 * i + rnd(0, 3));
    for (int i = 0; i < 5; ++i) add(false, i % 2 ? 1.0 : -1.0, i % 3 ? "car" : "van", rnd(3, 6), 18.0 * i + rnd(0, 6));
  }
  if (o.opening_vehicle) add(true, 1, "van", 3.0, 0.0);
}

World buildParkingLot(const SceneOptions& o, const TextureBank& tex) {
  World w;
  w.scene = "parking_lot";
  std::mt19937_64 rng(o.seed * 130363 + 5);
  addGarageStatics(w, rng, tex);
  addParked(w, o, tex);
  if (o.level == Level::kNone && !o.opening_vehicle) return w;
  std::mt19937_64 own(o.runSeed() * 130363 + 7);
  addGarageTraffic(w, o, o.runSeed() == o.seed ? rng : own, tex);
  return w;
}

}  // namespace

void addBox(std::vector<Quad>& quads, const Vector3d& min, const Vector3d& max, int texture, float albedo, bool inward,
            bool with_bottom, std::uint8_t object_id) {
  addOrientedBox(quads, min, Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ(), max - min, texture, albedo,
                 inward, with_bottom, object_id);
}

namespace {
double loopAngle(const Vehicle& v, double t) {
  return v.direction * (v.offset + v.speed * t) / (0.5 * (v.ellipse_a + v.ellipse_b));
}
}  // namespace

Vector3d Vehicle::position(double t) const {
  if (ellipse) {
    const double th = loopAngle(*this, t);
    return lane_start + Vector3d(ellipse_a * std::cos(th), ellipse_b * std::sin(th), 0.0);
  }
  double s = std::fmod(offset + speed * t, lane_length);
  if (s < 0) s += lane_length;
  return lane_start + lane_dir * s;
}

Vector3d Vehicle::heading(double t) const {
  if (!ellipse) return lane_dir;
  const double th = loopAngle(*this, t);
  return (direction * Vector3d(-ellipse_a * std::sin(th), ellipse_b * std::cos(th), 0.0)).normalized();
}

std::vector<Quad> Vehicle::faces(double t) const {
  const Vector3d f = heading(t);
  const Vector3d up = Vector3d::UnitZ();
  const Vector3d l = up.cross(f);
  const Vector3d c = position(t) - f * (0.5 * size.x()) - l * (0.5 * size.y());
  std::vector<Quad> quads;
  addOrientedBox(quads, c, f, l, up, size, texture, albedo, false, false, static_cast<std::uint8_t>(id));
  for (auto& q : quads) {  // texture fixed to the body, not to the world
    q.tex_offset_s = 0.5 * id;
    q.tex_offset_t = 0.3 * id;
  }
  return quads;
}

std::vector<Quad> World::quadsAt(double t) const {
  std::vector<Quad> all = statics;
  for (const auto& m : markers) all.push_back(m.quad);
  for (const auto& v : vehicles) {
    const auto f = v.faces(t);
    all.insert(all.end(), f.begin(), f.end());
  }
  return all;
}

bool parseLevel(const std::string& text, Level& level) {
  const char* names[] = {"none", "low", "mid", "high"};
  for (int i = 0; i < 4; ++i)
    if (text == names[i]) {
      level = static_cast<Level>(i);
      return true;
    }
  return false;
}

const char* toString(Level level) {
  const char* names[] = {"none", "low", "mid", "high"};
  return names[static_cast<int>(level)];
}

bool parseRoute(const std::string& text, Route& route) {
  if (text == "default")
    route = Route::kDefault;
  else if (text == "block")
    route = Route::kBlock;
  else
    return false;
  return true;
}

const char* toString(Route route) { return route == Route::kBlock ? "block" : "default"; }

World buildWorld(const SceneOptions& options, const TextureBank& textures) {
  if (options.route == Route::kBlock && options.scene != "city")
    throw std::invalid_argument("the block route is a lap of a city block (scene city)");
  if (options.scene == "city") return buildCity(options, textures);
  if (options.scene == "parking_lot") return buildParkingLot(options, textures);
  throw std::invalid_argument("unknown scene '" + options.scene + "' (expected city or parking_lot)");
}

}  // namespace idyvins::sim
