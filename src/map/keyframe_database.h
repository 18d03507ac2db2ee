#pragma once
// Keyframes that left the sliding window, with what loop closure and relocalization need:
// the pose, binary descriptors of corners for recognition, and the static landmarks seen
// (3D, with the corner they were seen at). Only static landmarks enter (DESIGN §7): the
// caller hands over features whose label is static; eliminated and confirmed-dynamic ones
// never reach this module. Place recognition: every descriptor in one faiss binary hash
// index; a query's descriptors vote for the keyframes of their near neighbours.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/time.h"
#include "map/loop_options.h"

namespace faiss {
struct IndexBinaryHash;
}

namespace idyvins::map {

/// A 256-bit binary descriptor (ORB / rBRIEF).
using Descriptor = std::array<std::uint8_t, 32>;
int hamming(const Descriptor& a, const Descriptor& b);

/// A static landmark as a keyframe saw it.
struct KeyframeLandmark {
  std::uint64_t id = 0;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  ///< world position (odometry frame)
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();   ///< left camera, normalized undistorted
  Descriptor descriptor{};                        ///< at its corner in this keyframe
};

struct Keyframe {
  std::uint32_t id = 0;  ///< set by the database: its index
  TimeNs t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  std::vector<Descriptor> descriptors;  ///< recognition corners (the landmarks' and extra ones)
  std::vector<KeyframeLandmark> landmarks;
};

struct PlaceCandidate {
  std::uint32_t keyframe = 0;
  int votes = 0;  ///< query descriptors with a near neighbour in this keyframe
};

class KeyframeDatabase {
 public:
  explicit KeyframeDatabase(const PlaceRecognitionOptions& options = {});
  ~KeyframeDatabase();
  KeyframeDatabase(KeyframeDatabase&&) noexcept;
  KeyframeDatabase& operator=(KeyframeDatabase&&) noexcept;

  /// Adds a keyframe (its id becomes its index) and its descriptors to the index.
  std::uint32_t add(Keyframe keyframe);
  /// Keyframes older than `before_t_ns` (or with an id below `any_age_below`: a loaded map's)
  /// whose descriptors the query's are near, best first (most votes, then lowest id: deterministic).
  std::vector<PlaceCandidate> query(const std::vector<Descriptor>& descriptors, TimeNs before_t_ns,
                                    std::uint32_t any_age_below = 0) const;

  std::size_t size() const { return keyframes_.size(); }
  const Keyframe& keyframe(std::uint32_t id) const { return keyframes_.at(id); }
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  std::size_t descriptorCount() const { return owner_.size(); }

 private:
  PlaceRecognitionOptions options_;
  std::vector<Keyframe> keyframes_;
  std::vector<std::uint32_t> owner_;  ///< keyframe of each indexed descriptor
  std::unique_ptr<faiss::IndexBinaryHash> index_;
};

}  // namespace idyvins::map
