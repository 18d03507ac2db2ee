#pragma once
// Strict reader for the small CSV / whitespace tables of EuRoC, TUM and friends.
// Every failure is an InputError naming file, line and what was expected.

#include <cstdint>
#include <string>
#include <vector>

#include "core/time.h"

namespace idyvins::io {

/// One data row of a text table, with its 1-based line number in the file.
struct TableRow {
  int line = 0;
  std::vector<std::string> fields;
};

/// How to split and check a table.
struct TableOptions {
  char separator = ',';  ///< ',' for CSV; ' ' means any run of spaces/tabs
  int min_columns = 1;   ///< a row with fewer fields is an error
  int max_columns = -1;  ///< -1: same as min_columns; 0: no upper bound
};

/// Reads a table: '#' lines are comments/headers; a first line whose first
/// field is not a number is a header too; blank lines are ignored. Throws
/// InputError on a missing or empty file, no data rows, or a bad column count.
std::vector<TableRow> readTable(const std::string& path, const TableOptions& options);

/// Parses an integer time stamp [ns] or throws InputError(path, line, ...).
TimeNs parseTimeNs(const std::string& text, const std::string& path, int line, int column);

/// Parses a finite double (NaN/inf refused) or throws InputError(path, line, ...).
double parseFinite(const std::string& text, const std::string& path, int line, int column);

/// Throws InputError unless every row's time stamp is strictly after the previous one.
void checkIncreasing(const std::vector<TimeNs>& stamps, const std::vector<int>& lines, const std::string& path);

}  // namespace idyvins::io
