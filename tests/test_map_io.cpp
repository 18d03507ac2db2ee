// Saved maps: save -> load is exact; damaged, foreign and other-version maps are one InputError.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "core/error.h"
#include "map/map_io.h"

namespace idyvins::map {
namespace {

namespace fs = std::filesystem;

SavedMap randomMap(int keyframes) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0, 3);
  SavedMap m;
  for (int k = 0; k < keyframes; ++k) {
    Keyframe kf;
    kf.id = static_cast<std::uint32_t>(k);
    kf.t_ns = 1'700'000'000'000'000'000 + k * 50'000'000LL;
    kf.p_w_b = {n(rng), n(rng), n(rng)};
    kf.q_w_b = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    for (int i = 0; i < 40 + k; ++i) {
      Descriptor d;
      for (auto& b : d) b = static_cast<std::uint8_t>(rng());
      kf.descriptors.push_back(d);
      if (i % 3 == 0) kf.landmarks.push_back({rng(), {n(rng), n(rng), n(rng)}, {n(rng), n(rng)}, d});
    }
    PoseGraphNode node;
    node.t_ns = kf.t_ns;
    node.p_odom = kf.p_w_b;
    node.q_odom = kf.q_w_b;
    node.p = kf.p_w_b + Eigen::Vector3d(0.1, -0.2, 0.01);
    node.yaw = 0.3 * n(rng);
    node.fixed = k == 0;
    m.keyframes.push_back(kf);
    m.nodes.push_back(node);
  }
  m.loops.push_back({1, static_cast<std::size_t>(keyframes - 1), RelativePose4{{0.123456789012345, -2, 3}, 0.5}});
  m.rig = "PINHOLE 752x480 f 380.00 380.00 (a test rig)";
  return m;
}

class MapIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("idyvins_map_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    saveMap(dir_.string(), randomMap(12));
  }
  void TearDown() override { fs::remove_all(dir_); }
  void expectRefused(const std::string& what) {
    try {
      loadMap(dir_.string());
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
  fs::path dir_;
};

TEST_F(MapIo, SaveLoadRoundTripIsExact) {
  const SavedMap a = randomMap(12), b = loadMap(dir_.string());
  EXPECT_EQ(a.rig, b.rig);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t k = 0; k < a.keyframes.size(); ++k) {
    const Keyframe &x = a.keyframes[k], &y = b.keyframes[k];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.t_ns, y.t_ns);
    EXPECT_EQ(x.p_w_b, y.p_w_b);
    EXPECT_EQ(x.q_w_b.coeffs(), y.q_w_b.coeffs());
    EXPECT_EQ(x.descriptors, y.descriptors);
    ASSERT_EQ(x.landmarks.size(), y.landmarks.size());
    for (std::size_t i = 0; i < x.landmarks.size(); ++i) {
      EXPECT_EQ(x.landmarks[i].id, y.landmarks[i].id);
      EXPECT_EQ(x.landmarks[i].p_w, y.landmarks[i].p_w);
      EXPECT_EQ(x.landmarks[i].xy, y.landmarks[i].xy);
      EXPECT_EQ(x.landmarks[i].descriptor, y.landmarks[i].descriptor);
    }
    EXPECT_EQ(a.nodes[k].p, b.nodes[k].p);
    EXPECT_EQ(a.nodes[k].yaw, b.nodes[k].yaw);
    EXPECT_EQ(a.nodes[k].fixed, b.nodes[k].fixed);
  }
  ASSERT_EQ(b.loops.size(), 1u);
  EXPECT_EQ(b.loops[0].to, 11u);
  EXPECT_EQ(b.loops[0].measured.t_from_to.x(), 0.123456789012345);  // printed with 17 digits: exact
}

TEST_F(MapIo, DamagedMapsAreRefused) {
  const fs::path bin = dir_ / "keyframes.bin";
  const auto size = fs::file_size(bin);
  {  // one byte changed: the checksum
    std::fstream f(bin, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    f.put('\x5a');
  }
  expectRefused("checksum differs");
  fs::resize_file(bin, size / 3);  // cut
  expectRefused("checksum differs");
  fs::remove(bin);
  expectRefused("missing or unreadable");
}

TEST_F(MapIo, ForeignAndOtherVersionMapsAreRefused) {
  const fs::path json = dir_ / "map.json";
  std::string text;
  {
    std::ifstream f(json);
    text.assign(std::istreambuf_iterator<char>(f), {});
  }
  std::ofstream(json) << std::string(text).replace(text.find("\"version\": 1"), 12, "\"version\": 2");
  expectRefused("map format version 2, this idyvins reads 1");
  std::ofstream(json) << "{\"format\": \"orb-slam3-atlas\"}";
  expectRefused("not an idyvins map");
  std::ofstream(json) << "not json";
  expectRefused("not JSON");
  std::ofstream(json) << text;
  std::ofstream(dir_ / "loops.csv") << "0,99,1,2,3,0\n";
  expectRefused("loops.csv:1: keyframe index outside");
  fs::remove_all(dir_);
  expectRefused("missing or unreadable (not an idyvins map folder?)");
}

}  // namespace
}  // namespace idyvins::map
