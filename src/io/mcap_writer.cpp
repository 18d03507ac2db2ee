#include "io/mcap_writer.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <fstream>
#include <map>

#include "core/error.h"

namespace idyvins::io {
namespace mcap_write {  // named: McapWriter::Impl holds these

/// Little-endian record content.
struct Bytes {
  std::vector<std::uint8_t> b;
  template <typename T>
  void put(T v) {
    for (std::size_t i = 0; i < sizeof(T); ++i)
      b.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  }
  void str(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  }
  void raw(const std::vector<std::uint8_t>& v) { b.insert(b.end(), v.begin(), v.end()); }
};

/// opcode, uint64 length, content.
void record(std::vector<std::uint8_t>& out, std::uint8_t opcode, const Bytes& content) {
  Bytes head;
  head.put(opcode);
  head.put(static_cast<std::uint64_t>(content.b.size()));
  out.insert(out.end(), head.b.begin(), head.b.end());
  out.insert(out.end(), content.b.begin(), content.b.end());
}

struct ChunkIndex {
  std::uint64_t start = 0, end = 0, offset = 0, length = 0, index_length = 0, compressed = 0, uncompressed = 0;
  std::map<std::uint16_t, std::uint64_t> index_offsets;
};

}  // namespace mcap_write

using mcap_write::Bytes;
using mcap_write::ChunkIndex;
using mcap_write::record;

struct McapWriter::Impl {
  std::string path, compression;
  std::size_t chunk_bytes;
  std::ofstream out;
  std::uint64_t pos = 0;
  std::vector<Bytes> schemas, channels;  ///< their records' content, repeated in the summary
  std::vector<std::uint8_t> chunk;       ///< the open chunk's records
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index;  ///< log time, offset
  std::uint64_t chunk_start = UINT64_MAX, chunk_end = 0, first = UINT64_MAX, last = 0, messages = 0;
  std::map<std::uint16_t, std::uint64_t> counts;
  std::vector<ChunkIndex> chunks;
  bool closed = false;

  void emit(const std::vector<std::uint8_t>& bytes) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw InputError(path, "cannot write");
    pos += bytes.size();
  }
  std::vector<std::uint8_t> compressed() const {
    std::vector<std::uint8_t> c;
    if (compression == "zstd") {
      c.resize(ZSTD_compressBound(chunk.size()));
      const std::size_t n = ZSTD_compress(c.data(), c.size(), chunk.data(), chunk.size(), 3);
      if (ZSTD_isError(n)) throw InputError(path, std::string("zstd: ") + ZSTD_getErrorName(n));
      c.resize(n);
    } else if (compression == "lz4") {
      c.resize(LZ4F_compressFrameBound(chunk.size(), nullptr));
      const std::size_t n = LZ4F_compressFrame(c.data(), c.size(), chunk.data(), chunk.size(), nullptr);
      if (LZ4F_isError(n)) throw InputError(path, std::string("lz4: ") + LZ4F_getErrorName(n));
      c.resize(n);
    } else {
      c = chunk;
    }
    return c;
  }
  void flushChunk() {
    if (chunk.empty()) return;
    const std::vector<std::uint8_t> data = compressed();
    Bytes c;
    c.put(chunk_start);
    c.put(chunk_end);
    c.put(static_cast<std::uint64_t>(chunk.size()));
    c.put(static_cast<std::uint32_t>(::crc32(0L, chunk.data(), static_cast<uInt>(chunk.size()))));
    c.str(compression == "none" ? "" : compression);
    c.put(static_cast<std::uint64_t>(data.size()));
    c.raw(data);
    ChunkIndex ci;
    ci.start = chunk_start;
    ci.end = chunk_end;
    ci.offset = pos;
    ci.compressed = data.size();
    ci.uncompressed = chunk.size();
    std::vector<std::uint8_t> bytes;
    record(bytes, 0x06, c);
    ci.length = bytes.size();
    emit(bytes);
    const std::uint64_t index_start = pos;
    for (const auto& [channel, entries] : chunk_index) {
      Bytes m;
      m.put(channel);
      m.put(static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [t, offset] : entries) {
        m.put(t);
        m.put(offset);
      }
      ci.index_offsets[channel] = pos;
      std::vector<std::uint8_t> r;
      record(r, 0x07, m);
      emit(r);
    }
    ci.index_length = pos - index_start;
    chunks.push_back(ci);
    chunk.clear();
    chunk_index.clear();
    chunk_start = UINT64_MAX;
    chunk_end = 0;
  }
  void summary() {
    const std::uint64_t summary_start = pos;
    std::vector<std::uint8_t> s;
    for (const Bytes& b : schemas) record(s, 0x03, b);
    for (const Bytes& b : channels) record(s, 0x04, b);
    Bytes st;
    st.put(messages);
    st.put(static_cast<std::uint16_t>(schemas.size()));
    st.put(static_cast<std::uint32_t>(channels.size()));
    st.put(std::uint32_t{0});  // attachments
    st.put(std::uint32_t{0});  // metadata
    st.put(static_cast<std::uint32_t>(chunks.size()));
    st.put(messages ? first : 0);
    st.put(last);
    st.put(static_cast<std::uint32_t>(counts.size() * 10));
    for (const auto& [channel, n] : counts) {
      st.put(channel);
      st.put(n);
    }
    record(s, 0x0B, st);
    for (const ChunkIndex& ci : chunks) {
      Bytes b;
      b.put(ci.start);
      b.put(ci.end);
      b.put(ci.offset);
      b.put(ci.length);
      b.put(static_cast<std::uint32_t>(ci.index_offsets.size() * 10));
      for (const auto& [channel, offset] : ci.index_offsets) {
        b.put(channel);
        b.put(offset);
      }
      b.put(ci.index_length);
      b.str(compression == "none" ? "" : compression);
      b.put(ci.compressed);
      b.put(ci.uncompressed);
      record(s, 0x08, b);
    }
    emit(s);
    Bytes footer;
    footer.put(summary_start);
    footer.put(std::uint64_t{0});  // no summary offset section
    footer.put(std::uint32_t{0});  // no summary CRC
    std::vector<std::uint8_t> f;
    record(f, 0x02, footer);
    emit(f);
  }
};

McapWriter::McapWriter(const std::string& path, const std::string& compression, std::size_t chunk_bytes)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  if (compression != "none" && compression != "zstd" && compression != "lz4")
    throw InputError(path, "unknown MCAP chunk compression '" + compression + "' (none, zstd, lz4)");
  m.path = path;
  m.compression = compression;
  m.chunk_bytes = chunk_bytes;
  m.out.open(path, std::ios::binary | std::ios::trunc);
  if (!m.out) throw InputError(path, "cannot write");
  m.emit({0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
  Bytes header;
  header.str("ros2");
  header.str("idyvins");
  std::vector<std::uint8_t> r;
  record(r, 0x01, header);
  m.emit(r);
}

McapWriter::~McapWriter() = default;

std::uint16_t McapWriter::addChannel(const std::string& topic, const std::string& type, const std::string& definition) {
  Impl& m = *impl_;
  const auto id = static_cast<std::uint16_t>(m.channels.size() + 1);
  Bytes schema;
  schema.put(id);
  schema.str(type);
  schema.str("ros2msg");
  schema.put(static_cast<std::uint32_t>(definition.size()));
  schema.b.insert(schema.b.end(), definition.begin(), definition.end());
  Bytes channel;
  channel.put(id);
  channel.put(id);  // its schema
  channel.str(topic);
  channel.str("cdr");
  channel.put(std::uint32_t{0});  // no metadata
  std::vector<std::uint8_t> r;
  record(r, 0x03, schema);
  record(r, 0x04, channel);
  m.emit(r);
  m.schemas.push_back(schema);
  m.channels.push_back(channel);
  return id;
}

void McapWriter::write(std::uint16_t channel, std::uint64_t log_time_ns, const std::vector<std::uint8_t>& cdr) {
  Impl& m = *impl_;
  Bytes msg;
  msg.put(channel);
  msg.put(static_cast<std::uint32_t>(m.messages));
  msg.put(log_time_ns);
  msg.put(log_time_ns);  // publish time
  msg.raw(cdr);
  m.chunk_index[channel].push_back({log_time_ns, m.chunk.size()});
  record(m.chunk, 0x05, msg);
  m.chunk_start = std::min(m.chunk_start, log_time_ns);
  m.chunk_end = std::max(m.chunk_end, log_time_ns);
  m.first = std::min(m.first, log_time_ns);
  m.last = std::max(m.last, log_time_ns);
  ++m.messages;
  ++m.counts[channel];
  if (m.chunk.size() >= m.chunk_bytes) m.flushChunk();
}

void McapWriter::close() {
  Impl& m = *impl_;
  if (m.closed) return;
  m.flushChunk();
  Bytes data_end;
  data_end.put(std::uint32_t{0});  // no data section CRC
  std::vector<std::uint8_t> r;
  record(r, 0x0F, data_end);
  m.emit(r);
  m.summary();
  m.emit({0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
  m.out.close();
  if (!m.out) throw InputError(m.path, "cannot write");
  m.closed = true;
}

}  // namespace idyvins::io
