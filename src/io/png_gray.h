#pragma once
// The PNGs a VIO system reads most, 8-bit grayscale and not interlaced (EuRoC's cameras, the
// renders of `idyvins simulate`), decoded with libdeflate: about twice as fast as OpenCV's
// libpng on the renders (docs/performance.md). Every chunk's CRC-32 and the image data's
// Adler-32 are checked; any other kind of PNG, or other bytes, is left to cv::imdecode.

#include <cstddef>
#include <opencv2/core/mat.hpp>
#include <string>

namespace idyvins::io {

enum class GrayPng {
  kDecoded,    ///< an 8-bit grayscale, non-interlaced PNG, decoded into `out`
  kOtherKind,  ///< another PNG kind, or not a PNG: `out` untouched, decode with cv::imdecode
  kCorrupt,    ///< a PNG of that kind whose bytes do not hold an image; `why` says where
};

/// Decodes `size` bytes held at `data`. `out` becomes CV_8UC1 when kDecoded; `why` is one line
/// (chunk and byte offset, or the row) when kCorrupt.
GrayPng decodeGrayPng(const unsigned char* data, std::size_t size, cv::Mat& out, std::string& why);

}  // namespace idyvins::io
