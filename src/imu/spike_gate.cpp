#include "imu/spike_gate.h"

#include <algorithm>
#include <array>

namespace idyvins::imu {
namespace {

/// Per-axis median of the vectors `get` picks from `samples`.
template <typename Get>
Eigen::Vector3d medianOf(const std::deque<ImuSample>& samples, Get get) {
  Eigen::Vector3d m;
  std::array<double, SpikeGate::kReference> v{};
  const std::size_t n = samples.size();
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 0; i < n; ++i) v[i] = get(samples[i])(axis);
    std::nth_element(v.begin(), v.begin() + n / 2, v.begin() + n);
    m(axis) = v[n / 2];
  }
  return m;
}

}  // namespace

bool SpikeGate::deviates(const ImuSample& s) const {
  if (recent_.size() < kReference) return false;
  if (options_.acc_mps2 > 0 &&
      (s.acc_b - medianOf(recent_, [](const ImuSample& r) { return r.acc_b; })).norm() > options_.acc_mps2)
    return true;
  return options_.gyr_radps > 0 &&
         (s.gyr_b - medianOf(recent_, [](const ImuSample& r) { return r.gyr_b; })).norm() > options_.gyr_radps;
}

void SpikeGate::release(const ImuSample& s, std::vector<ImuSample>& released) {
  released.push_back(s);
  recent_.push_back(s);
  if (recent_.size() > kReference) recent_.pop_front();
}

void SpikeGate::push(const ImuSample& s, std::vector<ImuSample>& released) {
  if (!enabled()) {
    released.push_back(s);
    return;
  }
  const TimeNs max_ns = static_cast<TimeNs>(options_.max_ms * 1e6);
  if (!held_.empty() && s.t_ns - held_.front().t_ns > max_ns) {  // the run outlasted a spike: a real change
    for (const ImuSample& h : held_) release(h, released);       // what follows is compared with the new level
    held_.clear();
  }
  // After a gap longer than a spike the recent samples say nothing about this one.
  if (held_.empty() && !recent_.empty() && s.t_ns - recent_.back().t_ns > max_ns) recent_.clear();
  if (deviates(s)) {
    held_.push_back(s);
    return;
  }
  if (!held_.empty()) {  // the run came back in time: a spike
    ++spikes_;
    dropped_samples_ += held_.size();
    held_.clear();
  }
  release(s, released);
}

void SpikeGate::flush(std::vector<ImuSample>& released) {
  for (const ImuSample& h : held_) release(h, released);
  held_.clear();
}

}  // namespace idyvins::imu
