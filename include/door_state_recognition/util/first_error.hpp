// The first exception thrown by any of several OpenMP tasks, kept until the
// tasks are done and rethrown there: an exception must not leave a task.
// ROS-free.
#pragma once

#include <exception>

namespace dsr {
namespace util {

class FirstError {
 public:
  // f(), its exception (the first of all) kept instead of thrown.
  template <class F>
  void run(const F& f) {
    try {
      f();
    } catch (...) {
#pragma omp critical(dsr_first_error)
      if (!error_) error_ = std::current_exception();
    }
  }
  // Rethrows the exception kept, if any.
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::exception_ptr error_;
};

}  // namespace util
}  // namespace dsr
