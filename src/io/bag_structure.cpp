#include "io/bag_structure.h"

#include <cstring>
#include <map>
#include <set>
#include <vector>

namespace idyvins::io {
namespace {

constexpr std::uint64_t kMagicSize = 13;
constexpr std::uint32_t kMaxHeader = 1u << 20;  // record headers are a few fields
enum Op : std::uint8_t { kMessage = 2, kBagHeader = 3, kIndex = 4, kChunk = 5, kChunkInfo = 6, kConnection = 7 };

/// A problem found: stops the walk.
struct Bad {
  std::string what;
};

[[noreturn]] void bad(std::uint64_t at, const std::string& what) {
  throw Bad{"byte " + std::to_string(at) + ": " + what};
}

std::uint32_t u32(const char* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);  // bags are little-endian, like every machine idyvins builds for
  return v;
}
std::uint64_t u64(const char* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

/// "name=value" fields, each prefixed by its 32-bit length, filling `bytes` exactly.
std::map<std::string, std::string> parseFields(const std::string& bytes, std::uint64_t at, const char* what) {
  std::map<std::string, std::string> fields;
  std::size_t p = 0;
  while (p < bytes.size()) {
    if (bytes.size() - p < 4) bad(at + p, std::string(what) + ": field length cut short");
    const std::uint32_t len = u32(bytes.data() + p);
    p += 4;
    if (len > bytes.size() - p)
      bad(at + p - 4, std::string(what) + ": field of " + std::to_string(len) + " bytes, " +
                          std::to_string(bytes.size() - p) + " left");
    const std::string field = bytes.substr(p, len);
    const auto eq = field.find('=');
    if (eq == std::string::npos) bad(at + p, std::string(what) + ": field without '='");
    fields[field.substr(0, eq)] = field.substr(eq + 1);
    p += len;
  }
  return fields;
}

struct Record {
  std::uint64_t pos = 0, data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint8_t op = 0;
  std::map<std::string, std::string> fields;
  std::uint64_t end() const { return data_pos + data_len; }
};

class Walker {
 public:
  Walker(std::istream& in, std::uint64_t size) : in_(in), size_(size) {}

  void walk() {
    std::uint64_t pos = kMagicSize;
    const Record header = read(pos, size_);
    if (header.op != kBagHeader) bad(pos, "the first record is not the bag header");
    const std::uint64_t index_pos = number(header, "index_pos", 8);
    const std::uint32_t conn_count = static_cast<std::uint32_t>(number(header, "conn_count", 4));
    const std::uint32_t chunk_count = static_cast<std::uint32_t>(number(header, "chunk_count", 4));
    std::vector<Record> top;
    for (pos = header.end(); pos < size_;) {
      top.push_back(read(pos, size_));
      pos = top.back().end();
    }
    if (index_pos == 0) return;  // unindexed: rosbag says so itself
    checkTop(top, index_pos, conn_count, chunk_count);
  }

 private:
  std::string bytes(std::uint64_t pos, std::uint32_t n) {
    std::string b(n, '\0');
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(pos));
    in_.read(b.data(), n);
    if (static_cast<std::uint32_t>(in_.gcount()) != n) bad(pos, "cannot read " + std::to_string(n) + " bytes");
    return b;
  }

  /// The record at `pos`, which must end by `end`.
  Record read(std::uint64_t pos, std::uint64_t end) {
    Record r;
    r.pos = pos;
    if (end - pos < 4) bad(pos, "record cut short");
    const std::uint32_t header_len = u32(bytes(pos, 4).data());
    if (header_len > kMaxHeader || header_len + 8ull > end - pos)
      bad(pos, "record header of " + std::to_string(header_len) + " bytes does not fit");
    r.fields = parseFields(bytes(pos + 4, header_len), pos + 4, "record header");
    const auto op = r.fields.find("op");
    if (op == r.fields.end() || op->second.size() != 1) bad(pos, "record without a one-byte op field");
    r.op = static_cast<std::uint8_t>(op->second[0]);
    r.data_pos = pos + 8 + header_len;
    r.data_len = u32(bytes(pos + 4 + header_len, 4).data());
    if (r.data_len > end - r.data_pos) bad(pos, "record data of " + std::to_string(r.data_len) + " bytes does not fit");
    if (r.op == kConnection) parseFields(bytes(r.data_pos, r.data_len), r.data_pos, "connection header");
    return r;
  }

  static std::uint64_t number(const Record& r, const char* name, std::size_t width) {
    const auto f = r.fields.find(name);
    if (f == r.fields.end() || f->second.size() != width)
      bad(r.pos, std::string("field ") + name + " missing or not " + std::to_string(width) + " bytes");
    return width == 8 ? u64(f->second.data()) : u32(f->second.data());
  }

  /// Starts of the records inside an uncompressed chunk (offsets from its data).
  std::set<std::uint32_t> chunkRecords(const Record& chunk) {
    std::set<std::uint32_t> starts;
    for (std::uint64_t pos = chunk.data_pos; pos < chunk.end();) {
      const Record r = read(pos, chunk.end());
      if (r.op != kMessage && r.op != kConnection) bad(pos, "a chunk holds a record of op " + std::to_string(r.op));
      if (r.op == kMessage) {
        number(r, "conn", 4);
        number(r, "time", 8);
      }
      starts.insert(static_cast<std::uint32_t>(pos - chunk.data_pos));
      pos = r.end();
    }
    return starts;
  }

  void checkTop(const std::vector<Record>& top, std::uint64_t index_pos, std::uint32_t conn_count,
                std::uint32_t chunk_count) {
    std::set<std::uint64_t> chunk_positions;
    std::set<std::uint32_t> starts;  // of the last chunk's records
    std::uint64_t chunk_size = 0;
    bool compressed = false, index_found = false;
    std::uint64_t connections = 0, infos = 0;
    for (const Record& r : top) {
      if (r.pos == index_pos) index_found = true;
      if (r.op == kChunk) {
        const auto c = r.fields.find("compression");
        if (c == r.fields.end()) bad(r.pos, "chunk without compression field");
        chunk_size = number(r, "size", 4);
        compressed = c->second != "none";
        if (!compressed && chunk_size != r.data_len) bad(r.pos, "uncompressed chunk whose size is not its data length");
        starts = compressed ? std::set<std::uint32_t>{} : chunkRecords(r);
        chunk_positions.insert(r.pos);
      } else if (r.op == kIndex) {
        checkIndex(r, starts, chunk_size, compressed);
      } else if (r.op == kChunkInfo) {
        const std::uint64_t count = number(r, "count", 4);
        if (count * 8 != r.data_len) bad(r.pos, "chunk info data is not 8 bytes per connection");
        if (!chunk_positions.count(number(r, "chunk_pos", 8))) bad(r.pos, "chunk info pointing at no chunk");
        infos += index_found ? 1 : 0;
      } else if (r.op == kConnection) {
        connections += index_found ? 1 : 0;
      }
    }
    const bool empty_index = index_pos == size_ && conn_count == 0 && chunk_count == 0;  // a bag without messages
    if (!index_found && !empty_index) bad(index_pos, "index_pos is not the start of a record");
    if (connections < conn_count || infos < chunk_count)
      bad(index_pos, "the index has fewer connections or chunk infos than the bag header says");
  }

  void checkIndex(const Record& r, const std::set<std::uint32_t>& starts, std::uint64_t chunk_size, bool compressed) {
    const std::uint64_t count = number(r, "count", 4);
    number(r, "conn", 4);
    if (number(r, "ver", 4) != 1) bad(r.pos, "index data version is not 1");
    if (count * 12 != r.data_len) bad(r.pos, "index data is not 12 bytes per message");
    const std::string entries = bytes(r.data_pos, r.data_len);
    for (std::uint64_t i = 0; i < count; ++i) {
      const std::uint32_t offset = u32(entries.data() + 12 * i + 8);
      if (compressed ? offset >= chunk_size : !starts.count(offset))
        bad(r.data_pos + 12 * i, "index entry pointing at no message of its chunk");
    }
  }

  std::istream& in_;
  std::uint64_t size_;
};

}  // namespace

std::optional<std::string> bagStructureProblem(std::istream& in, std::uint64_t size) {
  if (size < kMagicSize) return "shorter than the '#ROSBAG V2.0' line";
  try {
    Walker(in, size).walk();
  } catch (const Bad& b) {
    return b.what;
  }
  return std::nullopt;
}

}  // namespace idyvins::io
