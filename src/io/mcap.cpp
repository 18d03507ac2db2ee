#include "io/mcap.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "core/error.h"

namespace idyvins::io {
namespace {

constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr std::size_t kMcapMagicSize = 8;
namespace op {  // record opcodes
constexpr std::uint8_t kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
                       kStatistics = 0x0B, kDataEnd = 0x0F;
}
constexpr std::size_t kFooterSize = 1 + 8 + 20;  // opcode, length, summary_start, summary_offset_start, crc

/// Little-endian fields of one record's content, each checked against its end.
class Fields {
 public:
  Fields(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool ok(std::size_t n) const { return n <= size_ - pos_; }
  template <typename T>
  bool get(T& v) {
    if (!ok(sizeof(T))) return false;
    std::uint64_t x = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) x |= static_cast<std::uint64_t>(data_[pos_ + i]) << (8 * i);
    v = static_cast<T>(x);
    pos_ += sizeof(T);
    return true;
  }
  bool str(std::string& s) {
    std::uint32_t n = 0;
    if (!get(n) || !ok(n)) return false;
    s.assign(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return true;
  }
  bool skip(std::size_t n) {
    if (!ok(n)) return false;
    pos_ += n;
    return true;
  }
  const std::uint8_t* here() const { return data_ + pos_; }
  std::size_t left() const { return size_ - pos_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_, pos_ = 0;
};

std::string opcodeName(std::uint8_t op) {
  static const char* names[] = {
      "",         "header",         "footer",         "schema",     "channel",          "message",
      "chunk",    "message index",  "chunk index",    "attachment", "attachment index", "statistics",
      "metadata", "metadata index", "summary offset", "data end"};
  return op < 16 ? names[op] : "opcode " + std::to_string(op);
}

}  // namespace

void McapReader::fail(std::uint64_t offset, const std::string& what) const {
  throw InputError(path_,
                   "not a readable MCAP file (truncated or damaged?): byte " + std::to_string(offset) + ": " + what);
}

McapReader::McapReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
  std::error_code ec;
  size_ = std::filesystem::file_size(path, ec);
  if (!in_ || ec) throw InputError(path, "cannot open");
  char magic[kMcapMagicSize] = {};
  in_.read(magic, kMcapMagicSize);
  if (in_.gcount() != kMcapMagicSize || std::string(magic, kMcapMagicSize) != std::string(kMcapMagic, kMcapMagicSize))
    fail(0, "no MCAP magic at the start");
  data_end_ = size_;
  bool footer = false;
  if (size_ >= 2 * kMcapMagicSize + kFooterSize) {  // the footer: summary position
    std::uint8_t tail[kFooterSize + kMcapMagicSize];
    in_.seekg(static_cast<std::streamoff>(size_ - sizeof tail));
    in_.read(reinterpret_cast<char*>(tail), sizeof tail);
    if (std::string(reinterpret_cast<char*>(tail + kFooterSize), kMcapMagicSize) ==
            std::string(kMcapMagic, kMcapMagicSize) &&
        tail[0] == op::kFooter) {
      Fields f(tail + 9, 20);
      std::uint64_t summary_offset_start = 0;
      f.get(summary_start_);
      f.get(summary_offset_start);
      footer = true;
      data_end_ = size_ - sizeof tail;
      if (summary_start_ > data_end_) fail(size_ - sizeof tail, "the footer's summary start is past the footer");
      if (summary_start_ > 0) data_end_ = summary_start_;
    }
  }
  rewind();
  if (!footer) {  // cut short: find where, for the message
    Record r;
    while (nextRecord(r)) {
    }
    fail(pos_, "the file ends without a footer and closing magic (recording interrupted?)");
  }
}

void McapReader::rewind() {
  in_.clear();
  pos_ = kMcapMagicSize;
  in_.seekg(static_cast<std::streamoff>(pos_));
  in_chunk_ = false;
  done_ = false;
}

bool McapReader::nextRecord(Record& r) {
  if (in_chunk_) {
    if (chunk_pos_ < chunk_.size()) {
      if (chunk_.size() - chunk_pos_ < 9) fail(chunk_offset_, "a record inside the chunk is cut short");
      Fields f(chunk_.data() + chunk_pos_, 9);
      std::uint64_t len = 0;
      f.get(r.opcode);
      f.get(len);
      if (len > chunk_.size() - chunk_pos_ - 9)
        fail(chunk_offset_, "a " + opcodeName(r.opcode) + " record inside the chunk claims " + std::to_string(len) +
                                " bytes, past the chunk's end");
      r.offset = chunk_offset_;
      r.data = chunk_.data() + chunk_pos_ + 9;
      r.size = static_cast<std::size_t>(len);
      chunk_pos_ += 9 + r.size;
      return true;
    }
    in_chunk_ = false;
  }
  if (done_ || pos_ >= data_end_) return false;
  if (data_end_ - pos_ < 9) fail(pos_, "a record header is cut short");
  std::uint8_t head[9];
  in_.read(reinterpret_cast<char*>(head), 9);
  if (!in_) fail(pos_, "cannot read a record header");
  Fields f(head, 9);
  std::uint64_t len = 0;
  f.get(r.opcode);
  f.get(len);
  if (len > data_end_ - pos_ - 9)
    fail(pos_, "the " + opcodeName(r.opcode) + " record claims " + std::to_string(len) + " bytes, the file has " +
                   std::to_string(data_end_ - pos_ - 9) + " after it");
  r.offset = pos_;
  if (r.opcode == op::kFooter || r.opcode == op::kDataEnd) {
    done_ = true;
    return false;
  }
  if (r.opcode == op::kMessage || r.opcode == op::kChunk || r.opcode == op::kSchema || r.opcode == op::kChannel ||
      r.opcode == op::kHeader) {
    record_.resize(static_cast<std::size_t>(len));
    in_.read(reinterpret_cast<char*>(record_.data()), static_cast<std::streamsize>(len));
    if (!in_) fail(pos_, "cannot read the record");
    r.data = record_.data();
    r.size = record_.size();
  } else {  // indexes, attachments, metadata: not needed
    in_.seekg(static_cast<std::streamoff>(len), std::ios::cur);
    r.data = nullptr;
    r.size = 0;
  }
  pos_ += 9 + len;
  return true;
}

void McapReader::readChunk(const Record& r) {
  Fields f(r.data, r.size);
  std::uint64_t start = 0, end = 0, uncompressed = 0, records = 0;
  std::uint32_t crc = 0;
  std::string compression;
  if (!f.get(start) || !f.get(end) || !f.get(uncompressed) || !f.get(crc) || !f.str(compression) || !f.get(records) ||
      records > f.left())
    fail(r.offset, "the chunk's fields run past the record");
  if (uncompressed > (std::uint64_t{1} << 30))
    fail(r.offset, "the chunk claims " + std::to_string(uncompressed) + " bytes uncompressed (more than 1 GiB)");
  const std::string name = compression.empty() ? "none" : compression;
  if (std::find(compressions_.begin(), compressions_.end(), name) == compressions_.end()) compressions_.push_back(name);
  const std::uint8_t* src = f.here();
  const std::size_t n = static_cast<std::size_t>(records);
  // The size claimed, checked against what the compressed data can hold before it is allocated.
  if (compression.empty() && n != uncompressed)
    fail(r.offset, "an uncompressed chunk whose size differs from its records'");
  if (compression == "zstd") {
    const unsigned long long content = ZSTD_getFrameContentSize(src, n);  // the first frame's, when it says
    if (content == ZSTD_CONTENTSIZE_ERROR || (content != ZSTD_CONTENTSIZE_UNKNOWN && content > uncompressed))
      fail(r.offset, "the zstd chunk's frame does not fit the " + std::to_string(uncompressed) + " bytes it claims");
  }
  if (compression == "lz4" && uncompressed > 256 * static_cast<std::uint64_t>(n) + 4096)
    fail(r.offset, "the lz4 chunk cannot hold the " + std::to_string(uncompressed) + " bytes it claims");
  chunk_.resize(static_cast<std::size_t>(uncompressed));
  if (compression.empty()) {
    std::copy(src, src + n, chunk_.begin());
  } else if (compression == "zstd") {
    const std::size_t got = ZSTD_decompress(chunk_.data(), chunk_.size(), src, n);
    if (ZSTD_isError(got) || got != chunk_.size())
      fail(r.offset, std::string("the zstd chunk does not decompress: ") +
                         (ZSTD_isError(got) ? ZSTD_getErrorName(got) : "wrong size"));
  } else if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) fail(r.offset, "lz4 context");
    std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> guard(ctx, LZ4F_freeDecompressionContext);
    std::size_t out_pos = 0, in_pos = 0, hint = 1;
    while (hint != 0 && in_pos < n) {
      std::size_t out_n = chunk_.size() - out_pos, in_n = n - in_pos;
      hint = LZ4F_decompress(ctx, chunk_.data() + out_pos, &out_n, src + in_pos, &in_n, nullptr);
      if (LZ4F_isError(hint))
        fail(r.offset, std::string("the lz4 chunk does not decompress: ") + LZ4F_getErrorName(hint));
      out_pos += out_n;
      in_pos += in_n;
      if (out_n == 0 && in_n == 0) break;
    }
    if (out_pos != chunk_.size()) fail(r.offset, "the lz4 chunk decompresses to the wrong size");
  } else {
    fail(r.offset, "chunk compression '" + compression + "' is not read (none, zstd, lz4)");
  }
  if (crc != 0 && static_cast<std::uint32_t>(::crc32(0L, chunk_.data(), static_cast<uInt>(chunk_.size()))) != crc)
    fail(r.offset, "the chunk's CRC does not match its data");
  chunk_offset_ = r.offset;
  chunk_pos_ = 0;
  in_chunk_ = true;
}

void McapReader::takeSchemaOrChannel(const Record& r) {
  Fields f(r.data, r.size);
  if (r.opcode == op::kSchema) {
    std::uint16_t id = 0;
    std::string name, encoding;
    if (!f.get(id) || !f.str(name) || !f.str(encoding)) fail(r.offset, "the schema's fields run past the record");
    schemas_[id] = {name, encoding};
    return;
  }
  McapChannel c;
  std::uint16_t schema = 0;
  if (!f.get(c.id) || !f.get(schema) || !f.str(c.topic) || !f.str(c.message_encoding))
    fail(r.offset, "the channel's fields run past the record");
  const auto s = schemas_.find(schema);
  if (schema != 0 && s == schemas_.end()) fail(r.offset, "channel '" + c.topic + "' names an unknown schema");
  if (s != schemas_.end()) std::tie(c.schema_name, c.schema_encoding) = s->second;
  channels_[c.id] = c;
}

bool McapReader::next(McapMessage& m) {
  Record r;
  while (nextRecord(r)) {
    if (r.opcode == op::kChunk) {
      readChunk(r);
    } else if (r.opcode == op::kSchema || r.opcode == op::kChannel) {
      takeSchemaOrChannel(r);
    } else if (r.opcode == op::kMessage) {
      Fields f(r.data, r.size);
      std::uint32_t sequence = 0;
      std::uint64_t publish = 0;
      if (!f.get(m.channel_id) || !f.get(sequence) || !f.get(m.log_time_ns) || !f.get(publish))
        fail(r.offset, "a message's fields run past its record");
      if (!channels_.count(m.channel_id))
        fail(r.offset, "a message on channel " + std::to_string(m.channel_id) + " before that channel's record");
      m.data = f.here();
      m.size = f.left();
      return true;
    }
  }
  return false;
}

const McapChannel* McapReader::channel(std::uint16_t id) const {
  const auto it = channels_.find(id);
  return it == channels_.end() ? nullptr : &it->second;
}

bool McapReader::summary(std::map<std::uint16_t, McapChannel>& channels,
                         std::map<std::uint16_t, std::uint64_t>& counts) {
  if (summary_start_ == 0) return false;
  const std::uint64_t end = size_ - kMcapMagicSize - kFooterSize;
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(summary_start_));
  bool stats = false;
  for (std::uint64_t pos = summary_start_; pos < end;) {
    std::uint8_t head[9];
    in_.read(reinterpret_cast<char*>(head), 9);
    Fields h(head, 9);
    Record r;
    std::uint64_t len = 0;
    h.get(r.opcode);
    h.get(len);
    if (!in_ || len > end - pos - 9) fail(pos, "a summary record runs past the footer");
    record_.resize(static_cast<std::size_t>(len));
    in_.read(reinterpret_cast<char*>(record_.data()), static_cast<std::streamsize>(len));
    r.offset = pos;
    r.data = record_.data();
    r.size = record_.size();
    if (r.opcode == op::kSchema || r.opcode == op::kChannel) takeSchemaOrChannel(r);
    if (r.opcode == op::kStatistics) {
      Fields f(r.data, r.size);
      std::uint32_t map_bytes = 0;
      if (!f.skip(8 + 2 + 4 * 4 + 8 + 8) || !f.get(map_bytes) || map_bytes > f.left() || map_bytes % 10 != 0)
        fail(pos, "the statistics record is malformed");
      for (std::uint32_t k = 0; k < map_bytes / 10; ++k) {
        std::uint16_t id = 0;
        std::uint64_t n = 0;
        f.get(id);
        f.get(n);
        counts[id] = n;
      }
      stats = true;
    }
    pos += 9 + len;
  }
  channels = channels_;
  rewind();
  return stats;
}

}  // namespace idyvins::io
