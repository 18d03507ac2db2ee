#pragma once
// Saved maps (`idyvins run --save-map DIR`): the keyframe database (poses, descriptors, static
// landmarks) and the pose graph, in a versioned, documented format (docs/loop-closure.md#saved-maps):
//   DIR/map.json       format name, version, counts, the FNV-1a 64 checksum of keyframes.bin
//   DIR/keyframes.bin  little-endian records, one per keyframe (see map_io.cpp)
//   DIR/loops.csv      the pose graph's loop edges
// A damaged, foreign or other-version map is refused with one InputError.

#include <string>
#include <vector>

#include "map/keyframe_database.h"
#include "map/pose_graph.h"

namespace idyvins::map {

constexpr int kMapFormatVersion = 1;

/// What a saved map holds.
struct SavedMap {
  std::vector<Keyframe> keyframes;   ///< in database order (id = index)
  std::vector<PoseGraphNode> nodes;  ///< one per keyframe, same order
  std::vector<LoopEdge> loops;
  /// The left camera the map was built with (pipeline::rigFingerprint; empty: not recorded).
  std::string rig;
};

/// Writes `map` into `dir` (created if missing; files written under temporary names and
/// renamed). Throws InputError when it cannot write.
void saveMap(const std::string& dir, const SavedMap& map);
/// Reads a map saved by saveMap. Throws InputError (file, what) for anything else.
SavedMap loadMap(const std::string& dir);

}  // namespace idyvins::map
