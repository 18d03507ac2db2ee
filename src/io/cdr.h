#pragma once
// OMG CDR (XCDR1), the serialization of ROS 2 messages: a 4-byte encapsulation header
// (0x00 0x01 little-endian, 0x00 0x00 big-endian), then each primitive aligned to its own size,
// counted from the end of the header; strings as a uint32 length (with the terminating NUL) and
// the bytes; sequences as a uint32 count and the elements. Pure: no files.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace idyvins::io {

/// CDR data that does not parse (too short, a bad header, a length past the end).
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads one CDR-encoded message in place (the bytes must outlive the reader).
class CdrReader {
 public:
  /// Checks the encapsulation header. Throws CdrError.
  CdrReader(const std::uint8_t* data, std::size_t size);
  std::uint8_t u8();
  std::uint32_t u32();
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  double f64();
  /// A string without its terminating NUL.
  std::string string();
  /// A sequence<uint8>: where its bytes start (inside the message) and how many.
  const std::uint8_t* bytes(std::size_t& count);
  /// Skips `n` float64 (a fixed array).
  void skipF64(std::size_t n);
  /// Bytes read so far, the header included.
  std::size_t offset() const { return pos_; }

 private:
  void align(std::size_t n);
  void need(std::size_t n) const;
  /// An unsigned integer of `n` bytes (4 or 8), aligned and in the message's byte order.
  std::uint64_t word(std::size_t n);
  const std::uint8_t* data_;
  std::size_t size_, pos_ = 4;
  bool big_endian_ = false;
};

/// Writes one CDR message, little-endian (what ROS 2 publishes on x86 and ARM).
class CdrWriter {
 public:
  CdrWriter();
  void u8(std::uint8_t v);
  void u32(std::uint32_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f64(double v);
  void string(const std::string& s);
  void bytes(const std::uint8_t* data, std::size_t count);
  const std::vector<std::uint8_t>& data() const { return buf_; }

 private:
  void align(std::size_t n);
  std::vector<std::uint8_t> buf_;
};

}  // namespace idyvins::io
