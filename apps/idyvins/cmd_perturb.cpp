// `idyvins perturb DATASET OUT --fault KIND`: a copy of a EuRoC folder with one fault a robot
// meets (sensor dropouts, time jumps, bad images, IMU spikes), to reproduce how idyvins handles
// it. Unchanged files are hard links to the original's (no space, never written through).

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>

#include "commands.h"
#include "config/config.h"
#include "core/error.h"
#include "io/euroc_dataset.h"
#include "io/output_folder.h"

namespace idyvins::app {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kFaults = {
    "imu-gap",   "silence", "frame-drop", "time-jump", "desync",    "duplicate-stamps", "black",
    "saturated", "frozen",  "corrupt",    "salt",      "imu-spike", "time-offset",      "extrinsic"};

struct PerturbArgs {
  std::string dataset, out, fault;
  double at_s = 4.0, duration_s = 0.5, magnitude = 0;  ///< checkedArgs: --magnitude or the fault's default
  std::optional<double> magnitude_given;               ///< --magnitude
  int count = 1;
  /// extrinsic: the config whose body_T_cam0/1 are perturbed (its folder copied into OUT/config),
  /// the rotation (degrees, about a fixed tilted axis) and translation (cm, along a fixed tilted
  /// direction) of the error, and which camera: 0, 1 or rig (both, their stereo pose kept).
  std::string config, camera = "rig";
  double rotation_deg = 2.0, translation_cm = 2.0;
};

/// A data.csv: its comment lines, and its rows split at commas (field 0 the stamp).
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  static TimeNs stamp(const std::vector<std::string>& row) { return std::stoll(row[0]); }
};

Csv readCsv(const fs::path& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path.string(), "cannot read");
  Csv csv;
  for (std::string line; std::getline(f, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (line[0] == '#') {
      csv.header.push_back(line);
      continue;
    }
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string field; std::getline(ss, field, ',');) fields.push_back(field);
    csv.rows.push_back(fields);
  }
  return csv;
}

/// Replaces a (hard-linked) file by a new one: the original is never written through the link.
void writeCsv(const fs::path& path, const Csv& csv) {
  fs::remove(path);
  std::ofstream f(path);
  for (const auto& h : csv.header) f << h << '\n';
  for (const auto& r : csv.rows) {
    for (std::size_t i = 0; i < r.size(); ++i) f << (i ? "," : "") << r[i];
    f << '\n';
  }
  if (!f) throw InputError(path.string(), "cannot write");
}

/// Edits one data.csv in place (its rows, in order); a missing file is left alone.
void editCsv(const fs::path& path, const std::function<void(Csv&)>& edit) {
  if (!fs::exists(path)) return;
  Csv csv = readCsv(path);
  edit(csv);
  writeCsv(path, csv);
}

void dropRows(Csv& csv, const std::function<bool(TimeNs)>& drop) {
  std::vector<std::vector<std::string>> kept;
  for (auto& r : csv.rows)
    if (!drop(Csv::stamp(r))) kept.push_back(std::move(r));
  csv.rows = std::move(kept);
}

void shiftRows(Csv& csv, const std::function<bool(TimeNs)>& which, TimeNs by) {
  for (auto& r : csv.rows)
    if (which(Csv::stamp(r))) r[0] = std::to_string(Csv::stamp(r) + by);
}

/// Rewrites the images of cam0 and cam1 whose stamps `which` selects.
void editImages(const fs::path& mav0, const std::function<bool(TimeNs)>& which,
                const std::function<void(const fs::path&, int cam)>& edit) {
  for (int cam = 0; cam < 2; ++cam) {
    const fs::path dir = mav0 / ("cam" + std::to_string(cam));
    if (!fs::exists(dir / "data.csv")) continue;
    for (const auto& r : readCsv(dir / "data.csv").rows)
      if (r.size() >= 2 && which(Csv::stamp(r)) && fs::exists(dir / "data" / r[1]))  // EuRoC lists some absent images
        edit(dir / "data" / r[1], cam);
  }
}

void replaceImage(const fs::path& path, const cv::Mat& image) {
  fs::remove(path);
  if (!cv::imwrite(path.string(), image)) throw InputError(path.string(), "cannot write image");
}

void applyImageFault(const PerturbArgs& a, const fs::path& mav0, const std::function<bool(TimeNs)>& in_window) {
  std::optional<cv::Mat> frozen[2];
  editImages(mav0, in_window, [&](const fs::path& p, int cam) {
    if (a.fault == "corrupt") {  // the PNG cut in half, as a write interrupted mid-file
      const auto size = fs::file_size(p);
      std::ifstream in(p, std::ios::binary);
      std::string bytes(size / 2, '\0');
      in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      in.close();
      fs::remove(p);
      std::ofstream(p, std::ios::binary) << bytes;
      return;
    }
    const cv::Mat img = cv::imread(p.string(), cv::IMREAD_UNCHANGED);
    if (img.empty()) throw InputError(p.string(), "cannot read image");
    if (a.fault == "black")
      replaceImage(p, cv::Mat::zeros(img.size(), img.type()));
    else if (a.fault == "saturated")
      replaceImage(p, cv::Mat(img.size(), img.type(), cv::Scalar::all(255)));
    else if (a.fault == "salt") {  // MAGNITUDE (default 10) % of the pixels black or white
      cv::Mat noisy = img.clone(), u(img.size(), CV_32F);
      std::uint64_t seed = 1469598103934665603ull + static_cast<std::uint64_t>(cam);  // FNV-1a of the name
      for (unsigned char ch : p.filename().string()) seed = (seed ^ ch) * 1099511628211ull;
      cv::RNG rng(seed);
      rng.fill(u, cv::RNG::UNIFORM, 0.0, 1.0);
      const double share = a.magnitude / 100.0;
      noisy.setTo(cv::Scalar::all(0), u < share / 2);
      noisy.setTo(cv::Scalar::all(255), (u >= share / 2) & (u < share));
      replaceImage(p, noisy);
    } else if (a.fault == "frozen") {  // the first image of the window, again and again
      if (!frozen[cam])
        frozen[cam] = img;
      else
        replaceImage(p, *frozen[cam]);
    }
  });
}

void applyFault(const PerturbArgs& a, const fs::path& mav0, TimeNs t0) {
  const TimeNs at = t0 + static_cast<TimeNs>(a.at_s * 1e9), end = at + static_cast<TimeNs>(a.duration_s * 1e9);
  const auto in_window = [&](TimeNs t) { return t >= at && t < end; };
  const auto from_at = [&](TimeNs t) { return t >= at; };
  const fs::path imu = mav0 / "imu0" / "data.csv", cam0 = mav0 / "cam0" / "data.csv", cam1 = mav0 / "cam1" / "data.csv";
  const auto cams = [&](const std::function<void(Csv&)>& edit) { editCsv(cam0, edit), editCsv(cam1, edit); };
  const std::string& f = a.fault;
  if (f == "imu-gap" || f == "silence") editCsv(imu, [&](Csv& c) { dropRows(c, in_window); });
  if (f == "silence") cams([&](Csv& c) { dropRows(c, in_window); });
  if (f == "frame-drop") {  // `count` frames from `at` on, both cameras
    cams([&](Csv& c) {
      int left = a.count;
      dropRows(c, [&](TimeNs t) { return t >= at && left-- > 0; });
    });
  }
  if (f == "time-jump") {
    const TimeNs by = static_cast<TimeNs>(a.magnitude * 1e9);
    for (const auto& p : {imu, cam0, cam1, mav0 / "state_groundtruth_estimate0" / "data.csv"})
      editCsv(p, [&](Csv& c) { shiftRows(c, from_at, by); });
  }
  if (f == "desync") editCsv(cam1, [&](Csv& c) { shiftRows(c, in_window, static_cast<TimeNs>(a.magnitude * 1e6)); });
  if (f == "time-offset")  // every image stamp MAGNITUDE ms early on the IMU clock: a config's td of MAGNITUDE is right
    cams([&](Csv& c) {
      shiftRows(
          c, [](TimeNs) { return true; }, -static_cast<TimeNs>(std::llround(a.magnitude * 1e6)));
    });
  if (f == "duplicate-stamps") {  // each frame of the window stamped like the one before it
    cams([&](Csv& c) {
      for (std::size_t i = 1; i < c.rows.size(); ++i)
        if (in_window(Csv::stamp(c.rows[i]))) c.rows[i][0] = c.rows[i - 1][0];
    });
  }
  if (f == "imu-spike") {  // `count` samples from `at` on with `magnitude` m/s^2 more on x
    editCsv(imu, [&](Csv& c) {
      int left = a.count;
      for (auto& r : c.rows)
        if (Csv::stamp(r) >= at && left-- > 0) r[4] = std::to_string(std::stod(r[4]) + a.magnitude);
    });
  }
  if (f == "black" || f == "saturated" || f == "frozen" || f == "corrupt" || f == "salt")
    applyImageFault(a, mav0, in_window);
}

/// What --magnitude means for a fault, and its default: each default does something visible.
struct Magnitude {
  const char* fault;
  double fallback;
  const char* unit;
};
constexpr Magnitude kMagnitudes[] = {{"time-jump", 0.5, "s"},
                                     {"desync", 5.0, "ms"},
                                     {"imu-spike", 98.0, "m/s^2"},
                                     {"salt", 10.0, "%"},
                                     {"time-offset", 30.0, "ms"}};

/// The arguments with the fault's magnitude filled in, checked against the dataset. Throws.
PerturbArgs checkedArgs(PerturbArgs a, const io::EurocDataset& ds) {
  const Magnitude* m = nullptr;
  for (const Magnitude& k : kMagnitudes)
    if (a.fault == k.fault) m = &k;
  const bool given = a.magnitude_given.has_value();
  if (!m && given) throw CLI::ValidationError("--magnitude", "fault " + a.fault + " has no magnitude");
  if (m) a.magnitude = given ? *a.magnitude_given : m->fallback;
  if (m && (!std::isfinite(a.magnitude) || a.magnitude == 0))
    throw CLI::ValidationError("--magnitude", std::string("expected a finite, non-zero value (") + m->unit + ")");
  if (m && a.fault == std::string("salt") && !(a.magnitude > 0 && a.magnitude <= 100))
    throw CLI::ValidationError("--magnitude", "salt: expected a share of the pixels in (0, 100] %");
  if (m && std::string(m->unit) == "s" && std::abs(a.magnitude) > 1e6)
    throw CLI::ValidationError("--magnitude", "time-jump: expected at most 1e6 s");
  if (!m) a.magnitude = 0;
  if ((a.fault == "extrinsic") != !a.config.empty())
    throw CLI::ValidationError("--config", a.fault == "extrinsic" ? "extrinsic needs the config to perturb"
                                                                  : "only the extrinsic fault takes a config");
  if (a.fault == "extrinsic" && a.camera != "0" && a.camera != "1" && a.camera != "rig")
    throw CLI::ValidationError("--camera", "expected 0, 1 or rig, got '" + a.camera + "'");
  const double span_s = 1e-9 * static_cast<double>(ds.cam0.back().t_ns - ds.cam0.front().t_ns);
  if (a.at_s > span_s)
    throw CLI::ValidationError("--at", "expected a time within the sequence (0 to " + std::to_string(span_s) +
                                           " s from the first cam0 image), got " + std::to_string(a.at_s));
  return a;
}

/// `text` with the data of the opencv-matrix under `key` replaced by `T` (row-major, 4 x 4).
std::string withMatrix(const std::string& text, const std::string& key, const Eigen::Isometry3d& T,
                       const std::string& path) {
  const std::size_t k = text.find("\n" + key + ":");
  const std::size_t open = k == std::string::npos ? k : text.find('[', text.find("data:", k));
  const std::size_t close = open == std::string::npos ? open : text.find(']', open);
  if (close == std::string::npos) throw InputError(path, "no " + key + " matrix (data: [...]) to perturb");
  std::string data;
  char buf[40];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof buf, "%.12g", T.matrix()(r, c));
      data += std::string(r || c ? ", " : "") + buf;
    }
  return text.substr(0, open + 1) + data + text.substr(close);
}

/// extrinsic: OUT/config, a copy of the config's folder with body_T_cam0/1 moved against the IMU by
/// the error; returns the error (T_err: true body_T_cam = T_err^-1 * written).
Eigen::Isometry3d perturbExtrinsics(const PerturbArgs& a) {
  const Config cfg = loadConfig(a.config);
  const fs::path src = fs::path(a.config).parent_path(), dst = fs::path(a.out) / "config";
  fs::create_directories(dst);
  for (const auto& e : fs::directory_iterator(src.empty() ? fs::path(".") : src))
    if (e.is_regular_file()) {  // a file already there is a hard link into the source: replaced, never written through
      fs::remove(dst / e.path().filename());
      fs::copy_file(e.path(), dst / e.path().filename());
    }
  Eigen::Isometry3d T_err = Eigen::Isometry3d::Identity();
  T_err.linear() = Eigen::AngleAxisd(a.rotation_deg * M_PI / 180, Eigen::Vector3d(1, -1, 1).normalized()).matrix();
  T_err.translation() = 0.01 * a.translation_cm * Eigen::Vector3d(1, 1, -1).normalized();
  const fs::path out_cfg = dst / fs::path(a.config).filename();
  std::ifstream in(out_cfg);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  for (std::size_t i = 0; i < cfg.T_b_c.size(); ++i)
    if (a.camera == "rig" || a.camera == std::to_string(i))
      text = withMatrix(text, "body_T_cam" + std::to_string(i), T_err * cfg.T_b_c[i], a.config);
  fs::remove(out_cfg);
  std::ofstream(out_cfg) << text;
  loadConfig(out_cfg.string());  // what was written reads back
  return T_err;
}

int runPerturb(const PerturbArgs& args) {
  const io::EurocDataset ds = io::readEurocDataset(args.dataset);  // validated before anything is written
  if (ds.cam0.empty()) throw InputError(args.dataset, "no cam0 images");
  const PerturbArgs a = checkedArgs(args, ds);
  io::checkApartFromInputs(a.out, {a.dataset});
  if (fs::exists(fs::symlink_status(a.out))) throw InputError(a.out, "already exists; perturb writes a new folder");
  fs::copy(a.dataset, a.out, fs::copy_options::recursive | fs::copy_options::create_hard_links);
  const fs::path mav0 = fs::path(ds.root).filename() == "mav0" ? fs::path(a.out) / "mav0" : fs::path(a.out);
  applyFault(a, mav0, ds.cam0.front().t_ns);
  nlohmann::json what = {{"source", a.dataset},        {"fault", a.fault}, {"at_s", a.at_s},
                         {"duration_s", a.duration_s}, {"count", a.count}, {"magnitude", a.magnitude}};
  if (a.fault == "time-offset") what["td_true_ms"] = a.magnitude;
  if (a.fault == "extrinsic") {
    perturbExtrinsics(a);
    what["config"] = (fs::path(a.out) / "config" / fs::path(a.config).filename()).string();
    what["camera"] = a.camera;
    what["rotation_deg"] = a.rotation_deg;
    what["translation_cm"] = a.translation_cm;
  }
  std::ofstream(fs::path(a.out) / "perturb.json") << what.dump(1) << '\n';
  std::printf("wrote %s: %s at %.3f s into the sequence\n", a.out.c_str(), a.fault.c_str(), a.at_s);
  return kOk;
}

}  // namespace

void registerPerturb(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<PerturbArgs>();
  CLI::App* cmd = app.add_subcommand(
      "perturb",
      "Copy a EuRoC folder with one fault, to reproduce how idyvins handles it (unchanged files are\n"
      "hard links). Times are seconds from the first cam0 image. Faults: imu-gap and silence (IMU, or\n"
      "IMU and cameras, lose [at, at+duration)); frame-drop (COUNT stereo frames from at: 1 single, more\n"
      "a burst); time-jump (every stamp from at on moves by MAGNITUDE s, cameras, IMU and ground truth;\n"
      "negative: backwards); desync (cam1 stamps of the window moved by MAGNITUDE ms; beyond 1 ms the\n"
      "frames lose their partner); duplicate-stamps (frames of the window stamped like the one before);\n"
      "black, saturated, frozen (images of the window), salt (MAGNITUDE %, default 10, of their pixels\n"
      "black or white), corrupt (their PNG files cut in half); imu-spike (COUNT samples from at get MAGNITUDE m/s^2 "
      "more on x);\n"
      "time-offset (every image stamp MAGNITUDE ms, default 30, earlier: the config's td should be MAGNITUDE);\n"
      "extrinsic (--config CFG: OUT/config/ is CFG's folder with body_T_cam0/1 off by --rotation-deg about\n"
      "(1,-1,1) and --translation-cm along (1,1,-1), for --camera 0, 1 or rig; the data unchanged).\n"
      "Writes OUT/perturb.json with the fault.");
  cmd->add_option("dataset", a->dataset, "EuRoC folder")->required();
  cmd->add_option("out", a->out, "new folder")->required();
  cmd->add_option("--fault", a->fault, "the fault")->required()->check(CLI::IsMember(kFaults));
  cmd->add_option("--at", a->at_s, "s from the first cam0 image (default 4)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--duration", a->duration_s, "s (default 0.5)")->check(CLI::PositiveNumber);
  cmd->add_option("--count", a->count, "frames or samples (default 1)")->check(CLI::PositiveNumber);
  cmd->add_option("--magnitude", a->magnitude_given,
                  "time-jump: s (default 0.5); desync: ms (default 5); imu-spike: m/s^2 (default 98, 10 g);\n"
                  "salt: % (default 10); time-offset: ms (default 30); finite and non-zero");
  cmd->add_option("--config", a->config, "extrinsic: the config to perturb");
  cmd->add_option("--rotation-deg", a->rotation_deg, "extrinsic: rotation error, degrees (default 2)");
  cmd->add_option("--translation-cm", a->translation_cm, "extrinsic: translation error, cm (default 2)");
  cmd->add_option("--camera", a->camera, "extrinsic: 0, 1 or rig (default: both, the stereo pose kept)");
  cmd->callback([a, &exit_code] { exit_code = runPerturb(*a); });
}

}  // namespace idyvins::app
