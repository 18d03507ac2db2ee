#include "io/cdr.h"

#include <algorithm>
#include <cstring>

namespace idyvins::io {

CdrReader::CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
  if (size < 4) throw CdrError("CDR data of " + std::to_string(size) + " bytes is shorter than its 4-byte header");
  if (data[0] != 0 || data[1] > 1)
    throw CdrError("CDR encapsulation " + std::to_string(data[0]) + "," + std::to_string(data[1]) +
                   " is not plain CDR (expected 0,1 little-endian or 0,0 big-endian)");
  big_endian_ = data[1] == 0;
}

void CdrReader::align(std::size_t n) {
  const std::size_t body = pos_ - 4;
  pos_ += (n - body % n) % n;
}

void CdrReader::need(std::size_t n) const {
  if (pos_ > size_ || n > size_ - pos_)
    throw CdrError("CDR data ends at byte " + std::to_string(size_) + ", a field at byte " + std::to_string(pos_) +
                   " needs " + std::to_string(n));
}

std::uint8_t CdrReader::u8() {
  need(1);
  return data_[pos_++];
}

std::uint64_t CdrReader::word(std::size_t n) {
  align(n);
  need(n);
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v |= std::uint64_t{data_[pos_ + (big_endian_ ? n - 1 - i : i)]} << (8 * i);
  pos_ += n;
  return v;
}

std::uint32_t CdrReader::u32() { return static_cast<std::uint32_t>(word(4)); }

double CdrReader::f64() {
  const std::uint64_t v = word(8);
  double d;
  std::memcpy(&d, &v, sizeof d);
  return d;
}

std::string CdrReader::string() {
  const std::uint32_t n = u32();
  need(n);
  if (n == 0) return {};  // some writers send an empty string as length 0
  if (data_[pos_ + n - 1] != 0) throw CdrError("CDR string at byte " + std::to_string(pos_) + " does not end with NUL");
  std::string s(reinterpret_cast<const char*>(data_ + pos_), n - 1);
  pos_ += n;
  return s;
}

const std::uint8_t* CdrReader::bytes(std::size_t& count) {
  count = u32();
  need(count);
  const std::uint8_t* p = data_ + pos_;
  pos_ += count;
  return p;
}

void CdrReader::skipF64(std::size_t n) {
  if (n == 0) return;
  align(8);
  if (n > size_) need(size_ + 1);  // more float64 than bytes: past the end
  need(8 * n);
  pos_ += 8 * n;
}

CdrWriter::CdrWriter() : buf_{0, 1, 0, 0} {}

void CdrWriter::align(std::size_t n) {
  while ((buf_.size() - 4) % n != 0) buf_.push_back(0);
}

void CdrWriter::u8(std::uint8_t v) { buf_.push_back(v); }

void CdrWriter::u32(std::uint32_t v) {
  align(4);
  for (int i = 0; i < 4; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void CdrWriter::f64(double v) {
  align(8);
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int i = 0; i < 8; ++i) buf_.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
}

void CdrWriter::string(const std::string& s) {
  u32(static_cast<std::uint32_t>(s.size() + 1));
  buf_.insert(buf_.end(), s.begin(), s.end());
  buf_.push_back(0);
}

void CdrWriter::bytes(const std::uint8_t* data, std::size_t count) {
  u32(static_cast<std::uint32_t>(count));
  buf_.insert(buf_.end(), data, data + count);
}

}  // namespace idyvins::io
