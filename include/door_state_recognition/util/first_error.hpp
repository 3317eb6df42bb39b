// The first exception thrown by any of several OpenMP tasks, kept until the
// tasks are done and rethrown there: an exception must not leave a task.
// ROS-free.
#pragma once

#include <exception>
#include <utility>

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
      keep(std::current_exception());
    }
  }
  // e kept if it is the first.
  void keep(std::exception_ptr e) {
#pragma omp critical(dsr_first_error)
    if (!error_) error_ = std::move(e);
  }
  // Whether an exception is kept.
  bool failed() const {
    bool kept;
#pragma omp critical(dsr_first_error)
    kept = static_cast<bool>(error_);
    return kept;
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
