#pragma once
// A DataSource read on a background thread (image decoding overlaps processing),
// keeping at most `max_frames` stereo frames ahead. Order and content are unchanged.

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "io/data_source.h"

namespace idyvins::io {

/// `source` read ahead on its own thread; next() gives what source.next() would, in order.
class PrefetchSource {
 public:
  PrefetchSource(DataSource& source, std::size_t max_frames) : source_(source), max_frames_(max_frames) {
    thread_ = std::thread([this] { produce(); });
  }
  ~PrefetchSource() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  /// The next measurement, or nullopt at the end; rethrows the reader's error.
  std::optional<Measurement> next() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !queue_.empty() || done_; });
    if (queue_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return std::nullopt;
    }
    Measurement m = std::move(queue_.front());
    queue_.pop_front();
    if (std::holds_alternative<StereoFrame>(m)) --frames_queued_;
    cv_.notify_all();
    return m;
  }

 private:
  void produce() {
    try {
      while (true) {
        {
          std::unique_lock<std::mutex> lock(mutex_);
          cv_.wait(lock, [this] { return stop_ || frames_queued_ < max_frames_; });
          if (stop_) break;
        }
        auto m = source_.next();  // outside the lock: this is the slow part
        std::lock_guard<std::mutex> lock(mutex_);
        if (!m) break;
        if (std::holds_alternative<StereoFrame>(*m)) ++frames_queued_;
        queue_.push_back(std::move(*m));
        cv_.notify_all();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
    cv_.notify_all();
  }

  DataSource& source_;
  std::size_t max_frames_;
  std::deque<io::Measurement> queue_;
  std::size_t frames_queued_ = 0;
  bool stop_ = false, done_ = false;
  std::exception_ptr error_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::thread thread_;
};

}  // namespace idyvins::io
