#include <gtest/gtest.h>

#include "core/time.h"

namespace idyvins {
namespace {

TEST(Time, FormatIsExactDecimalSeconds) {
  EXPECT_EQ(formatSeconds(1403715273262142976), "1403715273.262142976");
  EXPECT_EQ(formatSeconds(5), "0.000000005");
  EXPECT_EQ(formatSeconds(-1'500'000'000), "-1.500000000");
}

TEST(Time, ParseRoundTripsExactly) {
  for (TimeNs t : {TimeNs{0}, TimeNs{1}, TimeNs{1403715273262142976}, TimeNs{-42}}) {
    const auto parsed = parseSecondsExact(formatSeconds(t));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, t);
  }
  EXPECT_EQ(*parseSecondsExact("12.5"), 12'500'000'000);
  EXPECT_EQ(*parseSecondsExact("3"), 3'000'000'000);
  EXPECT_EQ(*parseSecondsExact(".25"), 250'000'000);
  EXPECT_EQ(*parseSecondsExact("0.0000000016"), 2);  // rounds on the 10th digit
}

TEST(Time, ParseRefusesNonDecimal) {
  for (const char* bad : {"", "abc", "1e3", "1.2.3", "nan", "-", "."})
    EXPECT_FALSE(parseSecondsExact(bad).has_value()) << bad;
}

TEST(Time, SecondsConversion) {
  EXPECT_DOUBLE_EQ(toSeconds(1'500'000'000), 1.5);
  EXPECT_EQ(fromSeconds(1.5), 1'500'000'000);
}

}  // namespace
}  // namespace idyvins
