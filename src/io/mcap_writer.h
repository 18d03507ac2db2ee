#pragma once
// Writes MCAP files with ROS 2's profile (mcap.dev/spec): schemas (ros2msg) and channels (cdr) in
// the data section as they are added, messages in chunks (none, zstd or lz4 compressed, CRC
// set) each followed by its message indexes, then a summary (schemas, channels, statistics,
// chunk indexes) and the footer, so that readers can list topics and counts without a scan.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace idyvins::io {

/// One MCAP file being written; close() finishes it (the destructor of an unclosed writer leaves
/// a file without a footer, which readers refuse as cut short).
class McapWriter {
 public:
  /// Throws InputError when `path` cannot be written or `compression` is not none, zstd or lz4.
  McapWriter(const std::string& path, const std::string& compression, std::size_t chunk_bytes = 4u << 20);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;
  /// A channel on `topic` of ROS 2 type `type` (sensor_msgs/msg/Imu) whose ros2msg definition is `definition`.
  std::uint16_t addChannel(const std::string& topic, const std::string& type, const std::string& definition);
  /// One CDR message on `channel`, logged at `log_time_ns`.
  void write(std::uint16_t channel, std::uint64_t log_time_ns, const std::vector<std::uint8_t>& cdr);
  /// The last chunk, the summary and the footer. Throws InputError when writing fails.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace idyvins::io
