#include "map/keyframe_database.h"

#include <faiss/IndexBinaryHash.h>
#include <omp.h>

#include <algorithm>
#include <bitset>
#include <cstring>
#include <map>
#include <set>

namespace idyvins::map {

namespace {
/// faiss spreads a lookup's queries over OpenMP threads: one thread, for the calling thread only
/// (OpenMP's nthreads is per thread), leaves the other core to the odometry and keeps every
/// result independent of thread timing. Restored when done.
class OneOpenMpThread {
 public:
  OneOpenMpThread() : before_(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~OneOpenMpThread() { omp_set_num_threads(before_); }
  OneOpenMpThread(const OneOpenMpThread&) = delete;
  OneOpenMpThread& operator=(const OneOpenMpThread&) = delete;

 private:
  int before_;
};
}  // namespace

int hamming(const Descriptor& a, const Descriptor& b) {
  int d = 0;
  for (std::size_t i = 0; i < a.size(); i += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a.data() + i, 8);
    std::memcpy(&y, b.data() + i, 8);
    d += static_cast<int>(std::bitset<64>(x ^ y).count());
  }
  return d;
}

KeyframeDatabase::KeyframeDatabase(const PlaceRecognitionOptions& options)
    : options_(options), index_(std::make_unique<faiss::IndexBinaryHash>(256, options.hash_bits)) {
  index_->nflip = options.hash_flips;
}
KeyframeDatabase::~KeyframeDatabase() = default;
KeyframeDatabase::KeyframeDatabase(KeyframeDatabase&&) noexcept = default;
KeyframeDatabase& KeyframeDatabase::operator=(KeyframeDatabase&&) noexcept = default;

std::uint32_t KeyframeDatabase::add(Keyframe keyframe) {
  keyframe.id = static_cast<std::uint32_t>(keyframes_.size());
  if (!keyframe.descriptors.empty()) {
    const OneOpenMpThread one;
    std::vector<std::uint8_t> codes(32 * keyframe.descriptors.size());
    for (std::size_t i = 0; i < keyframe.descriptors.size(); ++i)
      std::copy(keyframe.descriptors[i].begin(), keyframe.descriptors[i].end(), codes.begin() + 32 * i);
    index_->add(static_cast<faiss::IndexBinary::idx_t>(keyframe.descriptors.size()), codes.data());
    owner_.insert(owner_.end(), keyframe.descriptors.size(), keyframe.id);
  }
  keyframes_.push_back(std::move(keyframe));
  return keyframes_.back().id;
}

std::vector<PlaceCandidate> KeyframeDatabase::query(const std::vector<Descriptor>& descriptors, TimeNs before_t_ns,
                                                    std::uint32_t any_age_below) const {
  std::vector<PlaceCandidate> out;
  if (descriptors.empty() || owner_.empty()) return out;
  const int k = std::max(1, options_.neighbours);
  const auto n = static_cast<faiss::IndexBinary::idx_t>(descriptors.size());
  std::vector<std::uint8_t> codes(32 * descriptors.size());
  for (std::size_t i = 0; i < descriptors.size(); ++i)
    std::copy(descriptors[i].begin(), descriptors[i].end(), codes.begin() + 32 * i);
  const OneOpenMpThread one;
  std::vector<std::int32_t> distances(static_cast<std::size_t>(n * k));
  std::vector<faiss::IndexBinary::idx_t> labels(static_cast<std::size_t>(n * k));
  index_->search(n, codes.data(), k, distances.data(), labels.data());
  std::map<std::uint32_t, int> votes;
  for (faiss::IndexBinary::idx_t q = 0; q < n; ++q) {
    std::set<std::uint32_t> voted;  // one vote per query descriptor and keyframe
    for (int j = 0; j < k; ++j) {
      const auto idx = static_cast<std::size_t>(q * k + j);
      if (labels[idx] < 0 || distances[idx] > options_.max_hamming) continue;
      const std::uint32_t kf = owner_[static_cast<std::size_t>(labels[idx])];
      if ((kf < any_age_below || keyframes_[kf].t_ns < before_t_ns) && voted.insert(kf).second) ++votes[kf];
    }
  }
  for (const auto& [kf, v] : votes)
    if (v >= options_.min_votes) out.push_back({kf, v});
  std::sort(out.begin(), out.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
    return a.votes != b.votes ? a.votes > b.votes : a.keyframe < b.keyframe;
  });
  if (out.size() > options_.max_candidates) out.resize(options_.max_candidates);
  return out;
}

}  // namespace idyvins::map
