#include <gtest/gtest.h>

#include <random>

#include "imu/spike_gate.h"
#include "io/euroc_dataset.h"
#include "test_util.h"

namespace idyvins::imu {
namespace {

/// 200 Hz samples of a vibrating body at rest (gravity on z, 3 m/s² and 0.05 rad/s noise).
std::vector<ImuSample> vibrating(std::size_t n, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<ImuSample> s(n);
  for (std::size_t k = 0; k < n; ++k) {
    s[k].t_ns = static_cast<TimeNs>(k) * 5'000'000;
    s[k].acc_b = Eigen::Vector3d(3 * g(rng), 3 * g(rng), 9.81 + 3 * g(rng));
    s[k].gyr_b = Eigen::Vector3d(0.05 * g(rng), 0.05 * g(rng), 0.05 * g(rng));
  }
  return s;
}

std::vector<ImuSample> passAll(SpikeGate& gate, const std::vector<ImuSample>& in) {
  std::vector<ImuSample> out;
  for (const ImuSample& s : in) gate.push(s, out);
  gate.flush(out);
  return out;
}

std::vector<TimeNs> times(const std::vector<ImuSample>& s) {
  std::vector<TimeNs> t;
  for (const ImuSample& x : s) t.push_back(x.t_ns);
  return t;
}

TEST(SpikeGate, DropsAShortAccelerationSpikeAndNothingElse) {
  std::vector<ImuSample> in = vibrating(400);
  for (std::size_t k = 200; k < 205; ++k) in[k].acc_b.x() += 100.0;  // 25 ms of +10 g, as `perturb --fault imu-spike`
  SpikeGate gate;
  const std::vector<ImuSample> out = passAll(gate, in);
  EXPECT_EQ(gate.spikes(), 1u);
  EXPECT_EQ(gate.droppedSamples(), 5u);
  std::vector<ImuSample> expected = in;
  expected.erase(expected.begin() + 200, expected.begin() + 205);
  ASSERT_EQ(times(out), times(expected));
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i].acc_b, expected[i].acc_b);  // released unchanged
}

TEST(SpikeGate, DropsAGyroscopeSpike) {
  std::vector<ImuSample> in = vibrating(300);
  for (std::size_t k = 100; k < 103; ++k) in[k].gyr_b.z() -= 20.0;
  SpikeGate gate;
  EXPECT_EQ(passAll(gate, in).size(), 297u);
  EXPECT_EQ(gate.spikes(), 1u);
}

TEST(SpikeGate, KeepsAChangeThatLastsLongerThanASpike) {
  std::vector<ImuSample> in = vibrating(400);
  for (std::size_t k = 200; k < 240; ++k) in[k].acc_b.x() += 80.0;  // 200 ms: a real push
  SpikeGate gate;
  std::vector<ImuSample> out;
  bool held_some = false;
  for (std::size_t k = 0; k < in.size(); ++k) {
    gate.push(in[k], out);
    held_some = held_some || gate.holding();
    if (k == 211) {  // 55 ms into the change: released, as it outlasted imu_spike_max_ms
      EXPECT_FALSE(gate.holding());
      EXPECT_EQ(out.size(), 212u);
    }
  }
  gate.flush(out);
  EXPECT_TRUE(held_some);
  EXPECT_EQ(gate.spikes(), 0u);
  EXPECT_EQ(times(out), times(in));
}

TEST(SpikeGate, ARunThatComesBackOnlyAfterMaxMsIsKept) {
  // Four samples 10 g off, then the stream pauses 80 ms: when the next (ordinary) sample
  // comes, the run has lasted longer than a spike, so it is released, not dropped.
  std::vector<ImuSample> in = vibrating(300);
  for (std::size_t k = 100; k < 104; ++k) in[k].acc_b.x() += 100.0;
  for (std::size_t k = 104; k < in.size(); ++k) in[k].t_ns += 80'000'000;
  SpikeGate gate;
  EXPECT_EQ(times(passAll(gate, in)), times(in));
  EXPECT_EQ(gate.spikes(), 0u);
}

TEST(SpikeGate, PassesRealEurocSamplesUntouchedAndFindsASpikeAddedToThem) {
  // A real MAV in flight (vibration included): nothing is taken for a spike.
  for (const char* file : {"euroc_v101_micro/mav0/imu0/data.csv", "euroc_imu_gt_excerpt/mav0/imu0/data.csv"}) {
    const std::vector<ImuSample> real = io::readImuCsv(test::sharedData(file));
    ASSERT_GT(real.size(), 1000u);
    SpikeGate gate;
    EXPECT_EQ(times(passAll(gate, real)), times(real)) << file;
    EXPECT_EQ(gate.spikes(), 0u) << file;
  }
  const std::vector<ImuSample> real = io::readImuCsv(test::sharedData("euroc_v101_micro/mav0/imu0/data.csv"));
  std::vector<ImuSample> spiked = real;
  for (std::size_t k = 700; k < 705; ++k) spiked[k].acc_b.x() += 100.0;
  SpikeGate gate2;
  EXPECT_EQ(passAll(gate2, spiked).size(), real.size() - 5);
  EXPECT_EQ(gate2.spikes(), 1u);
}

TEST(SpikeGate, OffPassesEverythingAndFlushReleasesWhatIsHeld) {
  std::vector<ImuSample> in = vibrating(100);
  for (std::size_t k = 50; k < 53; ++k) in[k].acc_b.x() += 100.0;
  SpikeGateOptions off;
  off.max_ms = 0;
  SpikeGate gate_off(off);
  EXPECT_EQ(passAll(gate_off, in).size(), in.size());

  SpikeGate gate;  // the stream ends inside a run: released as it is
  std::vector<ImuSample> out;
  for (std::size_t k = 0; k < 52; ++k) gate.push(in[k], out);
  EXPECT_TRUE(gate.holding());
  EXPECT_EQ(out.size(), 50u);
  gate.flush(out);
  EXPECT_EQ(out.size(), 52u);
  EXPECT_EQ(gate.spikes(), 0u);
}

TEST(SpikeGate, CompareAfterAGapWithWhatFollowsIt) {
  // 0.2 s without samples, then a level 60 m/s² away (the platform was pushed meanwhile):
  // the samples before the gap say nothing about it, so nothing is held.
  std::vector<ImuSample> in = vibrating(100);
  for (std::size_t k = 50; k < 100; ++k) {
    in[k].t_ns += 200'000'000;
    in[k].acc_b.x() += 60.0;
  }
  SpikeGate gate;
  std::vector<ImuSample> out;
  for (std::size_t k = 0; k < 51; ++k) gate.push(in[k], out);
  EXPECT_FALSE(gate.holding());
  EXPECT_EQ(out.size(), 51u);
}

}  // namespace
}  // namespace idyvins::imu
