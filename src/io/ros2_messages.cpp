#include "io/ros2_messages.h"

#include <algorithm>
#include <map>

#include "io/cdr.h"

namespace idyvins::io {
namespace {

/// std_msgs/Header's stamp (builtin_interfaces/Time) in ns; frame_id skipped.
TimeNs header(CdrReader& r) {
  const std::int64_t sec = r.i32();
  const std::uint32_t nsec = r.u32();
  r.string();
  if (nsec >= 1'000'000'000u) throw CdrError("header stamp nanosec " + std::to_string(nsec) + " is not below 1e9");
  return sec * 1'000'000'000 + nsec;
}

Eigen::Vector3d vector3(CdrReader& r) {
  const double x = r.f64(), y = r.f64(), z = r.f64();
  return {x, y, z};
}

/// geometry_msgs/Quaternion: x, y, z, w on the wire.
Eigen::Quaterniond quaternion(CdrReader& r) {
  const double x = r.f64(), y = r.f64(), z = r.f64(), w = r.f64();
  return Eigen::Quaterniond(w, x, y, z);
}

void writeHeader(CdrWriter& w, TimeNs t, const std::string& frame_id) {
  w.i32(static_cast<std::int32_t>(t / 1'000'000'000));
  w.u32(static_cast<std::uint32_t>(t % 1'000'000'000));
  w.string(frame_id);
}

template <typename F>
auto decoded(const char* type, F f) -> decltype(f()) {
  try {
    return f();
  } catch (const CdrError& e) {
    throw BagMessageError(std::string("cannot be read as ") + type + ": " + e.what());
  }
}

const std::map<std::string, std::string>& definitions() {
  static const std::map<std::string, std::string> defs = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"},
      {"geometry_msgs/PoseWithCovariance", "geometry_msgs/Pose pose\nfloat64[36] covariance\n"},
      {"geometry_msgs/Twist", "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n"},
      {"geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist twist\nfloat64[36] covariance\n"},
      {"sensor_msgs/Image",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\n"
       "uint8[] data\n"},
      {"sensor_msgs/Imu",
       "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
       "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
       "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"},
      {"nav_msgs/Odometry",
       "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
       "geometry_msgs/TwistWithCovariance twist\n"},
  };
  return defs;
}

/// The types `text` names (its fields' types that have a definition), in order of first use.
void dependencies(const std::string& type, std::vector<std::string>& out) {
  const std::string& text = definitions().at(type);
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t eol = text.find('\n', pos);
    std::string field_type = text.substr(pos, text.find(' ', pos) - pos);
    pos = eol + 1;
    if (const auto b = field_type.find('['); b != std::string::npos) field_type.resize(b);
    if (!definitions().count(field_type)) continue;
    if (std::find(out.begin(), out.end(), field_type) != out.end()) continue;
    out.push_back(field_type);
    dependencies(field_type, out);
  }
}

}  // namespace

BagImage decodeRos2Image(const std::uint8_t* cdr, std::size_t size, BagMessageKind kind) {
  const bool compressed = kind == BagMessageKind::kCompressedImage;
  return decoded(kindName(kind), [&] {
    CdrReader r(cdr, size);
    BagImage m;
    m.compressed = compressed;
    m.stamp_ns = header(r);
    if (compressed) {
      m.format = r.string();
    } else {
      m.height = r.u32();
      m.width = r.u32();
      m.encoding = r.string();
      if (r.u8() != 0 && m.encoding != "mono8") throw CdrError("big-endian pixel data is not read");
      m.step = r.u32();
    }
    m.data = r.bytes(m.size);
    return m;
  });
}

ImuSample decodeRos2Imu(const std::uint8_t* cdr, std::size_t size) {
  return decoded("sensor_msgs/Imu", [&] {
    CdrReader r(cdr, size);
    ImuSample s;
    s.t_ns = header(r);
    quaternion(r);
    r.skipF64(9);
    s.gyr_b = vector3(r);
    r.skipF64(9);
    s.acc_b = vector3(r);
    r.skipF64(9);
    return s;
  });
}

BagPose decodeRos2Pose(const std::uint8_t* cdr, std::size_t size, BagMessageKind kind) {
  return decoded(kindName(kind), [&] {
    CdrReader r(cdr, size);
    BagPose p;
    p.stamp_ns = header(r);
    if (kind == BagMessageKind::kOdometry || kind == BagMessageKind::kTransform) r.string();  // child_frame_id
    p.p = vector3(r);                                                                         // Point and Vector3 alike
    if (kind != BagMessageKind::kPoint) p.q = quaternion(r);
    return p;
  });
}

std::vector<std::uint8_t> encodeRos2Image(TimeNs t, const std::string& frame_id, std::uint32_t width,
                                          std::uint32_t height, const std::string& encoding, std::uint32_t step,
                                          const std::uint8_t* data) {
  CdrWriter w;
  writeHeader(w, t, frame_id);
  w.u32(height);
  w.u32(width);
  w.string(encoding);
  w.u8(0);
  w.u32(step);
  w.bytes(data, static_cast<std::size_t>(step) * height);
  return w.data();
}

std::vector<std::uint8_t> encodeRos2Imu(const ImuSample& s, const std::string& frame_id) {
  CdrWriter w;
  writeHeader(w, s.t_ns, frame_id);
  for (double v : {0.0, 0.0, 0.0, 1.0}) w.f64(v);
  for (int i = 0; i < 9; ++i) w.f64(i == 0 ? -1.0 : 0.0);
  for (int k = 0; k < 3; ++k) w.f64(s.gyr_b[k]);
  for (int i = 0; i < 9; ++i) w.f64(0.0);
  for (int k = 0; k < 3; ++k) w.f64(s.acc_b[k]);
  for (int i = 0; i < 9; ++i) w.f64(0.0);
  return w.data();
}

std::vector<std::uint8_t> encodeRos2Odometry(TimeNs t, const std::string& frame_id, const std::string& child_frame_id,
                                             const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  CdrWriter w;
  writeHeader(w, t, frame_id);
  w.string(child_frame_id);
  for (int k = 0; k < 3; ++k) w.f64(p[k]);
  for (double v : {q.x(), q.y(), q.z(), q.w()}) w.f64(v);
  for (int i = 0; i < 36 + 6 + 36; ++i) w.f64(0.0);  // pose covariance, twist, twist covariance
  return w.data();
}

std::string ros2MessageDefinition(const std::string& type) {
  std::string key = type;
  if (const auto m = key.find("/msg/"); m != std::string::npos) key.erase(m, 4);
  std::string out = definitions().at(key);
  std::vector<std::string> deps;
  dependencies(key, deps);
  for (const std::string& d : deps) out += std::string(80, '=') + "\nMSG: " + d + "\n" + definitions().at(d);
  return out;
}

}  // namespace idyvins::io
