#pragma once
// MCAP files (mcap.dev/spec, major version 0), what ROS 2 records by default: a forward scan of
// the data section, chunks uncompressed, zstd or lz4 (Debian's libzstd and liblz4) with their
// CRC checked, schemas and channels taken in as they come, and the summary section's channels
// and message counts when the file has one. Every length is checked against the file or chunk
// that holds it; a damaged file is refused with the byte offset of the record that is wrong.

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace idyvins::io {

/// One channel (topic) and its schema.
struct McapChannel {
  std::uint16_t id = 0;
  std::string topic, message_encoding, schema_name, schema_encoding;
};

/// One message of the data section; `data` is valid until the reader's next call.
struct McapMessage {
  std::uint16_t channel_id = 0;
  std::uint64_t log_time_ns = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// Reads one MCAP file. Throws InputError(path, "byte N: ...") for anything malformed.
class McapReader {
 public:
  /// Opens the file and checks both magics and the footer (a file without them was cut short).
  explicit McapReader(const std::string& path);
  /// The summary's channels and per-channel message counts; false when the file has no summary
  /// with statistics (then the counts come from a scan).
  bool summary(std::map<std::uint16_t, McapChannel>& channels, std::map<std::uint16_t, std::uint64_t>& counts);
  /// Starts the scan of the data section again.
  void rewind();
  /// The next message of the data section, false at its end.
  bool next(McapMessage& message);
  /// A channel seen so far (in the data section or the summary), nullptr when unknown.
  const McapChannel* channel(std::uint16_t id) const;
  /// The chunk compressions seen by the scans ("none", "zstd", "lz4").
  const std::vector<std::string>& compressions() const { return compressions_; }
  const std::string& path() const { return path_; }

 private:
  struct Record {
    std::uint8_t opcode = 0;
    std::uint64_t offset = 0;  ///< in the file (of the chunk, for a record inside one)
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  bool nextRecord(Record& r);
  void readChunk(const Record& r);
  void takeSchemaOrChannel(const Record& r);
  [[noreturn]] void fail(std::uint64_t offset, const std::string& what) const;
  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0, pos_ = 0, data_end_ = 0, summary_start_ = 0, chunk_offset_ = 0;
  std::vector<std::uint8_t> record_, chunk_;
  std::size_t chunk_pos_ = 0;
  bool in_chunk_ = false, done_ = false;
  std::map<std::uint16_t, std::pair<std::string, std::string>> schemas_;  ///< id -> name, encoding
  std::map<std::uint16_t, McapChannel> channels_;
  std::vector<std::string> compressions_;
};

}  // namespace idyvins::io
