#include "io/trajectory_io.h"

#include <cstdio>
#include <fstream>
#include <memory>

#include "core/error.h"
#include "io/csv.h"

namespace idyvins::io {
namespace {

using FilePtr = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

FilePtr openForWrite(const std::string& path) {
  FilePtr f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw InputError(path, "cannot write file (missing folder or no permission)");
  return f;
}

Eigen::Quaterniond unitQuaternion(double w, double x, double y, double z, const std::string& path, int line) {
  Eigen::Quaterniond q(w, x, y, z);
  const double n = q.norm();
  if (std::abs(n - 1.0) > 1e-2)
    throw InputError(path, line, "expected a unit quaternion, norm is " + std::to_string(n));
  q.normalize();
  return q;
}

void checkTimes(const std::vector<StampedPose>& poses, const std::vector<int>& lines, const std::string& path) {
  std::vector<TimeNs> stamps;
  stamps.reserve(poses.size());
  for (const auto& p : poses) stamps.push_back(p.t_ns);
  checkIncreasing(stamps, lines, path);
}

}  // namespace

void writeTum(const std::string& path, const std::vector<StampedPose>& poses) {
  FilePtr f = openForWrite(path);
  std::fprintf(f.get(), "# timestamp tx ty tz qx qy qz qw\n");
  for (const auto& p : poses) {
    const auto& q = p.q_w_b;
    std::fprintf(f.get(), "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", formatSeconds(p.t_ns).c_str(), p.p_w_b.x(),
                 p.p_w_b.y(), p.p_w_b.z(), q.x(), q.y(), q.z(), q.w());
  }
  if (std::ferror(f.get())) throw InputError(path, "write failed");
}

void writeEurocCsv(const std::string& path, const std::vector<StampedPose>& poses) {
  FilePtr f = openForWrite(path);
  std::fprintf(f.get(),
               "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],"
               "q_RS_y [],q_RS_z []\n");
  for (const auto& p : poses) {
    const auto& q = p.q_w_b;
    std::fprintf(f.get(), "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", static_cast<long long>(p.t_ns), p.p_w_b.x(),
                 p.p_w_b.y(), p.p_w_b.z(), q.w(), q.x(), q.y(), q.z());
  }
  if (std::ferror(f.get())) throw InputError(path, "write failed");
}

void writeStateCsv(const std::string& path, const std::vector<GroundTruthState>& states) {
  FilePtr f = openForWrite(path);
  std::fprintf(f.get(),
               "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
               "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
               "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n");
  for (const auto& g : states) {
    std::fprintf(
        f.get(),
        "%lld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n",
        static_cast<long long>(g.t_ns), g.p_w_b.x(), g.p_w_b.y(), g.p_w_b.z(), g.q_w_b.w(), g.q_w_b.x(), g.q_w_b.y(),
        g.q_w_b.z(), g.v_w.x(), g.v_w.y(), g.v_w.z(), g.bg.x(), g.bg.y(), g.bg.z(), g.ba.x(), g.ba.y(), g.ba.z());
  }
  if (std::ferror(f.get())) throw InputError(path, "write failed");
}

std::vector<StampedPose> readTum(const std::string& path) {
  const auto rows = readTable(path, {' ', 8, 8});
  std::vector<StampedPose> poses;
  std::vector<int> lines;
  for (const auto& r : rows) {
    StampedPose p;
    const auto t = parseSecondsExact(r.fields[0]);
    if (!t)
      throw InputError(path, r.line, "column 1: expected a time stamp in decimal seconds, got '" + r.fields[0] + "'");
    p.t_ns = *t;
    double v[7];
    for (int i = 0; i < 7; ++i) v[i] = parseFinite(r.fields[i + 1], path, r.line, i + 2);
    p.p_w_b = {v[0], v[1], v[2]};
    p.q_w_b = unitQuaternion(v[6], v[3], v[4], v[5], path, r.line);
    poses.push_back(p);
    lines.push_back(r.line);
  }
  checkTimes(poses, lines, path);
  return poses;
}

std::vector<StampedPose> readEurocCsv(const std::string& path) {
  const auto rows = readTable(path, {',', 8, 0});
  std::vector<StampedPose> poses;
  std::vector<int> lines;
  const std::size_t ncols = rows.front().fields.size();
  for (const auto& r : rows) {
    if (r.fields.size() != ncols || (ncols != 8 && ncols < 17))
      throw InputError(
          path, r.line,
          "expected 8 columns (t, p xyz, q wxyz) or 17 (EuRoC ground truth), got " + std::to_string(r.fields.size()));
    StampedPose p;
    p.t_ns = parseTimeNs(r.fields[0], path, r.line, 1);
    double v[7];
    for (int i = 0; i < 7; ++i) v[i] = parseFinite(r.fields[i + 1], path, r.line, i + 2);
    p.p_w_b = {v[0], v[1], v[2]};
    p.q_w_b = unitQuaternion(v[3], v[4], v[5], v[6], path, r.line);
    poses.push_back(p);
    lines.push_back(r.line);
  }
  checkTimes(poses, lines, path);
  return poses;
}

std::vector<StampedPose> readTrajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::string line;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    return line.find(',') != std::string::npos ? readEurocCsv(path) : readTum(path);
  }
  return readTum(path);  // reports "empty" / "no data rows" with the TUM expectations
}

}  // namespace idyvins::io
