#pragma once
// A structural check of a ROS1 bag (format 2.0) before Debian's rosbag_storage opens it:
// rosbag trusts the length fields of record headers, connection headers and index entries,
// and a damaged file makes it read past its buffers. This walk trusts nothing.

#include <cstdint>
#include <istream>
#include <optional>
#include <string>

namespace idyvins::io {

/// Walks every record of the bag in `in` (`size` bytes, starting with "#ROSBAG V2.0\n"):
/// record and field lengths inside their record, data inside the file or chunk, the records
/// of uncompressed chunks, index entries pointing at records of their chunk, the index
/// (connections, chunk infos) where the bag header says. Returns what is wrong, with its
/// byte offset, or nullopt for a well-formed bag. Reads headers only (seeks over data).
std::optional<std::string> bagStructureProblem(std::istream& in, std::uint64_t size);

}  // namespace idyvins::io
