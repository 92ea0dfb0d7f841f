// qdmr_avx512_tests' CPU check, run before any other static initialiser of that binary (tests/CMakeLists.txt).
// Its test files are compiled with the AVX-512 kernel's flags, so their initialisers (GoogleTest's registrations)
// may use AVX-512 too: copying a file-path string of more than 64 bytes took a zmm register, so a checkout in a
// longer folder died of SIGILL before main() could skip. This file is compiled for the baseline, and a constructor
// of priority 101 runs before every initialiser of the default priority: a CPU without what the AVX-512 kernel needs
// (the same check as the program's kernel choice) exits 77, which CTest reports as skipped.
#include <cstdio>
#include <cstdlib>

#include "qdmr/core/isa.hpp"

namespace {

[[gnu::constructor(101)]] void skip_without_avx512() {
  if (qdmr::cpu_supports(qdmr::Isa::Avx512)) return;
  std::puts("skipped: this CPU cannot run the AVX-512 kernel");
  std::fflush(stdout);
  std::_Exit(77);  // no destructors: the other initialisers have not run
}

}  // namespace
