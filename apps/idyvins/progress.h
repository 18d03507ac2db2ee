#pragma once
// A terminal progress bar on stderr: done/total, rate, ETA. Quiet when stderr is not a TTY
// unless forced, so logs stay readable.

#include <chrono>
#include <cstdio>
#include <string>

namespace idyvins::app {

/// Progress bar for a loop of known length.
class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total, const char* unit);
  /// Sets the count of finished items; redraws at most ~10 times a second.
  void update(std::size_t done);
  /// Draws the final state and ends the line.
  void finish();

 private:
  void draw(bool final);
  std::string label_;
  std::size_t total_, done_ = 0;
  const char* unit_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace idyvins::app
