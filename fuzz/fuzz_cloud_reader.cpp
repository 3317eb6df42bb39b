// libFuzzer target: arbitrary bytes as a PCD or PLY file's content, read by
// dsr::io::readCloudFromMemory (the code path of readCloud). The reader must
// either return a consistent cloud or throw CloudReadError; anything else
// (a crash, a sanitizer report, another exception, a huge allocation caught by
// -malloc_limit_mb) is a bug.
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "door_state_recognition/io/cloud_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const pcl::PointCloud<pcl::PointXYZ> c = dsr::io::readCloudFromMemory(data, size, "fuzz");
    // Invariants of a cloud the reader returns.
    if (static_cast<std::uint64_t>(c.width) * c.height != c.size()) std::abort();
    bool dense = true;
    for (const auto& p : c) dense = dense && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    if (dense != c.is_dense) std::abort();
  } catch (const dsr::io::CloudReadError& e) {
    if (e.what()[0] == '\0') std::abort();  // the message must say something
  }
  return 0;
}
