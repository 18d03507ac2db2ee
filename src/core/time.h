#pragma once
// Time stamps are int64 nanoseconds everywhere; seconds only inside math.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace idyvins {

/// Time stamp in nanoseconds (EuRoC convention: since the epoch of the sensor clock).
using TimeNs = std::int64_t;

constexpr TimeNs kNsPerSecond = 1'000'000'000;

/// Nanoseconds to seconds (double, for integration math and printing).
inline double toSeconds(TimeNs t_ns) { return static_cast<double>(t_ns) * 1e-9; }

/// Seconds to nanoseconds, rounded to the nearest nanosecond.
TimeNs fromSeconds(double t_s);

/// Exact decimal seconds text of a time stamp, e.g. "1403715273.262142976".
std::string formatSeconds(TimeNs t_ns);

/// Exact parse of decimal seconds text ("12.5", "1403715273.262142976", "1e3" is
/// refused); nullopt if the text is not a plain decimal number or overflows.
std::optional<TimeNs> parseSecondsExact(std::string_view text);

}  // namespace idyvins
