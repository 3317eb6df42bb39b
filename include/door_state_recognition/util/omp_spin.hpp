// A short OpenMP spin for a program: its OpenMP threads (GNU libgomp) wait
// for work spinning GOMP_SPINCOUNT 10000 (about 0.1 ms) before they sleep,
// instead of libgomp's default 300000 (about 3 ms), unless the environment
// sets GOMP_SPINCOUNT or OMP_WAIT_POLICY itself. On a machine whose cores
// are busy with other work a thread spinning between the pipeline's parallel
// regions takes a core from the thread it waits for: RGB-D frames took
// about twice as long; on idle cores the frame times are the same to within
// the noise (door_state_bench side by side, README "Benchmarks").
//
// For executables, never a library (a library must not change its
// process's environment). libgomp reads the environment once, when it is
// loaded, before main() (a variable set from .preinit_array does not last:
// libc sets its environment after it), so the program is run again with the
// variable set. A nodelet loaded into a manager gets it from the manager's
// environment (launch/door_state.launch sets it).
#pragma once

#include <unistd.h>

#include <cstdlib>

namespace dsr {
namespace util {

constexpr const char* kOmpSpinCount = "10000";

// First thing in main(): runs the program again (same arguments) with
// GOMP_SPINCOUNT set when neither it nor OMP_WAIT_POLICY is; returns at once
// when either is set, and when the program cannot be run again (libgomp's
// default spin then).
inline void shortOmpSpin(char** argv) {
  if (std::getenv("GOMP_SPINCOUNT") || std::getenv("OMP_WAIT_POLICY")) return;
  if (setenv("GOMP_SPINCOUNT", kOmpSpinCount, 0) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("GOMP_SPINCOUNT");  // not run again: as libgomp runs, for the children too
}

}  // namespace util
}  // namespace dsr
