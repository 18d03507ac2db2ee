#include "eval/dynamic_metrics.h"

#include <unordered_map>

namespace idyvins::eval {

namespace {
double ratio(std::size_t a, std::size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; }
}  // namespace

void addObservation(std::unordered_map<std::uint64_t, TrackCounts>& tracks, const MaskedObservation& o) {
  TrackCounts& t = tracks[o.id];
  ++t.observations;
  t.on_moving += o.on_moving;
  t.eliminated = t.eliminated || o.eliminated;
}

DynamicClassification classifyDynamic(const std::vector<MaskedObservation>& observations,
                                      const std::unordered_set<std::uint64_t>& confirmed_ids,
                                      const std::vector<std::uint64_t>& static_map_ids) {
  std::unordered_map<std::uint64_t, TrackCounts> tracks;
  for (const auto& o : observations) addObservation(tracks, o);
  return classifyTracks(tracks, confirmed_ids, static_map_ids);
}

DynamicClassification classifyTracks(const std::unordered_map<std::uint64_t, TrackCounts>& tracks,
                                     const std::unordered_set<std::uint64_t>& confirmed_ids,
                                     const std::vector<std::uint64_t>& static_map_ids) {
  // Every observation of a track shares its verdict: count them per track.
  DynamicClassification c;
  std::size_t tp_tracked = 0;
  for (const auto& [id, t] : tracks) {
    const bool flagged = t.eliminated || confirmed_ids.count(id);
    const std::size_t on_static = t.observations - t.on_moving;
    c.observations_on_moving += t.on_moving;
    c.observations_static += on_static;
    if (flagged) {
      c.true_positives += t.on_moving;
      c.false_positives += on_static;
    }
    if (t.observations >= 2) {
      c.observations_on_moving_tracked += t.on_moving;
      if (flagged) tp_tracked += t.on_moving;
    }
  }
  c.recall = ratio(c.true_positives, c.observations_on_moving);
  c.recall_tracked = ratio(tp_tracked, c.observations_on_moving_tracked);
  c.static_flagged = ratio(c.false_positives, c.observations_static);
  c.precision = ratio(c.true_positives, c.true_positives + c.false_positives);
  c.f1 = c.precision + c.recall > 0 ? 2 * c.precision * c.recall / (c.precision + c.recall) : 0.0;
  c.static_map_points = static_map_ids.size();
  for (auto id : static_map_ids) {
    const auto it = tracks.find(id);
    if (it == tracks.end()) continue;
    c.static_map_on_moving += 2 * it->second.on_moving > it->second.observations;
    c.static_map_ever_on_moving += it->second.on_moving > 0;
  }
  c.static_map_fraction_on_moving = ratio(c.static_map_on_moving, c.static_map_points);
  c.static_map_fraction_ever_on_moving = ratio(c.static_map_ever_on_moving, c.static_map_points);
  return c;
}

}  // namespace idyvins::eval
