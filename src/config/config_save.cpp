// Writing configs: saveConfig and the camera files, describe (what `info` prints) and the
// Markdown key table (docs/cli.md).

#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "camera/camera_model.h"
#include "config/config.h"
#include "config/modes.h"
#include "core/error.h"

namespace idyvins {

namespace {

namespace fs = std::filesystem;

/// The shortest decimal text that reads back as the same double.
std::string number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

std::string matrixYaml(const Eigen::Matrix4d& m) {
  std::string s = " !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [";
  for (int i = 0; i < 16; ++i) s += (i ? ", " : "") + number(m(i / 4, i % 4));
  return s + "]\n";
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw InputError(path, "cannot write file");
}

/// "key: value" lines of every declared key under "# section" lines; strings quoted. Given
/// the defaults' values (`skip`), a key that is not required and has its default value is left
/// out, and so is a section left empty.
class KeyPrinter final : public ParamVisitor {
 public:
  explicit KeyPrinter(std::string indent, const std::map<std::string, std::string>* skip = nullptr)
      : indent_(std::move(indent)), skip_(skip) {}
  void section(const char* title) override { pending_section_ = "\n" + indent_ + "# " + title + "\n"; }
  void param(const ParamKey& k, double& v) override { add(k, number(v)); }
  void param(const ParamKey& k, int& v) override { add(k, std::to_string(v)); }
  void param(const ParamKey& k, bool& v) override { add(k, v ? "1" : "0"); }
  void param(const ParamKey& k, std::string& v) override { add(k, "\"" + v + "\""); }
  std::string text;
  std::map<std::string, std::string> values;  ///< key -> its text, every key visited

 private:
  void add(const ParamKey& k, const std::string& value) {
    values[k.name] = value;
    if (skip_ && !k.required) {
      const auto it = skip_->find(k.name);
      if (it != skip_->end() && it->second == value) return;
    }
    text += pending_section_ + indent_ + k.name + ": " + value + "\n";
    pending_section_.clear();
  }
  std::string indent_;
  const std::map<std::string, std::string>* skip_;
  std::string pending_section_;
};

/// Every declared key of `c` as KeyPrinter lines (with `skip`: only the ones that differ).
std::string keyLines(const Config& c, const std::string& indent,
                     const std::map<std::string, std::string>* skip = nullptr) {
  Config copy = c;  // visitors take references; printing changes nothing
  KeyPrinter printer(indent, skip);
  declareParams(printer, copy);
  return printer.text;
}

/// The comment line of a config saved with SavedKeys::kChanged.
constexpr const char* kChangedKeysLine = "# Keys not written here have their defaults (docs/cli.md, Config keys)";

/// Every key's text at its default value.
std::map<std::string, std::string> defaultValues() {
  Config c;
  KeyPrinter printer("");
  declareParams(printer, c);
  return printer.values;
}

/// Markdown tables of every key: default and unit, one table per section.
class KeyTable final : public ParamVisitor {
 public:
  void section(const char* title) override {
    text += std::string(text.empty() ? "" : "\n") + "**" + title +
            "**\n\n| key | default | unit and meaning |\n| --- | --- | --- |\n";
  }
  void param(const ParamKey& k, double& v) override { add(k, number(v)); }
  void param(const ParamKey& k, int& v) override { add(k, std::to_string(v)); }
  void param(const ParamKey& k, bool& v) override { add(k, v ? "1" : "0"); }
  void param(const ParamKey& k, std::string& v) override { add(k, v.empty() ? "(none)" : "`" + v + "`"); }
  std::string text;

 private:
  void add(const ParamKey& k, const std::string& value) {
    text += "| `" + std::string(k.name) + "` | " + (k.required ? "required" : value) + " | " + k.unit + " |\n";
  }
};

}  // namespace

std::string describe(const Config& c) {
  std::ostringstream o;
  o << "config: " << c.path << "\n";
  o << "  imu: " << (c.use_imu ? 1 : 0) << ", num_of_cam: " << c.num_cam << ", image_width: " << c.image_width
    << ", image_height: " << c.image_height << "\n";
  for (std::size_t i = 0; i < c.cams.size(); ++i) {
    const auto& k = c.cams[i];
    o << "  cam" << i << "_calib: " << c.cam_paths[i] << " (" << camera::toString(k.type) << " f=(" << k.fx << ", "
      << k.fy << ") c=(" << k.cx << ", " << k.cy << ") dist=[" << k.dist[0] << ", " << k.dist[1] << ", " << k.dist[2]
      << ", " << k.dist[3] << "])\n";
    const Eigen::Vector3d t = c.T_b_c[i].translation();
    o << "  body_T_cam" << i << ": t = [" << t.transpose() << "] m\n";
  }
  if (c.cams.size() == 2) {
    const Eigen::Isometry3d T_c0_c1 = c.T_b_c[0].inverse() * c.T_b_c[1];
    o << "  stereo baseline: " << T_c0_c1.translation().norm() << " m\n";
  }
  o << keyLines(c, "  ").substr(1);
  o << "  (max_solver_time "
    << (c.estimator.time_limited ? "applied: solver_time_limit 1, results depend on load"
                                 : "not applied: deterministic")
    << ")\n";
  return o.str();
}

std::string keyTable() {
  Config c;
  KeyTable table;
  declareParams(table, c);
  return table.text;
}

void saveCameraFile(const camera::CameraParams& k, const std::string& path) {
  std::string s = "%YAML:1.0\n---\n";
  s += std::string("model_type: ") + camera::toString(k.type) + "\n";
  s += "camera_name: " + (k.name.empty() ? std::string("camera") : k.name) + "\n";
  s += "image_width: " + std::to_string(k.width) + "\nimage_height: " + std::to_string(k.height) + "\n";
  const char* dk[] = {"k1", "k2", "p1", "p2"};
  const char* kb[] = {"k2", "k3", "k4", "k5"};
  switch (k.type) {
    case camera::ModelType::kPinhole:
    case camera::ModelType::kMei:
      if (k.type == camera::ModelType::kMei) s += "mirror_parameters:\n   xi: " + number(k.xi) + "\n";
      s += "distortion_parameters:\n";
      for (int i = 0; i < 4; ++i) s += std::string("   ") + dk[i] + ": " + number(k.dist[i]) + "\n";
      s += k.type == camera::ModelType::kMei
               ? "projection_parameters:\n   gamma1: " + number(k.fx) + "\n   gamma2: " + number(k.fy)
               : "projection_parameters:\n   fx: " + number(k.fx) + "\n   fy: " + number(k.fy);
      s += std::string(k.type == camera::ModelType::kMei ? "\n   u0: " : "\n   cx: ") + number(k.cx) +
           (k.type == camera::ModelType::kMei ? "\n   v0: " : "\n   cy: ") + number(k.cy) + "\n";
      break;
    case camera::ModelType::kKannalaBrandt:
      s += "projection_parameters:\n";
      for (int i = 0; i < 4; ++i) s += std::string("   ") + kb[i] + ": " + number(k.dist[i]) + "\n";
      s += "   mu: " + number(k.fx) + "\n   mv: " + number(k.fy) + "\n   u0: " + number(k.cx) +
           "\n   v0: " + number(k.cy) + "\n";
      break;
  }
  writeFile(path, s);
}

void saveConfig(const Config& c, const std::string& path, SavedKeys keys) {
  const fs::path folder = fs::path(path).parent_path();
  std::string s = "%YAML:1.0\n# idyvins config (VINS-Fusion format)\n";
  s += "imu: " + std::to_string(c.use_imu ? 1 : 0) + "\nnum_of_cam: " + std::to_string(c.num_cam) + "\n";
  for (int i = 0; i < c.num_cam; ++i) {
    const std::string name = i < static_cast<int>(c.cam_paths.size()) && !c.cam_paths[i].empty()
                                 ? fs::path(c.cam_paths[i]).filename().string()
                                 : "cam" + std::to_string(i) + ".yaml";
    saveCameraFile(c.cams.at(i), (folder / name).string());
    s += "cam" + std::to_string(i) + "_calib: \"" + name + "\"\n";
  }
  s += "image_width: " + std::to_string(c.image_width) + "\nimage_height: " + std::to_string(c.image_height) + "\n";
  for (int i = 0; i < c.num_cam; ++i) s += "body_T_cam" + std::to_string(i) + ":" + matrixYaml(c.T_b_c.at(i).matrix());
  if (keys == SavedKeys::kChanged) {
    const std::map<std::string, std::string> defaults = defaultValues();
    s += std::string(kChangedKeysLine) + "\n" + keyLines(c, "", &defaults);
  } else {
    s += keyLines(c, "");
  }
  writeFile(path, s);
}

bool savedWithChangedKeysOnly(const std::string& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (line == kChangedKeysLine) return true;
  return false;
}

}  // namespace idyvins
