#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/error.h"
#include "io/euroc_dataset.h"
#include "io/trajectory_io.h"
#include "test_util.h"

namespace idyvins::io {
namespace {

using test::expectError;
using test::TempDir;
using test::writeFile;

std::vector<StampedPose> randomTrajectory(int n) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<StampedPose> poses;
  TimeNs t = 1403715273262142976;
  for (int i = 0; i < n; ++i) {
    StampedPose p;
    t += 50'000'000 + (i % 3);
    p.t_ns = t;
    p.p_w_b = {g(rng) * 10, g(rng) * 10, g(rng)};
    p.q_w_b = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
    poses.push_back(p);
  }
  return poses;
}

void expectSame(const std::vector<StampedPose>& a, const std::vector<StampedPose>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);  // exact: nanoseconds survive the text round trip
    EXPECT_LT((a[i].p_w_b - b[i].p_w_b).norm(), 1e-8);
    EXPECT_LT(a[i].q_w_b.angularDistance(b[i].q_w_b), 1e-8);
  }
}

TEST(TrajectoryIo, FuzzFindingsAreRefusedWithOneClearError) {
  // Inputs libFuzzer found (scripts/fuzz.sh), kept as regressions: InputError, nothing else.
  int replayed = 0;
  for (const auto& e : std::filesystem::directory_iterator(IDYVINS_SOURCE_DIR "/tests/fuzz/regressions")) {
    if (e.path().filename().string().rfind("trajectory_", 0) != 0) continue;
    SCOPED_TRACE(e.path().string());
    EXPECT_THROW(readTrajectory(e.path().string()), InputError);
    ++replayed;
  }
  EXPECT_GE(replayed, 1);
}

TEST(TrajectoryIo, TumRoundTrip) {
  TempDir dir;
  const auto poses = randomTrajectory(50);
  writeTum(dir / "t.tum", poses);
  expectSame(poses, readTum(dir / "t.tum"));
  expectSame(poses, readTrajectory(dir / "t.tum"));
}

TEST(TrajectoryIo, EurocCsvRoundTrip) {
  TempDir dir;
  const auto poses = randomTrajectory(50);
  writeEurocCsv(dir / "t.csv", poses);
  expectSame(poses, readEurocCsv(dir / "t.csv"));
  expectSame(poses, readTrajectory(dir / "t.csv"));
}

TEST(TrajectoryIo, StateCsvRoundTripsThroughTheGroundTruthReader) {
  TempDir dir;
  std::vector<GroundTruthState> states;
  for (const auto& p : randomTrajectory(20)) {
    const double k = static_cast<double>(states.size());
    states.push_back({p.t_ns, p.p_w_b, p.q_w_b, {k, -k, 0.5}, {1e-3 * k, -2e-3, 3e-4}, {0.05, -0.1 * k, 0.2}});
  }
  writeStateCsv(dir / "s.csv", states);
  const auto back = readGroundTruthCsv(dir / "s.csv");
  ASSERT_EQ(back.size(), states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    EXPECT_EQ(back[i].t_ns, states[i].t_ns);
    EXPECT_LT((back[i].p_w_b - states[i].p_w_b).norm(), 1e-9);
    EXPECT_LT(back[i].q_w_b.angularDistance(states[i].q_w_b), 1e-9);
    EXPECT_LT((back[i].v_w - states[i].v_w).norm(), 1e-9);
    EXPECT_LT((back[i].bg - states[i].bg).norm(), 1e-12);
    EXPECT_LT((back[i].ba - states[i].ba).norm(), 1e-9);
  }
  // The pose reader accepts it too (17 columns).
  EXPECT_EQ(readTrajectory(dir / "s.csv").size(), states.size());
}

TEST(TrajectoryIo, TumQuaternionOrderIsXyzw) {
  TempDir dir;
  writeFile(dir / "q.tum", "1.0 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n");
  const auto p = readTum(dir / "q.tum");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p[0].q_w_b.w(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p[0].q_w_b.z(), std::sqrt(0.5), 1e-12);
  EXPECT_EQ(p[0].t_ns, 1'000'000'000);
}

TEST(TrajectoryIo, ReadsSeventeenColumnGroundTruth) {
  const auto p = readEurocCsv(test::sharedData("euroc_imu_gt_excerpt/mav0/gt0/data.csv"));
  ASSERT_EQ(p.size(), 3340u);
  EXPECT_NEAR(p[0].q_w_b.x(), 0.790012, 1e-5);
}

TEST(TrajectoryIo, BadInput) {
  TempDir dir;
  writeFile(dir / "a.tum", "1.0 1 2 3 0 0 0 1\n0.5 1 2 3 0 0 0 1\n");
  expectError([&] { readTum(dir / "a.tum"); }, "a.tum:2: non-increasing time stamp");
  writeFile(dir / "b.tum", "1.0 1 2 3 0 0 0 5\n");
  expectError([&] { readTum(dir / "b.tum"); }, "b.tum:1: expected a unit quaternion");
  writeFile(dir / "c.tum", "1e9 1 2 3 0 0 0 1\n");
  expectError([&] { readTum(dir / "c.tum"); }, "c.tum:1: column 1: expected a time stamp in decimal seconds");
  writeFile(dir / "d.csv", "#t\n1,0,0,0,1,0,0,0\n2,0,0,0,1,0,0\n");
  expectError([&] { readEurocCsv(dir / "d.csv"); }, "d.csv:3: expected at least 8 columns, got 7");
  writeFile(dir / "e.csv", "#t\n1,0,0,0,1,0,0,0,5\n");
  expectError([&] { readEurocCsv(dir / "e.csv"); }, "e.csv:2: expected 8 columns (t, p xyz, q wxyz) or 17");
  expectError([&] { writeTum(dir / "no/such/dir/x.tum", {}); }, "cannot write file");
}

}  // namespace
}  // namespace idyvins::io
