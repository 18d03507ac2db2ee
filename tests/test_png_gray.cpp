// decodeGrayPng against OpenCV's libpng on real EuRoC images and on PNGs written here with each
// of the five row filters; other PNG kinds left to OpenCV; corrupt bytes refused with a reason.

#include <gtest/gtest.h>
#include <libdeflate.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "io/png_gray.h"
#include "test_util.h"

namespace idyvins::io {
namespace {

using Bytes = std::vector<unsigned char>;

void put32(Bytes& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<unsigned char>(v >> s));
}

void putChunk(Bytes& png, const char* type, const Bytes& body) {
  put32(png, static_cast<std::uint32_t>(body.size()));
  Bytes typed(type, type + 4);
  typed.insert(typed.end(), body.begin(), body.end());
  png.insert(png.end(), typed.begin(), typed.end());
  put32(png, libdeflate_crc32(0, typed.data(), typed.size()));
}

int paethOf(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

/// Row y of `image` filtered with `filter` (PNG's five filters, one byte per pixel).
Bytes filteredRow(const cv::Mat& image, int y, int filter) {
  Bytes row{static_cast<unsigned char>(filter)};
  for (int x = 0; x < image.cols; ++x) {
    const int v = image.at<unsigned char>(y, x), a = x ? image.at<unsigned char>(y, x - 1) : 0;
    const int b = y ? image.at<unsigned char>(y - 1, x) : 0, c = (x && y) ? image.at<unsigned char>(y - 1, x - 1) : 0;
    const int predictor = filter == 1   ? a
                          : filter == 2 ? b
                          : filter == 3 ? (a + b) / 2
                          : filter == 4 ? paethOf(a, b, c)
                                        : 0;
    row.push_back(static_cast<unsigned char>((v - predictor) & 0xff));
  }
  return row;
}

/// An 8-bit gray PNG of `image`, row y filtered with filter_of(y); IHDR's bytes as given.
template <class F>
Bytes writePng(const cv::Mat& image, F filter_of, int bit_depth = 8, int color = 0, int interlace = 0) {
  Bytes raw;
  for (int y = 0; y < image.rows; ++y) {
    const Bytes row = filteredRow(image, y, filter_of(y));
    raw.insert(raw.end(), row.begin(), row.end());
  }
  libdeflate_compressor* z = libdeflate_alloc_compressor(6);
  Bytes idat(libdeflate_zlib_compress_bound(z, raw.size()));
  idat.resize(libdeflate_zlib_compress(z, raw.data(), raw.size(), idat.data(), idat.size()));
  libdeflate_free_compressor(z);
  Bytes png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, ihdr;
  put32(ihdr, static_cast<std::uint32_t>(image.cols));
  put32(ihdr, static_cast<std::uint32_t>(image.rows));
  for (int v : {bit_depth, color, 0, 0, interlace}) ihdr.push_back(static_cast<unsigned char>(v));
  putChunk(png, "IHDR", ihdr);
  putChunk(png, "IDAT", Bytes(idat.begin(), idat.begin() + static_cast<long>(idat.size() / 2)));  // two IDATs
  putChunk(png, "IDAT", Bytes(idat.begin() + static_cast<long>(idat.size() / 2), idat.end()));
  putChunk(png, "IEND", {});
  return png;
}

cv::Mat randomImage(int rows, int cols, unsigned seed) {
  cv::Mat image(rows, cols, CV_8UC1);
  std::mt19937 rng(seed);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) image.at<unsigned char>(y, x) = static_cast<unsigned char>(rng() % 256);
  return image;
}

GrayPng decode(const Bytes& png, cv::Mat& out, std::string& why) {
  return decodeGrayPng(png.data(), png.size(), out, why);
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(PngGray, EveryFilterOnEveryRowDecodesToTheImageAsOpenCV) {
  const cv::Mat image = randomImage(23, 37, 7);
  for (int shift = 0; shift < 5; ++shift) {  // the first row with each filter too
    const Bytes png = writePng(image, [&](int y) { return (y + shift) % 5; });
    cv::Mat out;
    std::string why;
    ASSERT_EQ(decode(png, out, why), GrayPng::kDecoded) << why;
    EXPECT_TRUE(same(out, image)) << "shift " << shift;
    EXPECT_TRUE(same(out, cv::imdecode(png, cv::IMREAD_GRAYSCALE)));
  }
}

TEST(PngGray, RealEurocImagesDecodeAsOpenCV) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::sharedData("euroc_v101_micro/mav0/cam0/data"))) {
    if (++n > 8) break;
    std::ifstream f(e.path(), std::ios::binary);
    const Bytes png((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    cv::Mat out;
    std::string why;
    ASSERT_EQ(decode(png, out, why), GrayPng::kDecoded) << e.path() << ": " << why;
    EXPECT_EQ(out.size(), cv::Size(752, 480));
    EXPECT_TRUE(same(out, cv::imdecode(png, cv::IMREAD_GRAYSCALE))) << e.path();
  }
  EXPECT_EQ(n, 9);
}

TEST(PngGray, OtherKindsAreLeftToOpenCV) {
  const cv::Mat gray = randomImage(8, 9, 3);
  Bytes rgb, deep;
  cv::Mat colour;
  cv::cvtColor(gray, colour, cv::COLOR_GRAY2BGR);
  ASSERT_TRUE(cv::imencode(".png", colour, rgb));
  cv::Mat wide;
  gray.convertTo(wide, CV_16U, 200.0);
  ASSERT_TRUE(cv::imencode(".png", wide, deep));
  const auto none = [](int) { return 0; };
  for (const Bytes& png : {rgb, deep, writePng(gray, none, 8, 0, 1), writePng(gray, none, 16, 0, 0),
                           Bytes{'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g'}}) {
    cv::Mat out;
    std::string why;
    EXPECT_EQ(decode(png, out, why), GrayPng::kOtherKind);
    EXPECT_TRUE(out.empty());
  }
}

TEST(PngGray, CorruptBytesAreRefusedWithWhere) {
  const cv::Mat image = randomImage(16, 20, 5);
  const Bytes good = writePng(image, [](int y) { return y % 5; });
  const auto refused = [](const Bytes& png, const std::string& expected) {
    cv::Mat out;
    std::string why;
    EXPECT_EQ(decode(png, out, why), GrayPng::kCorrupt) << expected;
    EXPECT_NE(why.find(expected), std::string::npos) << why;
  };
  Bytes flipped = good;
  flipped[8 + 25 + 8 + 3] ^= 0x10;  // a byte of the first IDAT's data
  refused(flipped, "CRC mismatch in the IDAT chunk at byte 33");
  refused(Bytes(good.begin(), good.end() - 12), "no IEND chunk");
  refused(Bytes(good.begin(), good.end() - 5), "a chunk cut short");
  // Well-formed chunks around bad content: one row too many in IHDR, a filter type of 7, a stream that is not zlib.
  cv::Mat taller;
  cv::vconcat(image, image.row(0), taller);
  Bytes short_data = writePng(image, [](int) { return 0; });
  const Bytes tall_header = writePng(taller, [](int) { return 0; });
  std::copy(tall_header.begin() + 8, tall_header.begin() + 33, short_data.begin() + 8);  // IHDR of 17 rows
  refused(short_data, "the image data do not hold 20x17 pixels");
  refused(writePng(image, [](int y) { return y == 3 ? 7 : 0; }), "row 3 has filter type 7");
  Bytes not_zlib{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  not_zlib.insert(not_zlib.end(), good.begin() + 8, good.begin() + 33);
  putChunk(not_zlib, "IDAT", {1, 2, 3, 4, 5, 6});
  putChunk(not_zlib, "IEND", {});
  refused(not_zlib, "do not inflate");
}

}  // namespace
}  // namespace idyvins::io
