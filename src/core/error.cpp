#include "core/error.h"

namespace idyvins {
namespace {
std::string format(const std::string& file, int line, const std::string& message) {
  if (line > 0) return file + ":" + std::to_string(line) + ": " + message;
  return file + ": " + message;
}
}  // namespace

InputError::InputError(const std::string& file, int line, const std::string& message)
    : std::runtime_error(format(file, line, message)), file_(file), line_(line) {}

InputError::InputError(const std::string& file, const std::string& message) : InputError(file, 0, message) {}

}  // namespace idyvins
