// CellMap: an open-addressing hash map from a packed voxel key to a dense
// cell number, numbered in order of first insertion (so every result built on
// it is deterministic). It is what voxel downsampling and the neighbour grid
// share; far faster than std::unordered_map for millions of lookups.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "door_state_recognition/util/floor.hpp"

namespace dsr {
namespace preprocess {

// Integer cell coordinates of a point for cells of edge 1/inv.
inline Eigen::Vector3i cellOf(const Eigen::Vector3f& p, double inv) {
  return Eigen::Vector3i(util::floorToInt(p.x() * inv), util::floorToInt(p.y() * inv), util::floorToInt(p.z() * inv));
}

// 21 bits an axis. Coordinates beyond +-2^20 cells wrap: two far-apart cells
// may then share a key, which only merges their points in one bucket (the
// callers check real distances, or accept merging distant voxels).
inline std::uint64_t packCell(int x, int y, int z) {
  constexpr std::uint64_t m = 0x1FFFFF;
  return (static_cast<std::uint64_t>(x) & m) | ((static_cast<std::uint64_t>(y) & m) << 21) |
         ((static_cast<std::uint64_t>(z) & m) << 42);
}

class CellMap {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  explicit CellMap(std::size_t expected = 1024) {
    std::size_t cap = 1024;
    while (cap < 2 * expected) cap <<= 1;
    slots_.assign(cap, Slot());
  }
  std::size_t size() const { return size_; }

  // The cell number of key, inserting it (numbered size()) when new.
  std::uint32_t insert(std::uint64_t key) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    std::size_t h = slot(key);
    while (slots_[h].key != kEmpty) {
      if (slots_[h].key == key) return slots_[h].val;
      h = (h + 1) & (slots_.size() - 1);
    }
    slots_[h] = {key, static_cast<std::uint32_t>(size_)};
    return static_cast<std::uint32_t>(size_++);
  }
  // The cell number of key, or kNone.
  std::uint32_t find(std::uint64_t key) const {
    std::size_t h = slot(key);
    while (slots_[h].key != kEmpty) {
      if (slots_[h].key == key) return slots_[h].val;
      h = (h + 1) & (slots_.size() - 1);
    }
    return kNone;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);  // packed keys use 63 bits
#pragma pack(push, 4)
  struct Slot {  // key and number side by side (12 bytes): mostly one cache line per probe
    std::uint64_t key = kEmpty;
    std::uint32_t val = kNone;
  };
#pragma pack(pop)
  static_assert(sizeof(Slot) == 12, "packed slot");
  std::size_t slot(std::uint64_t key) const {
    key ^= key >> 29;
    key *= 0xbf58476d1ce4e5b9ull;
    key ^= key >> 32;
    return static_cast<std::size_t>(key) & (slots_.size() - 1);
  }
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(2 * old.size(), Slot());
    for (const Slot& s : old) {
      if (s.key == kEmpty) continue;
      std::size_t h = slot(s.key);
      while (slots_[h].key != kEmpty) h = (h + 1) & (slots_.size() - 1);
      slots_[h] = s;
    }
  }
  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

}  // namespace preprocess
}  // namespace dsr
