#pragma once
// Process-wide allocator tuning for the per-frame pipeline (called by programs, not the library).

namespace idyvins {

/// Keeps freed image-sized blocks in the heap instead of returning them to the OS:
/// glibc's default mmap threshold makes every per-frame image buffer (pyramids,
/// OpenCV's internal eigenvalue images) a fresh mmap + page faults, which slows tracking
/// several times (docs/performance.md). No-op on other C libraries.
void configureAllocatorForStreaming();

}  // namespace idyvins
