#pragma once
// FNV-1a 64-bit checksums: saved maps' integrity (map/map_io.h) and the inputs a benchmark job
// ran on (stats.json's config_fnv1a64, bench --plan). Not cryptographic: they tell damaged or
// different files apart, nothing more.

#include <cstdint>
#include <string>
#include <string_view>

namespace idyvins {

constexpr std::uint64_t kFnv1a64Offset = 1469598103934665603ull;

/// FNV-1a 64 of `bytes`, continuing from `h` (chain several inputs into one checksum).
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t h = kFnv1a64Offset);
/// FNV-1a 64 of a file's bytes, continuing from `h`. Throws InputError if it cannot be read.
std::uint64_t fnv1a64File(const std::string& path, std::uint64_t h = kFnv1a64Offset);
/// 16 lower-case hex digits.
std::string hex64(std::uint64_t value);

}  // namespace idyvins
