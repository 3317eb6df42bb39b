#pragma once

#include "door_state_recognition/util/first_error.hpp"

namespace dsr {
namespace util {

// f(0) and, when split, f(1) at once: f(1) as an OpenMP task (taken by a
// thread of the enclosing parallel region when it comes free, or by this
// one when it waits), f(0) here; outside a parallel region in turn. The
// first exception thrown is rethrown here.
template <class F>
void bothHalves(bool split, const F& f) {
  if (!split) {
    f(0);
    return;
  }
  FirstError error;
#pragma omp task shared(error, f)
  error.run([&] { f(1); });
  error.run([&] { f(0); });
#pragma omp taskwait
  error.rethrow();
}

}  // namespace util
}  // namespace dsr
