#include "io/png_gray.h"

#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

namespace idyvins::io {

namespace {

constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 28;  // larger ones go to OpenCV

std::uint32_t bigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

GrayPng corrupt(std::string& why, std::string text) {
  why = std::move(text);
  return GrayPng::kCorrupt;
}

bool isType(const unsigned char* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

/// The header and the concatenated image data of a PNG.
struct Chunks {
  std::uint32_t width = 0, height = 0;
  std::vector<unsigned char> idat;
};

/// Walks the chunks (lengths and CRCs checked); kDecoded here means "of the fast path's kind".
GrayPng readChunks(const unsigned char* data, std::size_t size, Chunks& c, std::string& why) {
  std::size_t at = 8;
  bool iend = false;
  while (!iend && at < size) {
    const std::string where = " at byte " + std::to_string(at);
    if (size - at < 12) return corrupt(why, "a chunk cut short" + where);
    const std::uint32_t len = bigEndian32(data + at);
    if (len > 0x7fffffffu || len > size - at - 12) return corrupt(why, "a chunk runs past the end" + where);
    const unsigned char* type = data + at + 4;
    const unsigned char* body = type + 4;
    const std::string name(reinterpret_cast<const char*>(type), 4);
    if (libdeflate_crc32(0, type, 4 + std::size_t{len}) != bigEndian32(body + len))
      return corrupt(why, "CRC mismatch in the " + name + " chunk" + where);
    if (at == 8 && (!isType(type, "IHDR") || len != 13)) return corrupt(why, "the first chunk is not a 13-byte IHDR");
    if (isType(type, "IHDR")) {
      c.width = bigEndian32(body);
      c.height = bigEndian32(body + 4);
      if (c.width == 0 || c.height == 0) return corrupt(why, "IHDR gives a zero width or height");
      if (body[10] != 0 || body[11] != 0) return corrupt(why, "IHDR names an unknown compression or filter method");
      const bool gray8 = body[8] == 8 && body[9] == 0 && body[12] == 0;
      if (!gray8 || std::uint64_t{c.width} * c.height > kMaxPixels) return GrayPng::kOtherKind;
    } else if (isType(type, "IDAT")) {
      c.idat.insert(c.idat.end(), body, body + len);
    } else if (isType(type, "IEND")) {
      iend = true;
    } else if ((type[0] & 0x20) == 0) {
      return GrayPng::kOtherKind;  // another critical chunk (a palette): libpng's to judge
    }
    at += 12 + std::size_t{len};
  }
  if (!iend) return corrupt(why, "no IEND chunk");
  if (c.idat.empty()) return corrupt(why, "no IDAT chunk");
  return GrayPng::kDecoded;
}

/// Undoes the filter of one row (one byte per pixel); `up` is null on the first row.
bool unfilterRow(int filter, const unsigned char* in, const unsigned char* up, unsigned char* out, int width) {
  switch (filter) {
    case 0:
      std::memcpy(out, in, static_cast<std::size_t>(width));
      return true;
    case 1: {
      unsigned a = 0;
      for (int x = 0; x < width; ++x) out[x] = static_cast<unsigned char>(a = (in[x] + a) & 0xffu);
      return true;
    }
    case 2:
      for (int x = 0; x < width; ++x) out[x] = static_cast<unsigned char>(in[x] + (up ? up[x] : 0));
      return true;
    case 3: {
      unsigned a = 0;
      for (int x = 0; x < width; ++x)
        out[x] = static_cast<unsigned char>(a = (in[x] + ((a + (up ? up[x] : 0u)) >> 1)) & 0xffu);
      return true;
    }
    case 4: {
      int a = 0, c = 0;  // left and upper-left; with no row above, Paeth is the left pixel
      for (int x = 0; x < width; ++x) {
        const int b = up ? up[x] : 0;
        const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
        const int predictor = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
        out[x] = static_cast<unsigned char>(a = (in[x] + predictor) & 0xff);
        c = b;
      }
      return true;
    }
    default:
      return false;
  }
}

}  // namespace

GrayPng decodeGrayPng(const unsigned char* data, std::size_t size, cv::Mat& out, std::string& why) {
  if (size < 8 || std::memcmp(data, kSignature, 8) != 0) return GrayPng::kOtherKind;
  Chunks c;
  const GrayPng kind = readChunks(data, size, c, why);
  if (kind != GrayPng::kDecoded) return kind;
  const int width = static_cast<int>(c.width), height = static_cast<int>(c.height);
  const std::size_t stride = std::size_t{c.width} + 1;
  std::vector<unsigned char> raw(stride * c.height);
  const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> inflater(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  if (!inflater) return corrupt(why, "out of memory for the decompressor");
  std::size_t got = 0;
  const libdeflate_result r =
      libdeflate_zlib_decompress(inflater.get(), c.idat.data(), c.idat.size(), raw.data(), raw.size(), &got);
  if (r == LIBDEFLATE_INSUFFICIENT_SPACE || (r == LIBDEFLATE_SUCCESS && got != raw.size()))
    return why =
               "the image data do not hold " + std::to_string(width) + "x" + std::to_string(height) + " pixels (IHDR)",
           GrayPng::kCorrupt;
  if (r != LIBDEFLATE_SUCCESS) return corrupt(why, "the image data do not inflate (a broken zlib stream)");
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    const unsigned char* row = raw.data() + static_cast<std::size_t>(y) * stride;
    if (!unfilterRow(row[0], row + 1, y > 0 ? image.ptr<unsigned char>(y - 1) : nullptr, image.ptr<unsigned char>(y),
                     width))
      return corrupt(why,
                     "row " + std::to_string(y) + " has filter type " + std::to_string(row[0]) + " (0-4 expected)");
  }
  out = image;
  return GrayPng::kDecoded;
}

}  // namespace idyvins::io
