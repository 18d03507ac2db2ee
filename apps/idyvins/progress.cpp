#include "progress.h"

#include <unistd.h>

#include <algorithm>

namespace idyvins::app {

ProgressBar::ProgressBar(std::string label, std::size_t total, const char* unit)
    : label_(std::move(label)),
      total_(total),
      unit_(unit),
      enabled_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

void ProgressBar::update(std::size_t done) {
  done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  draw(false);
}

void ProgressBar::finish() { draw(true); }

void ProgressBar::draw(bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  const double eta = rate > 0 ? (total_ - std::min(done_, total_)) / rate : 0.0;
  if (!enabled_) {
    if (final)
      std::fprintf(stderr, "%s: %zu/%zu %s in %.1f s (%.1f %s/s)\n", label_.c_str(), done_, total_, unit_, elapsed,
                   rate, unit_);
    return;
  }
  constexpr int kWidth = 30;
  const double frac = total_ ? std::min(1.0, static_cast<double>(done_) / total_) : 1.0;
  const int filled = static_cast<int>(frac * kWidth);
  std::string bar(filled, '#');
  bar.resize(kWidth, '.');
  std::fprintf(stderr, "\r%s [%s] %zu/%zu %s  %.1f %s/s  ETA %.0f s   ", label_.c_str(), bar.c_str(), done_, total_,
               unit_, rate, unit_, final ? 0.0 : eta);
  if (final) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace idyvins::app
