#include "core/checksum.h"

#include <cstdio>
#include <fstream>
#include <vector>

#include "core/error.h"

namespace idyvins {

std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t h) {
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return h;
}

std::uint64_t fnv1a64File(const std::string& path, std::uint64_t h) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot be read");
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h = fnv1a64(std::string_view(buf.data(), static_cast<std::size_t>(in.gcount())), h);
  }
  if (in.bad()) throw InputError(path, "read error");
  return h;
}

std::string hex64(std::uint64_t value) {
  char b[17];
  std::snprintf(b, sizeof(b), "%016llx", static_cast<unsigned long long>(value));
  return b;
}

}  // namespace idyvins
