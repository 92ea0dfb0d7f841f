// The main of qdmr_avx512_tests (tests/CMakeLists.txt): the SIMD helpers' tests compiled as the AVX-512 kernel,
// run only where the CPU has what that kernel needs (the same check as the program's kernel choice); elsewhere
// exit 77, which CTest reports as skipped.
#include <gtest/gtest.h>

#include <cstdio>

#include "qdmr/core/isa.hpp"

int main(int argc, char** argv) {
  if (!qdmr::cpu_supports(qdmr::Isa::Avx512)) {
    std::puts("skipped: this CPU cannot run the AVX-512 kernel");
    return 77;
  }
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
