// Place recognition's cost against the size of the keyframe database (issue: 1k, 10k and 100k
// keyframes). Synthetic descriptors: 300 random 256-bit codes per keyframe (the size of a real
// keyframe's set: landmark corners + 150 extra); the query is one stored keyframe's set with 20
// of 256 bits flipped in each code, as a place seen again. Real descriptors are not uniform:
// crowded buckets make real lookups slower than these (garage frames: 3-4 ms at 134 keyframes).

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>

#include "map/keyframe_database.h"

namespace {

using namespace idyvins::map;

constexpr int kPerKeyframe = 300;

Descriptor randomCode(std::mt19937_64& rng) {
  Descriptor d;
  for (std::size_t i = 0; i < d.size(); i += 8) {
    const std::uint64_t r = rng();
    for (int b = 0; b < 8; ++b) d[i + b] = static_cast<std::uint8_t>(r >> (8 * b));
  }
  return d;
}

/// One database per size, built once and shared by the benchmarks of that size.
const KeyframeDatabase& database(int keyframes) {
  static std::map<int, std::unique_ptr<KeyframeDatabase>> cache;
  auto& db = cache[keyframes];
  if (!db) {
    db = std::make_unique<KeyframeDatabase>();
    std::mt19937_64 rng(7);
    for (int k = 0; k < keyframes; ++k) {
      Keyframe kf;
      kf.t_ns = k;
      for (int i = 0; i < kPerKeyframe; ++i) kf.descriptors.push_back(randomCode(rng));
      db->add(std::move(kf));
    }
  }
  return *db;
}

void BM_PlaceQuery(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const KeyframeDatabase& db = database(n);
  std::mt19937_64 rng(11);
  std::vector<Descriptor> query = db.keyframe(static_cast<std::uint32_t>(n / 2)).descriptors;
  for (Descriptor& d : query)
    for (int flip = 0; flip < 20; ++flip) {
      const auto bit = static_cast<int>(rng() % 256);
      d[static_cast<std::size_t>(bit / 8)] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
  std::size_t found_right = 0, queries = 0;
  for (auto _ : state) {
    const auto candidates = db.query(query, n);
    found_right += !candidates.empty() && candidates[0].keyframe == static_cast<std::uint32_t>(n / 2);
    ++queries;
  }
  state.counters["right_place_first"] = static_cast<double>(found_right) / static_cast<double>(queries);
  state.counters["descriptors"] = static_cast<double>(db.descriptorCount());
}
BENCHMARK(BM_PlaceQuery)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_AddKeyframe(benchmark::State& state) {
  std::mt19937_64 rng(3);
  KeyframeDatabase db;
  for (auto _ : state) {
    Keyframe kf;
    for (int i = 0; i < kPerKeyframe; ++i) kf.descriptors.push_back(randomCode(rng));
    db.add(std::move(kf));
  }
}
BENCHMARK(BM_AddKeyframe)->Unit(benchmark::kMicrosecond);

}  // namespace
