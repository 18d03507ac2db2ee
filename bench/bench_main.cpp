// Shared main of the benchmark programs: the same allocator setting as `idyvins`.

#include <benchmark/benchmark.h>

#include "core/allocator.h"

int main(int argc, char** argv) {
  idyvins::configureAllocatorForStreaming();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
