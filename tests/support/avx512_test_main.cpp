// The main of qdmr_avx512_tests (tests/CMakeLists.txt): the SIMD helpers' tests compiled as the AVX-512 kernel. On a
// CPU without AVX-512 the binary exits 77 (skipped) before main: support/avx512_cpu_guard.cpp.
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
