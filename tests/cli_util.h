#pragma once
// Running the `idyvins` binary from a test: exit code and everything it printed.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace idyvins::test {

struct CliResult {
  int code = -1;
  std::string out;  ///< stdout and stderr
};

/// `idyvins ARGS` through the shell (ARGS are shell words).
inline CliResult runCli(const std::string& args) {
  const std::string cmd = std::string(IDYVINS_BINARY) + " " + args + " 2>&1";
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace idyvins::test
