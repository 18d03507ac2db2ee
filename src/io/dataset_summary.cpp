#include "io/dataset_summary.h"

#include <algorithm>

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
  s.gaps = static_cast<std::size_t>(std::count_if(
      dt.begin(), dt.end(), [&](TimeNs d) { return 2 * d > 3 * median; }));
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
  s.groundtruth =
      streamStats(stamps(ds.groundtruth, [](const GroundTruthState& x) { return x.t_ns; }));
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

}  // namespace idyvins::io
