#include "map/map_io.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/checksum.h"
#include "core/error.h"

namespace idyvins::map {
namespace {

namespace fs = std::filesystem;
constexpr char kMagic[8] = {'I', 'D', 'Y', 'M', 'A', 'P', 'K', 'F'};
constexpr const char* kFormat = "idyvins-map";

/// Appends little-endian values (the machines idyvins builds for are little-endian).
class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    bytes_.append(p, sizeof(T));
  }
  void put(const Eigen::Vector3d& v) { put(v.x()), put(v.y()), put(v.z()); }
  void put(const Eigen::Vector2d& v) { put(v.x()), put(v.y()); }
  void put(const Eigen::Quaterniond& q) { put(q.w()), put(q.x()), put(q.y()), put(q.z()); }
  void put(const Descriptor& d) { bytes_.append(reinterpret_cast<const char*>(d.data()), d.size()); }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

/// Reads what Writer wrote; any read past the end throws InputError naming the offset.
class Reader {
 public:
  Reader(const std::string& bytes, const std::string& path) : bytes_(bytes), path_(path) {}
  template <typename T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  Eigen::Vector3d vec3() {
    const double x = get<double>(), y = get<double>();
    return {x, y, get<double>()};
  }
  Eigen::Vector2d vec2() {
    const double x = get<double>();
    return {x, get<double>()};
  }
  Eigen::Quaterniond quat() {
    const double w = get<double>(), x = get<double>(), y = get<double>(), z = get<double>();
    return Eigen::Quaterniond(w, x, y, z);
  }
  Descriptor descriptor() {
    need(32);
    Descriptor d;
    std::memcpy(d.data(), bytes_.data() + pos_, 32);
    pos_ += 32;
    return d;
  }
  /// A count of items of at least `item_bytes` each that must fit in what is left.
  std::uint32_t count(std::size_t item_bytes) {
    const auto n = get<std::uint32_t>();
    if (static_cast<std::uint64_t>(n) * item_bytes > bytes_.size() - pos_)
      fail("count " + std::to_string(n) + " does not fit");
    return n;
  }
  bool atEnd() const { return pos_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_, "byte " + std::to_string(pos_) + ": " + what + " (damaged map?)");
  }

 private:
  void need(std::size_t n) const {
    if (n > bytes_.size() - pos_) fail("file ends early");
  }
  const std::string& bytes_;
  std::string path_;
  std::size_t pos_ = 0;
};

void writeKeyframe(Writer& w, const Keyframe& k, const PoseGraphNode& n) {
  w.put(k.id);
  w.put(static_cast<std::int64_t>(k.t_ns));
  w.put(k.p_w_b);
  w.put(k.q_w_b);
  w.put(n.p);
  w.put(n.yaw);
  w.put(static_cast<std::uint8_t>(n.fixed));
  w.put(static_cast<std::uint32_t>(k.descriptors.size()));
  for (const Descriptor& d : k.descriptors) w.put(d);
  w.put(static_cast<std::uint32_t>(k.landmarks.size()));
  for (const KeyframeLandmark& l : k.landmarks) {
    w.put(l.id);
    w.put(l.p_w);
    w.put(l.xy);
    w.put(l.descriptor);
  }
}

void readKeyframe(Reader& r, std::uint32_t index, SavedMap& map) {
  Keyframe k;
  PoseGraphNode n;
  k.id = r.get<std::uint32_t>();
  if (k.id != index) r.fail("keyframe id " + std::to_string(k.id) + " where " + std::to_string(index) + " belongs");
  k.t_ns = n.t_ns = r.get<std::int64_t>();
  k.p_w_b = n.p_odom = r.vec3();
  k.q_w_b = n.q_odom = r.quat();
  if (!k.p_w_b.allFinite() || std::abs(k.q_w_b.norm() - 1.0) > 1e-6) r.fail("keyframe pose not finite or not unit");
  n.p = r.vec3();
  n.yaw = r.get<double>();
  n.fixed = r.get<std::uint8_t>() != 0;
  const std::uint32_t nd = r.count(32);
  for (std::uint32_t i = 0; i < nd; ++i) k.descriptors.push_back(r.descriptor());
  const std::uint32_t nl = r.count(8 + 40 + 32);
  for (std::uint32_t i = 0; i < nl; ++i) {
    KeyframeLandmark l;
    l.id = r.get<std::uint64_t>();
    l.p_w = r.vec3();
    l.xy = r.vec2();
    l.descriptor = r.descriptor();
    k.landmarks.push_back(l);
  }
  map.keyframes.push_back(std::move(k));
  map.nodes.push_back(n);
}

void writeAtomically(const fs::path& path, const std::string& bytes) {
  const fs::path part = path.string() + ".part";
  {
    std::ofstream f(part, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!f) throw InputError(part.string(), "cannot write");
  }
  std::error_code ec;
  fs::rename(part, path, ec);
  if (ec) throw InputError(path.string(), "cannot rename " + part.string() + ": " + ec.message());
}

std::string readWhole(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string(), "missing or unreadable (not an idyvins map folder?)");
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

/// The loop edges of loops.csv; node indices below `nodes`.
std::vector<LoopEdge> readLoops(const std::string& path, std::uint32_t nodes) {
  std::istringstream in(readWhole(path));
  std::vector<LoopEdge> loops;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string f[6];
    int k = 0;
    while (k < 6 && std::getline(fields, f[k], ',')) ++k;
    double v[6];
    for (int i = 0; i < 6; ++i) {
      char* end = nullptr;
      v[i] = i < k ? std::strtod(f[i].c_str(), &end) : 0;
      if (i >= k || end == f[i].c_str() || *end != '\0' || !std::isfinite(v[i]))
        throw InputError(path, number, "expected from,to,dx,dy,dz,dyaw_rad (6 numbers)");
    }
    if (v[0] < 0 || v[1] < 0 || v[0] >= nodes || v[1] >= nodes || v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]))
      throw InputError(path, number, "keyframe index outside 0.." + std::to_string(nodes) + " - 1");
    loops.push_back({static_cast<std::size_t>(v[0]), static_cast<std::size_t>(v[1]),
                     RelativePose4{Eigen::Vector3d(v[2], v[3], v[4]), v[5]}});
  }
  return loops;
}

}  // namespace

void saveMap(const std::string& dir, const SavedMap& map) {
  if (map.keyframes.size() != map.nodes.size())
    throw std::invalid_argument("saveMap: one pose-graph node per keyframe");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir, "cannot create map folder: " + ec.message());
  Writer w;
  w.put(kMagic);
  w.put(static_cast<std::uint32_t>(kMapFormatVersion));
  w.put(static_cast<std::uint32_t>(map.keyframes.size()));
  std::size_t landmarks = 0;
  for (std::size_t i = 0; i < map.keyframes.size(); ++i) {
    writeKeyframe(w, map.keyframes[i], map.nodes[i]);
    landmarks += map.keyframes[i].landmarks.size();
  }
  std::ostringstream loops;
  loops << "# from,to,dx,dy,dz,dyaw_rad (4-DoF pose of `to` in `from`'s body frame)\n";
  loops.precision(17);
  for (const LoopEdge& l : map.loops)
    loops << l.from << ',' << l.to << ',' << l.measured.t_from_to.x() << ',' << l.measured.t_from_to.y() << ','
          << l.measured.t_from_to.z() << ',' << l.measured.dyaw << '\n';
  const nlohmann::json header = {{"format", kFormat},
                                 {"version", kMapFormatVersion},
                                 {"keyframes", map.keyframes.size()},
                                 {"landmarks", landmarks},
                                 {"loops", map.loops.size()},
                                 {"descriptor_bits", 256},
                                 {"keyframes_fnv1a64", std::to_string(fnv1a64(w.bytes()))},
                                 {"rig", map.rig}};
  writeAtomically(fs::path(dir) / "keyframes.bin", w.bytes());
  writeAtomically(fs::path(dir) / "loops.csv", loops.str());
  writeAtomically(fs::path(dir) / "map.json", header.dump(1) + "\n");  // last: its presence means complete
}

SavedMap loadMap(const std::string& dir) {
  const fs::path json_path = fs::path(dir) / "map.json";
  nlohmann::json header;
  try {
    header = nlohmann::json::parse(readWhole(json_path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(json_path.string(), std::string("not JSON: ") + e.what());
  }
  if (!header.is_object() || header.value("format", "") != kFormat)
    throw InputError(json_path.string(), "not an idyvins map (format is not \"idyvins-map\")");
  if (!header["version"].is_number_integer() || header["version"].get<int>() != kMapFormatVersion)
    throw InputError(json_path.string(), "map format version " + header["version"].dump() + ", this idyvins reads " +
                                             std::to_string(kMapFormatVersion));
  const fs::path bin_path = fs::path(dir) / "keyframes.bin";
  const std::string bytes = readWhole(bin_path);
  if (std::to_string(fnv1a64(bytes)) != header.value("keyframes_fnv1a64", ""))
    throw InputError(bin_path.string(), "checksum differs from map.json's (damaged or replaced)");
  Reader r(bytes, bin_path.string());
  for (char c : kMagic)
    if (r.get<char>() != c) r.fail("not an idyvins keyframe file");
  if (r.get<std::uint32_t>() != kMapFormatVersion) r.fail("format version differs from map.json's");
  SavedMap map;
  const std::uint32_t n = r.count(100);
  for (std::uint32_t i = 0; i < n; ++i) readKeyframe(r, i, map);
  if (!r.atEnd()) r.fail("bytes after the last keyframe");
  map.loops = readLoops((fs::path(dir) / "loops.csv").string(), n);
  if (header.contains("rig")) {
    if (!header["rig"].is_string()) throw InputError(json_path.string(), "\"rig\" is not a string");
    map.rig = header["rig"].get<std::string>();
  }
  return map;
}

}  // namespace idyvins::map
