#include <gtest/gtest.h>

#include "core/error.h"
#include "io/csv.h"
#include "test_util.h"

namespace idyvins::io {
namespace {

using test::expectError;
using test::TempDir;
using test::writeFile;

TEST(Csv, ReadsRowsWithLineNumbersSkippingHeaderAndBlankLines) {
  TempDir dir;
  writeFile(dir / "a.csv", "#t,x\n1, 2.5\n\n2,3\r\n");
  const auto rows = readTable(dir / "a.csv", {',', 2, 2});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].line, 2);
  EXPECT_EQ(rows[0].fields[1], "2.5");
  EXPECT_EQ(rows[1].line, 4);
  EXPECT_EQ(rows[1].fields[1], "3");
}

TEST(Csv, HeaderWithoutHashIsAccepted) {
  TempDir dir;
  writeFile(dir / "a.csv", "timestamp,x\n1,2\n");
  EXPECT_EQ(readTable(dir / "a.csv", {',', 2, 2}).size(), 1u);
}

TEST(Csv, WhitespaceSeparatedTables) {
  TempDir dir;
  writeFile(dir / "a.txt", "# c\n1.0  2 \t3\n");
  const auto rows = readTable(dir / "a.txt", {' ', 3, 3});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].fields[2], "3");
}

TEST(Csv, BadInputGivesFileLineAndExpectation) {
  TempDir dir;
  expectError([&] { readTable(dir / "missing.csv", {',', 2, 2}); }, "missing.csv: cannot open");
  writeFile(dir / "empty.csv", "");
  expectError([&] { readTable(dir / "empty.csv", {',', 2, 2}); }, "empty.csv: file is empty");
  writeFile(dir / "header.csv", "#t,x\n");
  expectError([&] { readTable(dir / "header.csv", {',', 2, 2}); }, "header.csv: no data rows");
  writeFile(dir / "cols.csv", "#t,x\n1,2\n3\n");
  expectError([&] { readTable(dir / "cols.csv", {',', 2, 2}); }, "cols.csv:3: expected 2 columns, got 1");
}

TEST(Csv, NumberParsing) {
  EXPECT_EQ(parseTimeNs("1403715273262142976", "f", 1, 1), 1403715273262142976);
  EXPECT_DOUBLE_EQ(parseFinite("-3.5e-2", "f", 1, 1), -0.035);
  expectError([] { parseTimeNs("12.5", "f.csv", 7, 1); }, "f.csv:7: column 1: expected an integer");
  expectError([] { parseTimeNs("", "f.csv", 7, 1); }, "f.csv:7");
  expectError([] { parseFinite("abc", "f.csv", 3, 4); }, "f.csv:3: column 4: expected a number, got 'abc'");
  expectError([] { parseFinite("1.0x", "f.csv", 3, 4); }, "expected a number");
  expectError([] { parseFinite("nan", "f.csv", 3, 2); }, "f.csv:3: column 2: expected a finite number");
  expectError([] { parseFinite("-inf", "f.csv", 3, 2); }, "expected a finite number");
}

TEST(Csv, TimeOrder) {
  EXPECT_NO_THROW(checkIncreasing({1, 2, 3}, {2, 3, 4}, "f"));
  expectError([] { checkIncreasing({1, 2, 2}, {2, 3, 4}, "f.csv"); }, "f.csv:4: duplicate time stamp 2");
  expectError([] { checkIncreasing({1, 5, 3}, {2, 3, 4}, "f.csv"); }, "f.csv:4: non-increasing time stamp 3");
}

}  // namespace
}  // namespace idyvins::io
