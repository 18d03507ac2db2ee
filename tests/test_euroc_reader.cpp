#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "io/data_source.h"
#include "io/dataset_summary.h"
#include "io/euroc_dataset.h"
#include "test_util.h"

namespace idyvins::io {
namespace {

namespace fs = std::filesystem;
using test::expectError;
using test::sharedData;
using test::TempDir;
using test::writeFile;

const std::string kMicro = sharedData("euroc_v101_micro");

TEST(EurocReader, RealMicroDatasetCounts) {
  const EurocDataset ds = readEurocDataset(kMicro);
  EXPECT_EQ(ds.cam0.size(), 95u);
  EXPECT_EQ(ds.cam1.size(), 99u);
  EXPECT_EQ(ds.imu.size(), 29120u);
  EXPECT_EQ(ds.pairs.size(), 95u);
  EXPECT_TRUE(ds.unmatched0.empty());
  ASSERT_EQ(ds.unmatched1.size(), 4u);  // the 4 cam1 rows past the last cam0 image
  for (auto i : ds.unmatched1) EXPECT_FALSE(ds.cam1[i].exists);
  EXPECT_FALSE(ds.has_groundtruth);
  EXPECT_EQ(ds.pairs.front().t_ns, 1403715273262142976);
  EXPECT_EQ(ds.pairs.back().t_ns, 1403715277962142976);
  // First IMU row of the file, parsed exactly.
  EXPECT_EQ(ds.imu.front().t_ns, 1403715273262142976);
  EXPECT_DOUBLE_EQ(ds.imu.front().gyr_b.z(), 0.07749261878854824);
  EXPECT_DOUBLE_EQ(ds.imu.front().acc_b.x(), 9.0874956666666655);
}

TEST(EurocReader, RealMicroDatasetSummary) {
  const DatasetSummary s = summarize(readEurocDataset(kMicro));
  EXPECT_NEAR(s.imu.rate_hz, 200.0, 0.01);
  EXPECT_NEAR(s.cam0.rate_hz, 20.0, 0.01);
  EXPECT_NEAR(s.pairs.span_s, 4.70, 1e-6);
  EXPECT_NEAR(s.imu.span_s, 145.595, 1e-3);
  EXPECT_EQ(s.imu.gaps, 0u);
  EXPECT_EQ(s.pairs.gaps, 0u);
  EXPECT_EQ(s.unmatched_missing_image, 4u);
}

TEST(EurocReader, StreamIsTimeOrderedWithImuBeforeFrameAtSameStamp) {
  EurocSource source(readEurocDataset(kMicro), 752, 480);
  TimeNs last = 0;
  std::size_t frames = 0, imu = 0;
  bool first = true;
  while (auto m = source.next()) {
    const TimeNs t = std::visit([](const auto& x) { return x.t_ns; }, *m);
    EXPECT_GE(t, last);
    if (const auto* f = std::get_if<StereoFrame>(&*m)) {
      EXPECT_EQ(f->left.cols, 752);
      EXPECT_EQ(f->right.rows, 480);
      EXPECT_EQ(f->left.type(), CV_8UC1);
      if (first) {
        EXPECT_EQ(imu, 1u);  // IMU at the same stamp comes first
      }
      first = false;
      ++frames;
    } else {
      ++imu;
    }
    last = t;
  }
  EXPECT_EQ(frames, 95u);
  EXPECT_EQ(imu, 29120u);
}

TEST(EurocReader, WrongImageSizeIsAnError) {
  EurocSource source(readEurocDataset(kMicro), 640, 480);
  auto next_frame = [&] {
    while (auto m = source.next())
      if (std::holds_alternative<StereoFrame>(*m)) return;
  };
  expectError(next_frame, "cam0/data.csv:2: image");
  expectError(next_frame, "is 752x480, expected 640x480");
}

/// A tiny valid EuRoC folder: 3 stereo pairs of 16x8 images, 11 IMU samples.
class TinyEuroc : public ::testing::Test {
 protected:
  void SetUp() override {
    root = dir / "ds";
    const cv::Mat img(8, 16, CV_8UC1, cv::Scalar(128));
    for (const char* cam : {"cam0", "cam1"}) {
      fs::create_directories(root + "/mav0/" + cam + "/data");
      std::string csv = "#timestamp [ns],filename\n";
      for (int i = 0; i < 3; ++i) {
        const std::string name = std::to_string(1000 + 50 * i) + ".png";
        cv::imwrite(root + "/mav0/" + cam + "/data/" + name, img);
        csv += std::to_string(1000 + 50 * i) + "," + name + "\n";
      }
      writeFile(root + "/mav0/" + cam + "/data.csv", csv);
    }
    writeImu(imuText());
  }
  void TearDown() override {}
  std::string imuText() {
    std::string s = "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n";
    for (int i = 0; i <= 10; ++i) s += std::to_string(1000 + 10 * i) + ",0,0,0.1,0,0,9.81\n";
    return s;
  }
  void writeImu(const std::string& text) {
    fs::create_directories(root + "/mav0/imu0");
    writeFile(root + "/mav0/imu0/data.csv", text);
  }
  std::string csv(const char* rel) { return root + "/mav0/" + rel; }
  TempDir dir;
  std::string root;
};

TEST_F(TinyEuroc, Valid) {
  const EurocDataset ds = readEurocDataset(root);
  EXPECT_EQ(ds.pairs.size(), 3u);
  EXPECT_EQ(ds.imu.size(), 11u);
  // mav0 itself is accepted as well.
  EXPECT_EQ(readEurocDataset(root + "/mav0").pairs.size(), 3u);
}

TEST_F(TinyEuroc, OneCameraTakesEveryLeftImageWhetherCam1HasItsPartnerOrNot) {
  // cam1 lacks the middle image: a stereo read drops that cam0 row, a one-camera read keeps it.
  writeFile(csv("cam1/data.csv"), "#timestamp [ns],filename\n1000,1000.png\n1100,1100.png\n");
  const EurocDataset stereo = readEurocDataset(root);
  EXPECT_EQ(stereo.pairs.size(), 2u);
  EXPECT_EQ(stereo.unmatched0.size(), 1u);
  EurocOptions one;
  one.left_only = true;
  const EurocDataset mono = readEurocDataset(root, one);
  EXPECT_TRUE(mono.cam1.empty());
  ASSERT_EQ(mono.pairs.size(), 3u);
  EXPECT_EQ(mono.pairs[1].t_ns, 1050);
  EXPECT_TRUE(mono.unmatched0.empty());
}

TEST_F(TinyEuroc, MissingFolderOrFile) {
  expectError([&] { readEurocDataset(dir / "nope"); }, "nope: dataset folder does not exist");
  fs::create_directories(dir / "empty");
  expectError([&] { readEurocDataset(dir / "empty"); }, "not a EuRoC ASL folder");
  fs::remove(csv("imu0/data.csv"));
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv: cannot open");
}

TEST_F(TinyEuroc, EmptyAndHeaderOnlyCsv) {
  writeImu("");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv: file is empty");
  writeImu("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv: no data rows");
  writeFile(csv("cam0/data.csv"), "#timestamp [ns],filename\n");
  expectError([&] { readEurocDataset(root); }, "cam0/data.csv: no data rows");
}

TEST_F(TinyEuroc, WrongColumnCount) {
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1010,0,0,0,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:3: expected 7 columns, got 6");
  writeFile(csv("cam1/data.csv"), "#t,f\n1000,1000.png,extra\n");
  expectError([&] { readEurocDataset(root); }, "cam1/data.csv:2: expected 2 columns, got 3");
}

TEST_F(TinyEuroc, NonNumericAndNonFinite) {
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1010,0,zero,0,0,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:3: column 3: expected a number, got 'zero'");
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1010,0,0,0,nan,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:3: column 5: expected a finite number");
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1010,0,0,0,0,inf,9.8\n");
  expectError([&] { readEurocDataset(root); }, "column 6: expected a finite number, got 'inf'");
  writeImu("#t\n1000,0,0,0,0,0,9.8\n10x0,0,0,0,0,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:3: column 1: expected an integer time stamp");
}

TEST_F(TinyEuroc, NonIncreasingAndDuplicateStamps) {
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1010,0,0,0,0,0,9.8\n1005,0,0,0,0,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:4: non-increasing time stamp 1005");
  writeImu("#t\n1000,0,0,0,0,0,9.8\n1000,0,0,0,0,0,9.8\n");
  expectError([&] { readEurocDataset(root); }, "imu0/data.csv:3: duplicate time stamp 1000");
  writeImu(imuText());
  writeFile(csv("cam0/data.csv"), "#t,f\n1000,1000.png\n1100,1100.png\n1050,1050.png\n");
  expectError([&] { readEurocDataset(root); }, "cam0/data.csv:4: non-increasing time stamp 1050");
  writeFile(csv("cam1/data.csv"), "#t,f\n1000,1000.png\n1000,1050.png\n");
  writeFile(csv("cam0/data.csv"), "#t,f\n1000,1000.png\n");
  expectError([&] { readEurocDataset(root); }, "cam1/data.csv:3: duplicate time stamp 1000");
}

TEST_F(TinyEuroc, MissingOrUnreadableImage) {
  fs::remove(csv("cam1/data/1050.png"));
  expectError([&] { readEurocDataset(root); }, "cam1/data.csv:3: image file missing:");
  writeFile(csv("cam1/data/1050.png"), "this is not a png");
  const EurocDataset ds = readEurocDataset(root);  // exists: the reader checks the content lazily
  EurocSource source(ds, 16, 8);
  auto drain = [&] {
    while (source.next()) {
    }
  };
  expectError(drain, "cam1/data.csv:3: image file unreadable");
  // A gray PNG with one byte of its image data flipped: refused by its CRC, with the chunk named.
  std::vector<unsigned char> png;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(8, 16, CV_8UC1, cv::Scalar(90)), png));
  png[33 + 8 + 2] ^= 0x40;
  writeFile(csv("cam1/data/1050.png"), std::string(png.begin(), png.end()));
  EurocSource again(ds, 16, 8);
  expectError(
      [&] {
        while (again.next()) {
        }
      },
      "cam1/data.csv:3: image file unreadable (a corrupt PNG: CRC mismatch in the IDAT chunk at byte 33)");
}

TEST_F(TinyEuroc, UnmatchedFramesAreReportedNotErrors) {
  writeFile(csv("cam1/data.csv"), "#t,f\n1000,1000.png\n1100,1100.png\n1500,nothere.png\n");
  const EurocDataset ds = readEurocDataset(root, EurocOptions{10});  // 10 ns tolerance
  EXPECT_EQ(ds.pairs.size(), 2u);
  ASSERT_EQ(ds.unmatched0.size(), 1u);
  EXPECT_EQ(ds.cam0[ds.unmatched0[0]].t_ns, 1050);
  ASSERT_EQ(ds.unmatched1.size(), 1u);
  EXPECT_EQ(ds.cam1[ds.unmatched1[0]].t_ns, 1500);
  EXPECT_FALSE(ds.cam1[ds.unmatched1[0]].exists);
}

TEST(PairByTime, NearestWithinTolerance) {
  auto rec = [](std::vector<TimeNs> ts) {
    std::vector<ImageRecord> r;
    for (auto t : ts) r.push_back({t, "", 0, true});
    return r;
  };
  std::vector<StereoPair> pairs;
  std::vector<std::size_t> u0, u1;
  pairByTime(rec({100, 200, 300}), rec({98, 105, 203, 900}), 10, pairs, u0, u1);
  ASSERT_EQ(pairs.size(), 2u);  // 300 has no partner within 10 ns
  EXPECT_EQ(pairs[0].i1, 0u);   // |100-98| < |100-105|
  EXPECT_EQ(pairs[1].i1, 2u);
  ASSERT_EQ(u0.size(), 1u);
  EXPECT_EQ(u0[0], 2u);
  EXPECT_EQ(u1, (std::vector<std::size_t>{1, 3}));
}

TEST(StreamStats, RateGapsSpan) {
  const auto s = streamStats({0, 10, 20, 30, 70, 80});
  EXPECT_EQ(s.count, 6u);
  EXPECT_NEAR(s.rate_hz, 1e8, 1);
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_NEAR(s.max_gap_s, 40e-9, 1e-15);
  EXPECT_NEAR(s.span_s, 80e-9, 1e-15);
}

TEST(GroundTruth, ReadsEurocStateFile) {
  const auto gt = readGroundTruthCsv(sharedData("euroc_imu_gt_excerpt/mav0/gt0/data.csv"));
  ASSERT_EQ(gt.size(), 3340u);
  EXPECT_EQ(gt[0].t_ns, 1403715524922140000);
  EXPECT_DOUBLE_EQ(gt[0].p_w_b.x(), 0.515292);
  EXPECT_NEAR(gt[0].q_w_b.w(), 0.161869, 1e-5);
  EXPECT_DOUBLE_EQ(gt[0].v_w.x(), -0.006748);
  EXPECT_DOUBLE_EQ(gt[0].bg.y(), 0.020744);
  EXPECT_DOUBLE_EQ(gt[0].ba.z(), 0.093086);
}

}  // namespace
}  // namespace idyvins::io
