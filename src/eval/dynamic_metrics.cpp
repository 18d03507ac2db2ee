#include "eval/dynamic_metrics.h"

#include <unordered_map>

namespace idyvins::eval {

namespace {
double ratio(std::size_t a, std::size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; }
}  // namespace

DynamicClassification classifyDynamic(const std::vector<MaskedObservation>& observations,
                                      const std::unordered_set<std::uint64_t>& confirmed_ids,
                                      const std::vector<std::uint64_t>& static_map_ids) {
  struct Track {
    std::size_t observations = 0, on_moving = 0;
    bool eliminated = false;
  };
  std::unordered_map<std::uint64_t, Track> tracks;
  for (const auto& o : observations) {
    Track& t = tracks[o.id];
    ++t.observations;
    t.on_moving += o.on_moving;
    t.eliminated = t.eliminated || o.eliminated;
  }
  DynamicClassification c;
  std::size_t tp_tracked = 0;
  for (const auto& o : observations) {
    const Track& t = tracks[o.id];
    const bool flagged = t.eliminated || confirmed_ids.count(o.id);
    if (o.on_moving) {
      ++c.observations_on_moving;
      c.true_positives += flagged;
      if (t.observations >= 2) {
        ++c.observations_on_moving_tracked;
        tp_tracked += flagged;
      }
    } else {
      ++c.observations_static;
      c.false_positives += flagged;
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
