#include "io/dataset_summary.h"

#include <algorithm>
#include <cstdio>

#include "core/error.h"

namespace idyvins::io {

StreamStats streamStats(const std::vector<TimeNs>& stamps) {
  StreamStats s;
  s.count = stamps.size();
  if (stamps.empty()) return s;
  s.first_ns = stamps.front();
  s.last_ns = stamps.back();
  s.span_s = toSeconds(s.last_ns - s.first_ns);
  if (stamps.size() < 2) return s;
  std::vector<TimeNs> dt(stamps.size() - 1);
  for (std::size_t i = 1; i < stamps.size(); ++i) dt[i - 1] = stamps[i] - stamps[i - 1];
  std::vector<TimeNs> sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const TimeNs median = sorted[sorted.size() / 2];
  s.rate_hz = median > 0 ? 1.0 / toSeconds(median) : 0.0;
  const TimeNs max_dt = *std::max_element(dt.begin(), dt.end());
  s.max_gap_s = toSeconds(max_dt);
  s.gaps = static_cast<std::size_t>(std::count_if(dt.begin(), dt.end(), [&](TimeNs d) { return 2 * d > 3 * median; }));
  return s;
}

DatasetSummary summarize(const EurocDataset& ds) {
  DatasetSummary s;
  auto stamps = [](const auto& items, auto get) {
    std::vector<TimeNs> t;
    t.reserve(items.size());
    for (const auto& it : items) t.push_back(get(it));
    return t;
  };
  s.imu = streamStats(stamps(ds.imu, [](const ImuSample& x) { return x.t_ns; }));
  s.cam0 = streamStats(stamps(ds.cam0, [](const ImageRecord& x) { return x.t_ns; }));
  s.cam1 = streamStats(stamps(ds.cam1, [](const ImageRecord& x) { return x.t_ns; }));
  s.pairs = streamStats(stamps(ds.pairs, [](const StereoPair& x) { return x.t_ns; }));
  s.groundtruth = streamStats(stamps(ds.groundtruth, [](const GroundTruthState& x) { return x.t_ns; }));
  s.stereo = ds.stereo();
  s.has_groundtruth = ds.has_groundtruth;
  s.unmatched0 = ds.unmatched0.size();
  s.unmatched1 = ds.unmatched1.size();
  for (auto i : ds.unmatched0) s.unmatched_missing_image += ds.cam0[i].exists ? 0 : 1;
  for (auto i : ds.unmatched1) s.unmatched_missing_image += ds.cam1[i].exists ? 0 : 1;
  if (!ds.pairs.empty() && !ds.imu.empty()) {
    s.imu_before_first_frame_s = toSeconds(ds.pairs.front().t_ns - ds.imu.front().t_ns);
    s.imu_after_last_frame_s = toSeconds(ds.imu.back().t_ns - ds.pairs.back().t_ns);
  }
  return s;
}

namespace {

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// A stream's rate that only another unit than ns explains (EuRoC stamps are ns).
void checkUnit(const std::string& file, const StreamStats& s, double max_hz, const char* what) {
  if (s.rate_hz <= max_hz) return;
  const double us = s.rate_hz / 1e3, ms = s.rate_hz / 1e6;
  throw InputError(file, std::string(what) + " at " + fixed(s.rate_hz, 0) + " Hz if its stamps are ns: expected ns " +
                             "(in us it would be " + fixed(us, 1) + " Hz, in ms " + fixed(ms, 1) + " Hz)");
}

}  // namespace

std::vector<std::string> checkPlausible(const EurocDataset& ds, const DatasetSummary& s, const ExpectedRig& c) {
  std::vector<std::string> warnings;
  const std::string imu_file = ds.root + "/imu0/data.csv", cam_file = ds.root + "/cam0/data.csv";
  if (c.num_cam == 2 && !ds.stereo())
    throw InputError(ds.root, "the config asks for 2 cameras (num_of_cam: 2) but the dataset has no cam1/");
  checkUnit(cam_file, s.cam0, 1000.0, "cam0");
  if (!c.use_imu) return warnings;
  if (ds.imu.size() < 2) throw InputError(imu_file, "expected IMU samples, got " + std::to_string(ds.imu.size()));
  checkUnit(imu_file, s.imu, 10000.0, "the IMU");
  if (!ds.pairs.empty() && (ds.imu.back().t_ns < ds.pairs.front().t_ns || ds.imu.front().t_ns > ds.pairs.back().t_ns))
    throw InputError(imu_file, "no IMU sample at the frame times (IMU " + std::to_string(ds.imu.front().t_ns) + " to " +
                                   std::to_string(ds.imu.back().t_ns) + " ns, frames " +
                                   std::to_string(ds.pairs.front().t_ns) + " to " +
                                   std::to_string(ds.pairs.back().t_ns) + " ns): stamps of another clock or unit?");
  std::vector<double> acc, gyr;
  for (const ImuSample& m : ds.imu) acc.push_back(m.acc_b.norm()), gyr.push_back(m.gyr_b.norm());
  const double a = medianOf(acc), w = medianOf(gyr), g = c.g_norm;
  if (a < 0.3 * g || a > 3 * g)
    throw InputError(imu_file, "accelerometer median " + fixed(a, 3) + " m/s^2, expected about g_norm " + fixed(g, 3) +
                                   (a > 0.5 && a < 1.5 ? " (in g? expected m/s^2)" : " (all zero? another unit?)"));
  if (std::abs(a - g) > 0.1 * g)
    warnings.push_back(imu_file + ": accelerometer median " + fixed(a, 3) + " m/s^2, " +
                       fixed(100 * std::abs(a - g) / g, 0) + " % off g_norm " + fixed(g, 3) + " (a scale error?)");
  if (w > 3.0)
    throw InputError(imu_file, "gyroscope median " + fixed(w, 2) + " (" + fixed(w * 57.29578, 0) +
                                   " deg/s if these are rad/s, " + fixed(w / 57.29578, 3) +
                                   " rad/s if deg/s): expected rad/s");
  if (w > 1.5)
    warnings.push_back(imu_file + ": gyroscope median " + fixed(w, 2) + " rad/s, fast for a camera rig (deg/s?)");
  const double per_frame = s.pairs.rate_hz > 0 ? s.imu.rate_hz / s.pairs.rate_hz : 0;
  if (s.imu.rate_hz < 100 || (per_frame > 0 && per_frame < 5))
    warnings.push_back(imu_file + ": IMU at " + fixed(s.imu.rate_hz, 1) + " Hz, " + fixed(per_frame, 1) +
                       " samples per frame: preintegration wants 100 Hz or more (VINS-Fusion's rigs: 100 to 400 Hz); "
                       "expect a larger error");
  if (s.imu_before_first_frame_s < 0)
    warnings.push_back(imu_file + ": the IMU starts " + fixed(-s.imu_before_first_frame_s, 3) +
                       " s after the first frame: the frames before it are not used");
  if (s.imu_after_last_frame_s < 0)
    warnings.push_back(imu_file + ": the IMU ends " + fixed(-s.imu_after_last_frame_s, 3) +
                       " s before the last frame: the frames after it are not used");
  return warnings;
}

}  // namespace idyvins::io
