#include "io/euroc_dataset.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "io/csv.h"
#include "io/png_gray.h"

namespace fs = std::filesystem;

namespace idyvins::io {
namespace {

std::vector<TimeNs> stampsOf(const std::vector<TableRow>& rows, const std::string& path) {
  std::vector<TimeNs> stamps;
  stamps.reserve(rows.size());
  for (const auto& r : rows) stamps.push_back(parseTimeNs(r.fields[0], path, r.line, 1));
  return stamps;
}

std::vector<int> linesOf(const std::vector<TableRow>& rows) {
  std::vector<int> lines;
  lines.reserve(rows.size());
  for (const auto& r : rows) lines.push_back(r.line);
  return lines;
}

Eigen::Vector3d vec3(const TableRow& r, int first, const std::string& path) {
  return {parseFinite(r.fields[first], path, r.line, first + 1),
          parseFinite(r.fields[first + 1], path, r.line, first + 2),
          parseFinite(r.fields[first + 2], path, r.line, first + 3)};
}

std::string resolveMav0(const std::string& dir) {
  const fs::path p(dir);
  if (fs::exists(p) && !fs::is_directory(p))
    throw InputError(dir, "is a file, but neither a ROS1 bag (no '#ROSBAG V2.0' header) nor a EuRoC folder");
  if (!fs::is_directory(p)) throw InputError(dir, "dataset folder does not exist");
  if (fs::is_directory(p / "mav0")) return (p / "mav0").string();
  if (fs::is_directory(p / "cam0")) return p.string();
  throw InputError(dir, "not a EuRoC ASL folder (expected a mav0/ folder with cam0/ and imu0/)");
}

}  // namespace

std::vector<ImageRecord> readImageList(const std::string& csv_path, const std::string& data_dir) {
  const auto rows = readTable(csv_path, {',', 2, 2});
  std::vector<ImageRecord> records;
  records.reserve(rows.size());
  for (const auto& r : rows) {
    ImageRecord rec;
    rec.t_ns = parseTimeNs(r.fields[0], csv_path, r.line, 1);
    if (r.fields[1].empty()) throw InputError(csv_path, r.line, "column 2: expected a file name");
    rec.path = (fs::path(data_dir) / r.fields[1]).string();
    rec.csv_line = r.line;
    rec.exists = fs::is_regular_file(rec.path);
    records.push_back(std::move(rec));
  }
  std::vector<TimeNs> stamps;
  for (const auto& rec : records) stamps.push_back(rec.t_ns);
  checkIncreasing(stamps, linesOf(rows), csv_path);
  return records;
}

std::vector<ImuSample> readImuCsv(const std::string& path) {
  const auto rows = readTable(path, {',', 7, 7});
  const auto stamps = stampsOf(rows, path);
  checkIncreasing(stamps, linesOf(rows), path);
  std::vector<ImuSample> imu(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    imu[i].t_ns = stamps[i];
    imu[i].gyr_b = vec3(rows[i], 1, path);
    imu[i].acc_b = vec3(rows[i], 4, path);
  }
  return imu;
}

std::vector<GroundTruthState> readGroundTruthCsv(const std::string& path) {
  const auto rows = readTable(path, {',', 17, 17});
  const auto stamps = stampsOf(rows, path);
  checkIncreasing(stamps, linesOf(rows), path);
  std::vector<GroundTruthState> gt(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    auto& s = gt[i];
    s.t_ns = stamps[i];
    s.p_w_b = vec3(r, 1, path);
    const double qw = parseFinite(r.fields[4], path, r.line, 5);
    const Eigen::Vector3d qxyz = vec3(r, 5, path);
    s.q_w_b = Eigen::Quaterniond(qw, qxyz.x(), qxyz.y(), qxyz.z());
    const double norm = s.q_w_b.norm();
    if (std::abs(norm - 1.0) > 1e-2) {
      throw InputError(path, r.line,
                       "columns 5-8: expected a unit quaternion w x y z, norm is " + std::to_string(norm));
    }
    s.q_w_b.normalize();
    s.v_w = vec3(r, 8, path);
    s.bg = vec3(r, 11, path);
    s.ba = vec3(r, 14, path);
  }
  return gt;
}

void pairByTime(const std::vector<ImageRecord>& cam0, const std::vector<ImageRecord>& cam1, TimeNs tolerance_ns,
                std::vector<StereoPair>& pairs, std::vector<std::size_t>& unmatched0,
                std::vector<std::size_t>& unmatched1) {
  pairs.clear();
  unmatched0.clear();
  unmatched1.clear();
  std::size_t j = 0;
  std::vector<bool> used1(cam1.size(), false);
  for (std::size_t i = 0; i < cam0.size(); ++i) {
    const TimeNs t = cam0[i].t_ns;
    while (j < cam1.size() && cam1[j].t_ns < t - tolerance_ns) ++j;
    // Nearest unused cam1 stamp within the tolerance (both lists are sorted).
    std::size_t best = cam1.size();
    for (std::size_t k = j; k < cam1.size() && cam1[k].t_ns <= t + tolerance_ns; ++k) {
      if (used1[k]) continue;
      if (best == cam1.size() || std::llabs(cam1[k].t_ns - t) < std::llabs(cam1[best].t_ns - t)) best = k;
    }
    if (best == cam1.size()) {
      unmatched0.push_back(i);
    } else {
      used1[best] = true;
      pairs.push_back({t, i, best});
    }
  }
  for (std::size_t k = 0; k < cam1.size(); ++k)
    if (!used1[k]) unmatched1.push_back(k);
}

EurocDataset readEurocDataset(const std::string& dir, const EurocOptions& options) {
  EurocDataset ds;
  ds.root = resolveMav0(dir);
  const fs::path root(ds.root);
  const auto cam_csv = [&](const char* cam) { return (root / cam / "data.csv").string(); };
  const auto cam_data = [&](const char* cam) { return (root / cam / "data").string(); };

  if (!fs::is_directory(root / "cam0")) throw InputError(ds.root, "missing folder cam0/");
  if (!fs::is_directory(root / "imu0")) throw InputError(ds.root, "missing folder imu0/");
  ds.cam0 = readImageList(cam_csv("cam0"), cam_data("cam0"));
  if (!options.left_only && fs::is_directory(root / "cam1")) ds.cam1 = readImageList(cam_csv("cam1"), cam_data("cam1"));
  ds.imu = readImuCsv((root / "imu0" / "data.csv").string());

  const auto gt_csv = root / "state_groundtruth_estimate0" / "data.csv";
  if (fs::is_regular_file(gt_csv)) {
    ds.groundtruth = readGroundTruthCsv(gt_csv.string());
    ds.has_groundtruth = true;
  }

  if (ds.stereo()) {
    pairByTime(ds.cam0, ds.cam1, options.pair_tolerance_ns, ds.pairs, ds.unmatched0, ds.unmatched1);
  } else {
    for (std::size_t i = 0; i < ds.cam0.size(); ++i) ds.pairs.push_back({ds.cam0[i].t_ns, i, 0});
  }
  if (ds.pairs.empty()) throw InputError(ds.root, "no cam0/cam1 rows share a time stamp");
  for (const auto& p : ds.pairs) {
    const auto& r0 = ds.cam0[p.i0];
    if (!r0.exists) throw InputError(cam_csv("cam0"), r0.csv_line, "image file missing: " + r0.path);
    if (ds.stereo() && !ds.cam1[p.i1].exists) {
      const auto& r1 = ds.cam1[p.i1];
      throw InputError(cam_csv("cam1"), r1.csv_line, "image file missing: " + r1.path);
    }
  }
  return ds;
}

cv::Mat loadGrayImage(const ImageRecord& record, const std::string& csv_path, int expected_width, int expected_height) {
  if (!fs::is_regular_file(record.path))
    throw InputError(csv_path, record.csv_line, "image file missing: " + record.path);
  // Read here and decoded from memory: a PNG cut short (no IEND chunk at its end) is refused
  // with one line before libpng would print its own.
  std::ifstream file(record.path, std::ios::binary | std::ios::ate);  // one read of the whole file
  std::vector<unsigned char> bytes(file ? static_cast<std::size_t>(file.tellg()) : 0);
  if (!file.seekg(0) || !file.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw InputError(csv_path, record.csv_line, "image file unreadable: " + record.path);
  static const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static const unsigned char kIend[8] = {'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
  if (bytes.size() >= 8 && std::equal(kPngSignature, kPngSignature + 8, bytes.begin()) &&
      (bytes.size() < 20 || !std::equal(kIend, kIend + 8, bytes.end() - 8)))
    throw InputError(csv_path, record.csv_line, "truncated PNG (no IEND chunk at its end): " + record.path);
  cv::Mat image;
  std::string why;
  const GrayPng kind = bytes.empty() ? GrayPng::kOtherKind : decodeGrayPng(bytes.data(), bytes.size(), image, why);
  if (kind == GrayPng::kCorrupt)
    throw InputError(csv_path, record.csv_line, "image file unreadable (a corrupt PNG: " + why + "): " + record.path);
  if (kind == GrayPng::kOtherKind && !bytes.empty()) image = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  if (image.empty())
    throw InputError(csv_path, record.csv_line, "image file unreadable (expected an 8-bit PNG): " + record.path);
  if (expected_width > 0 && (image.cols != expected_width || image.rows != expected_height)) {
    throw InputError(csv_path, record.csv_line,
                     "image " + record.path + " is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                         ", expected " + std::to_string(expected_width) + "x" + std::to_string(expected_height) +
                         " (image_width/image_height of the config)");
  }
  return image;
}

}  // namespace idyvins::io
