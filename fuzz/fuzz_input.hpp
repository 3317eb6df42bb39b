// Reads a fuzz input front to back as little-endian integers; past the end
// every value is 0. A simple, documented encoding keeps the seed corpus easy
// to write (fuzz/make_corpus.py) and the mutations meaningful.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace fuzz {
class Input {
 public:
  Input(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  std::size_t left() const { return n_; }
  std::uint8_t u8() { return static_cast<std::uint8_t>(take(1)); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(take(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(take(4)); }
  std::vector<std::uint8_t> rest() {
    std::vector<std::uint8_t> v(p_, p_ + n_);
    p_ += n_;
    n_ = 0;
    return v;
  }

 private:
  std::uint64_t take(std::size_t k) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < k && n_ > 0; ++i, ++p_, --n_) v |= std::uint64_t(*p_) << (8 * i);
    return v;
  }
  const std::uint8_t* p_;
  std::size_t n_;
};
}  // namespace fuzz
