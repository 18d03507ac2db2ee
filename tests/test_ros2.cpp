// ROS 2 bags without ROS 2: CDR (alignment, byte order, bounds), the message codecs, and MCAP
// files written and read back (chunk compressions, summary, damage refused with its offset).
// Bags written by independent implementations are read in ros2_bag_check.py.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "io/bag_file.h"
#include "io/cdr.h"
#include "io/mcap.h"
#include "io/mcap_writer.h"
#include "io/ros2_messages.h"

namespace idyvins::io {
namespace {

std::filesystem::path scratchDir() {
  return std::filesystem::temp_directory_path() / ("idyvins_test_ros2_" + std::to_string(::getpid()));
}

std::string scratch(const std::string& name) {
  std::filesystem::create_directories(scratchDir());
  return (scratchDir() / name).string();
}

/// Removes the scratch files when the tests end.
struct ScratchCleanup : ::testing::Environment {
  void TearDown() override { std::filesystem::remove_all(scratchDir()); }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

TEST(Cdr, AlignsEachPrimitiveToItsSizeFromTheEndOfTheHeader) {
  // u8 at body offset 0, u32 padded to 4, f64 at 8 (already aligned); a u32 after it at 16, then
  // an f64 padded from 20 to 24: little-endian.
  const std::vector<std::uint8_t> bytes{0,    1,    0,    0,    7, 0xEE, 0xEE, 0xEE, 0x78, 0x56, 0x34, 0x12,
                                        0,    0,    0,    0,    0, 0,    0xF0, 0x3F, 5,    0,    0,    0,
                                        0xEE, 0xEE, 0xEE, 0xEE, 0, 0,    0,    0,    0,    0,    0,    0x40};
  CdrReader r(bytes.data(), bytes.size());
  EXPECT_EQ(r.u8(), 7);
  EXPECT_EQ(r.u32(), 0x12345678u);
  EXPECT_EQ(r.f64(), 1.0);
  EXPECT_EQ(r.u32(), 5u);
  EXPECT_EQ(r.f64(), 2.0);
  EXPECT_EQ(r.offset(), bytes.size());
}

TEST(Cdr, ReadsBigEndianAndStringsAndRefusesWhatRunsPastTheEnd) {
  const std::vector<std::uint8_t> be{0, 0, 0, 0, 0x12, 0x34, 0x56, 0x78, 0, 0, 0, 3, 'h', 'i', 0};
  CdrReader r(be.data(), be.size());
  EXPECT_EQ(r.u32(), 0x12345678u);
  EXPECT_EQ(r.string(), "hi");
  EXPECT_THROW(r.u8(), CdrError);
  const std::vector<std::uint8_t> long_string{0, 1, 0, 0, 200, 0, 0, 0, 'x'};
  CdrReader s(long_string.data(), long_string.size());
  EXPECT_THROW(s.string(), CdrError);
  const std::vector<std::uint8_t> xcdr2{0, 7, 0, 0};
  EXPECT_THROW(CdrReader(xcdr2.data(), xcdr2.size()), CdrError);
  EXPECT_THROW(CdrReader(xcdr2.data(), 3), CdrError);
}

TEST(Cdr, WriterAndReaderAgreeOnEveryType) {
  CdrWriter w;
  w.u8(3);
  w.f64(-2.5);
  w.string("frame");
  const std::uint8_t blob[] = {9, 8, 7};
  w.bytes(blob, 3);
  w.i32(-7);
  CdrReader r(w.data().data(), w.data().size());
  EXPECT_EQ(r.u8(), 3);
  EXPECT_EQ(r.f64(), -2.5);
  EXPECT_EQ(r.string(), "frame");
  std::size_t n = 0;
  const std::uint8_t* p = r.bytes(n);
  ASSERT_EQ(n, 3u);
  EXPECT_EQ(p[2], 7);
  EXPECT_EQ(r.i32(), -7);
}

TEST(Ros2Messages, ImuImageAndOdometryRoundTripAndTruncationIsRefused) {
  ImuSample s;
  s.t_ns = 1'700'000'000'123'456'789;
  s.gyr_b = {0.1, -0.2, 0.3};
  s.acc_b = {9.8, 0.01, -0.02};
  const auto imu = encodeRos2Imu(s, "imu");
  const ImuSample back = decodeRos2Imu(imu.data(), imu.size());
  EXPECT_EQ(back.t_ns, s.t_ns);
  EXPECT_EQ(back.gyr_b, s.gyr_b);
  EXPECT_EQ(back.acc_b, s.acc_b);
  EXPECT_THROW(decodeRos2Imu(imu.data(), imu.size() - 1), BagMessageError);

  const std::vector<std::uint8_t> pixels{1, 2, 3, 4, 5, 6};
  const auto image = encodeRos2Image(42, "cam0", 3, 2, "mono8", 3, pixels.data());
  const BagImage m = decodeRos2Image(image.data(), image.size(), BagMessageKind::kImage);
  EXPECT_EQ(m.stamp_ns, 42);
  EXPECT_EQ(m.width, 3u);
  EXPECT_EQ(m.height, 2u);
  EXPECT_EQ(m.encoding, "mono8");
  ASSERT_EQ(m.size, 6u);
  EXPECT_EQ(m.data[5], 6);

  const Eigen::Quaterniond q(0.5, 0.5, -0.5, 0.5);
  const auto odom = encodeRos2Odometry(7, "world", "body", {1, 2, 3}, q);
  const BagPose p = decodeRos2Pose(odom.data(), odom.size(), BagMessageKind::kOdometry);
  EXPECT_EQ(p.stamp_ns, 7);
  EXPECT_EQ(p.p, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.q.coeffs(), q.coeffs());
}

TEST(Ros2Messages, DefinitionsCarryTheirDependencies) {
  const std::string d = ros2MessageDefinition("sensor_msgs/msg/Imu");
  EXPECT_EQ(d.rfind("std_msgs/Header header\n", 0), 0u);
  EXPECT_NE(d.find("MSG: std_msgs/Header\n"), std::string::npos);
  EXPECT_NE(d.find("MSG: builtin_interfaces/Time\n"), std::string::npos);
  EXPECT_NE(d.find("MSG: geometry_msgs/Quaternion\n"), std::string::npos);
}

/// An MCAP of `n` IMU messages on one channel, chunks of `chunk` bytes.
std::string writeImuMcap(const std::string& name, const std::string& compression, int n, std::size_t chunk) {
  const std::string path = scratch(name);
  McapWriter w(path, compression, chunk);
  const auto c = w.addChannel("/imu0", "sensor_msgs/msg/Imu", ros2MessageDefinition("sensor_msgs/msg/Imu"));
  for (int i = 0; i < n; ++i) {
    ImuSample s;
    s.t_ns = TimeNs{1'000'000'000} + TimeNs{5'000'000} * i;
    s.gyr_b = {0.001 * i, 0, 0};
    w.write(c, static_cast<std::uint64_t>(s.t_ns), encodeRos2Imu(s, "imu"));
  }
  w.close();
  return path;
}

TEST(Mcap, EveryCompressionReadsBackWithTheSummaryCounts) {
  for (const std::string comp : {"none", "zstd", "lz4"}) {
    SCOPED_TRACE(comp);
    const std::string path = writeImuMcap("imu_" + comp + ".mcap", comp, 300, 4096);
    EXPECT_EQ(bagFormat(path), BagFormat::kRos2);
    McapReader r(path);
    std::map<std::uint16_t, McapChannel> channels;
    std::map<std::uint16_t, std::uint64_t> counts;
    ASSERT_TRUE(r.summary(channels, counts));
    ASSERT_EQ(channels.size(), 1u);
    EXPECT_EQ(channels.begin()->second.topic, "/imu0");
    EXPECT_EQ(channels.begin()->second.schema_name, "sensor_msgs/msg/Imu");
    EXPECT_EQ(counts.begin()->second, 300u);
    McapMessage m;
    int k = 0;
    while (r.next(m)) {
      const ImuSample s = decodeRos2Imu(m.data, m.size);
      EXPECT_EQ(s.gyr_b.x(), 0.001 * k);
      EXPECT_EQ(m.log_time_ns, static_cast<std::uint64_t>(s.t_ns));
      ++k;
    }
    EXPECT_EQ(k, 300);
    EXPECT_EQ(r.compressions(), std::vector<std::string>{comp});
  }
}

TEST(Mcap, ACutOrChangedFileIsRefusedWithItsByteOffset) {
  const std::string path = writeImuMcap("imu_cut.mcap", "zstd", 300, 4096);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const std::size_t keep : {bytes.size() / 2, bytes.size() - 3, std::size_t{20}}) {
    const std::string cut = scratch("cut.mcap");
    std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(keep));
    try {
      McapReader r(cut);
      McapMessage m;
      while (r.next(m)) {
      }
      ADD_FAILURE() << "a file cut at " << keep << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not a readable MCAP file (truncated or damaged?): byte "),
                std::string::npos)
          << e.what();
    }
  }
  std::string changed = bytes;
  std::size_t pos = 8, length = 0;  // the first chunk record (opcode 6): change a byte of its data
  for (; pos + 9 <= bytes.size(); pos += 9 + length) {
    std::memcpy(&length, bytes.data() + pos + 1, 8);
    if (bytes[pos] == 6) break;
  }
  ASSERT_LT(pos + 9 + length, bytes.size());
  changed[pos + 9 + length / 2] = static_cast<char>(changed[pos + 9 + length / 2] ^ 0x5A);
  const std::string bad = scratch("changed.mcap");
  std::ofstream(bad, std::ios::binary).write(changed.data(), static_cast<std::streamsize>(changed.size()));
  McapReader r(bad);
  McapMessage m;
  EXPECT_THROW(
      {
        while (r.next(m)) {
        }
      },
      InputError);
}

}  // namespace
}  // namespace idyvins::io
