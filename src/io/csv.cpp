#include "io/csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace idyvins::io {
namespace {

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  if (separator == ' ') {
    std::istringstream in(line);
    std::string f;
    while (in >> f) fields.push_back(f);
    return fields;
  }
  std::string::size_type start = 0;
  while (true) {
    const auto pos = line.find(separator, start);
    fields.push_back(trim(line.substr(start, pos - start)));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return fields;
}

bool looksNumeric(const std::string& field) {
  if (field.empty()) return false;
  const char c = field[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

std::string columnText(int column) { return "column " + std::to_string(column); }

}  // namespace

std::vector<TableRow> readTable(const std::string& path, const TableOptions& options) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  const int max_cols = options.max_columns < 0 ? options.min_columns : options.max_columns;
  std::vector<TableRow> rows;
  std::string line;
  int line_no = 0;
  bool any_content = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty()) continue;
    any_content = true;
    if (t[0] == '#') continue;
    TableRow row{line_no, split(t, options.separator)};
    if (row.fields.empty()) continue;  // separators only (e.g. a vertical tab; found by fuzzing)
    if (rows.empty() && !looksNumeric(row.fields[0]) && line_no == 1) continue;  // header
    const int n = static_cast<int>(row.fields.size());
    if (n < options.min_columns || (max_cols > 0 && n > max_cols)) {
      std::string expected = std::to_string(options.min_columns);
      if (max_cols == 0)
        expected = "at least " + expected;
      else if (max_cols != options.min_columns)
        expected += " to " + std::to_string(max_cols);
      throw InputError(path, line_no, "expected " + expected + " columns, got " + std::to_string(n));
    }
    rows.push_back(std::move(row));
  }
  if (!any_content) throw InputError(path, "file is empty (expected a header and data rows)");
  if (rows.empty()) throw InputError(path, "no data rows (only a header or comments)");
  return rows;
}

TimeNs parseTimeNs(const std::string& text, const std::string& path, int line, int column) {
  TimeNs value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) {
    throw InputError(path, line,
                     columnText(column) + ": expected an integer time stamp in nanoseconds, got '" + text + "'");
  }
  return value;
}

double parseFinite(const std::string& text, const std::string& path, int line, int column) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (text.empty() || end != begin + text.size()) {
    throw InputError(path, line, columnText(column) + ": expected a number, got '" + text + "'");
  }
  if (!std::isfinite(value) || errno == ERANGE) {
    throw InputError(path, line, columnText(column) + ": expected a finite number, got '" + text + "'");
  }
  return value;
}

void checkIncreasing(const std::vector<TimeNs>& stamps, const std::vector<int>& lines, const std::string& path) {
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    if (stamps[i] <= stamps[i - 1]) {
      throw InputError(path, lines[i],
                       std::string(stamps[i] == stamps[i - 1] ? "duplicate" : "non-increasing") + " time stamp " +
                           std::to_string(stamps[i]) + " (expected after " + std::to_string(stamps[i - 1]) +
                           " on line " + std::to_string(lines[i - 1]) + ")");
    }
  }
}

}  // namespace idyvins::io
