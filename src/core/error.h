#pragma once
// Typed errors for bad input. The library throws these; only apps/ turn them
// into a message and an exit code.

#include <stdexcept>
#include <string>

namespace idyvins {

/// Bad user input (file, config, dataset): the message names the file, the
/// line (1-based, 0 when the whole file is meant) and what was expected.
class InputError : public std::runtime_error {
 public:
  /// `file:line: message` (line > 0) or `file: message` (line == 0).
  InputError(const std::string& file, int line, const std::string& message);
  /// Error about a whole file or folder.
  InputError(const std::string& file, const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_ = 0;
};

/// Case-insensitive Levenshtein distance between two names (a message's nearest known key).
std::size_t editDistance(const std::string& a, const std::string& b);

}  // namespace idyvins
