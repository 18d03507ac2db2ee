#pragma once
// Short IMU spikes held back and dropped before they reach the integration. A spike is a
// run of samples that jumps away from the recent ones (acceleration or angular rate
// farther than a threshold from the per-axis median of the last released samples) and
// comes back within a short time: a shock, an electrical glitch, a bit error. Such a run is
// dropped (the integration bridges the gap from the sample before to the sample after);
// a run that lasts longer than `max_ms` is a real change of motion and is released whole.
// Samples that might be a spike are held until that is decided, so a consumer waiting for
// the IMU to reach a time waits at most `max_ms` longer.

#include <cstddef>
#include <deque>
#include <vector>

#include "core/measurements.h"
#include "core/params.h"

namespace idyvins::imu {

/// Keys of the spike gate (config: imu_spike_acc, imu_spike_gyr, imu_spike_max_ms).
struct SpikeGateOptions {
  /// m/s^2; a sample whose acceleration is farther than this from the recent median starts or
  /// continues a run; 0 = acceleration not tested. About 5 g: real EuRoC samples (a MAV's
  /// vibration) deviate from that median by at most 9.6 m/s^2 (../shared/data, both excerpts).
  double acc_mps2 = 50.0;
  /// rad/s, the same for the angular rate; 0 = not tested.
  double gyr_radps = 10.0;
  /// ms; a run that lasts longer is released (a real change); 0 = the gate is off.
  double max_ms = 50.0;

  void visit(ParamVisitor& v) {
    v.param({"imu_spike_acc",
             "m/s^2, acceleration this far from the recent median starts a possible spike (0 = not tested)",
             ParamRule::kNonNegative},
            acc_mps2);
    v.param({"imu_spike_gyr",
             "rad/s, angular rate this far from the recent median starts a possible spike (0 = not tested)",
             ParamRule::kNonNegative},
            gyr_radps);
    v.param({"imu_spike_max_ms", "ms, a run of such samples returning within this is dropped as a spike (0 = gate off)",
             ParamRule::kNonNegative},
            max_ms);
  }
};

/// Passes IMU samples through in order, dropping short spikes. One instance per stream.
class SpikeGate {
 public:
  /// Samples compared with the median of this many released ones (fewer at the start: all pass).
  static constexpr std::size_t kReference = 5;

  explicit SpikeGate(const SpikeGateOptions& options = {}) : options_(options) {}

  /// Takes the next sample (later than the previous one, finite) and appends to `released`
  /// the samples now known not to be a spike, in time order.
  void push(const ImuSample& sample, std::vector<ImuSample>& released);
  /// End of the stream: appends the samples still held, as they are.
  void flush(std::vector<ImuSample>& released);

  bool holding() const { return !held_.empty(); }
  std::size_t spikes() const { return spikes_; }                   ///< runs dropped
  std::size_t droppedSamples() const { return dropped_samples_; }  ///< samples in them

 private:
  bool enabled() const { return options_.max_ms > 0 && (options_.acc_mps2 > 0 || options_.gyr_radps > 0); }
  bool deviates(const ImuSample& sample) const;
  void release(const ImuSample& sample, std::vector<ImuSample>& released);

  SpikeGateOptions options_;
  std::deque<ImuSample> recent_;  ///< the last released samples (at most kReference)
  std::vector<ImuSample> held_;   ///< a run that may be a spike
  std::size_t spikes_ = 0, dropped_samples_ = 0;
};

}  // namespace idyvins::imu
