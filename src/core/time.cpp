#include "core/time.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

namespace idyvins {

TimeNs fromSeconds(double t_s) { return static_cast<TimeNs>(std::llround(t_s * 1e9)); }

std::string formatSeconds(TimeNs t_ns) {
  const bool negative = t_ns < 0;
  // Work on the magnitude in unsigned arithmetic (INT64_MIN safe).
  const auto mag = negative ? static_cast<std::uint64_t>(-(t_ns + 1)) + 1u : static_cast<std::uint64_t>(t_ns);
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(mag / kNsPerSecond),
                static_cast<unsigned long long>(mag % kNsPerSecond));
  return buf;
}

std::optional<TimeNs> parseSecondsExact(std::string_view text) {
  if (text.empty()) return std::nullopt;
  bool negative = false;
  if (text.front() == '-' || text.front() == '+') {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  const auto dot = text.find('.');
  const std::string_view int_part = text.substr(0, dot);
  std::string_view frac_part = dot == std::string_view::npos ? std::string_view{} : text.substr(dot + 1);
  if (int_part.empty() && frac_part.empty()) return std::nullopt;
  for (char c : int_part)
    if (c < '0' || c > '9') return std::nullopt;
  for (char c : frac_part)
    if (c < '0' || c > '9') return std::nullopt;
  std::int64_t seconds = 0;
  if (!int_part.empty()) {
    auto [ptr, ec] = std::from_chars(int_part.data(), int_part.data() + int_part.size(), seconds);
    if (ec != std::errc() || ptr != int_part.data() + int_part.size()) return std::nullopt;
  }
  if (seconds > std::numeric_limits<std::int64_t>::max() / kNsPerSecond - 1) return std::nullopt;
  std::int64_t frac_ns = 0;
  int digits = 0;
  for (char c : frac_part) {
    if (digits == 9) {  // round on the 10th digit, ignore the rest
      if (c >= '5') ++frac_ns;
      break;
    }
    frac_ns = frac_ns * 10 + (c - '0');
    ++digits;
  }
  for (; digits < 9; ++digits) frac_ns *= 10;
  const std::int64_t total = seconds * kNsPerSecond + frac_ns;
  return negative ? -total : total;
}

}  // namespace idyvins
