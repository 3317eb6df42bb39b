// Proves the sanitizers are on in this build: run.sh expects `canary asan` to
// die with a heap-buffer-overflow report, `canary ubsan` and `canary floatcast`
// with a UBSan runtime error. If the flags were lost, these would exit 0 and run.sh fails.
#include <climits>
#include <cstdio>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  volatile int n = argc + 1;  // not constant-folded
  if (std::strcmp(argv[1], "asan") == 0) {
    std::vector<int> v(static_cast<std::size_t>(n));
    std::printf("%d\n", v.data()[n]);  // one past the end
  } else if (std::strcmp(argv[1], "ubsan") == 0) {
    volatile int big = INT_MAX - 1;
    std::printf("%d\n", big + n);  // signed overflow
  } else if (std::strcmp(argv[1], "floatcast") == 0) {
    volatile double huge = 1e13 * n;
    std::printf("%d\n", static_cast<int>(huge));  // gcc needs -fsanitize=float-cast-overflow
  }
  return 0;
}
