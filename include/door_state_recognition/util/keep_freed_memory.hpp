// Freed memory kept for the next cloud, for a program that runs the pipeline
// again and again (the node, the bench, a survey in the CLI). By default
// glibc's malloc gives a large block back to the kernel when it is freed
// (blocks from 128 KiB up to 32 MiB, the threshold rising with what was
// freed, are mmap'ed; the top of a heap is trimmed beyond twice that), and
// the next cloud faults the same pages in again, zeroed by the kernel. With
// blocks up to 64 MiB taken from the heaps and heaps trimmed only beyond
// 1 GiB, a run of the 400k-ray room faulted 199 pages instead of 1573
// (perf stat -e page-faults, door_state_bench --runs 11 against --runs 1)
// and took 37.3-43.6 ms instead of 56.0-56.6, the 4M-ray room 105-122 ms
// instead of 207-236 (three alternating rounds, quiet machine, README
// "Benchmarks"); RGB-D frames were unchanged within the noise. Resident
// memory stays at the high-water mark of the largest cloud seen, which the
// process reached anyway.
//
// For executables, never a library (a library must not change its process's
// allocator). A nodelet loaded into a manager gets the same from the
// manager's environment: launch/door_state.launch sets
// MALLOC_MMAP_THRESHOLD_ and MALLOC_TRIM_THRESHOLD_ for the processes it
// starts.
#pragma once

#include <malloc.h>

#include <cstdlib>
#include <string>

namespace dsr {
namespace util {

constexpr int kKeepMmapThreshold = 64 << 20;  // bytes
constexpr int kKeepTrimThreshold = 1 << 30;   // bytes
// The environment variables by which malloc is set at start-up: any of them
// set, keepFreedMemory leaves malloc as they made it.
constexpr const char* kMallocEnvironment[] = {"MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_",
                                              "GLIBC_TUNABLES"};

// First thing in main(): sets the two thresholds unless the environment
// sets malloc's own (MALLOC_MMAP_THRESHOLD_, MALLOC_TRIM_THRESHOLD_,
// MALLOC_TOP_PAD_ or GLIBC_TUNABLES, read by glibc at start-up). Returns
// what is in force, for a program's header.
inline std::string keepFreedMemory() {
  for (const char* v : kMallocEnvironment)
    if (std::getenv(v)) return std::string("as the environment sets (") + v + ")";
  if (mallopt(M_MMAP_THRESHOLD, kKeepMmapThreshold) != 1 || mallopt(M_TRIM_THRESHOLD, kKeepTrimThreshold) != 1)
    return "glibc's defaults (mallopt refused)";
  return "kept (mmap threshold 64 MiB, trim threshold 1 GiB)";
}

}  // namespace util
}  // namespace dsr
