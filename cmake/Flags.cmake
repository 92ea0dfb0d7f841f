# Flags for project code only (dependencies are compiled by Debian).
#
# qdmr_project_flags(target ISA): ISA is "baseline" (x86-64: everything outside the draw kernels), or the ISA of
# a draw kernel ("sse4.2", "avx2", "avx512"), which also puts the code into the namespace qdmr::<isa>
# (core/isa_namespace.hpp).
function(qdmr_project_flags target isa)
  # -ffp-contract=off: no fused multiply-add behind our back, so every ISA gives the same bits.
  set(werror "")
  if(QDMR_WERROR)
    set(werror -Werror)
  endif()
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic ${werror} -ffp-contract=off -fno-fast-math)
  if(isa STREQUAL "avx2")
    # AVX2 without FMA: xsimd's default arch becomes avx2, not fma3<avx2> (which fuses inside its math).
    target_compile_options(${target} PRIVATE -mavx2 -mno-fma -mf16c -mpopcnt)
    target_compile_definitions(${target} PRIVATE QDMR_ISA=avx2 QDMR_ISA_ENUM=Avx2)
  elseif(isa STREQUAL "avx512")
    # No -mno-fma: clang's AVX512F implies FMA and -mno-fma would switch AVX-512 off (GCC 12's does not imply
    # it). Either way xsimd's default arch is avx512bw, whose fma is a*b+c; -ffp-contract=off does the rest.
    target_compile_options(${target} PRIVATE -mavx512f -mavx512cd -mavx512bw -mavx512dq -mavx512vl -mpopcnt)
    # GCC (12.2 here) warns inside its own AVX-512 intrinsics: _mm512_undefined_ps() is `__m512 __Y = __Y;`.
    # The SSE4.2 and AVX2 builds of the same sources keep these warnings.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      target_compile_options(${target} PRIVATE -Wno-uninitialized -Wno-maybe-uninitialized)
    endif()
    target_compile_definitions(${target} PRIVATE QDMR_ISA=avx512 QDMR_ISA_ENUM=Avx512)
  elseif(isa STREQUAL "sse4.2")
    target_compile_options(${target} PRIVATE -msse4.2 -mno-avx -mno-fma -mpopcnt)
    target_compile_definitions(${target} PRIVATE QDMR_ISA=sse42 QDMR_ISA_ENUM=Sse42)
  elseif(NOT isa STREQUAL "baseline")
    message(FATAL_ERROR "qdmr_project_flags: ISA must be baseline, sse4.2, avx2 or avx512, not '${isa}'")
  endif()
  if(QDMR_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
  if(QDMR_FUZZ)
    # Coverage for libFuzzer in every project target; the harnesses add -fsanitize=fuzzer (its main) themselves.
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()

# Compiles a target's sources in batches of eight (CMake's unity build; the test binaries, and every target of the
# `fuzz` preset, do the same): the library's shared headers (nlohmann/json, OpenEXR, oneTBB) are parsed, and their
# inline functions compiled, once per batch instead of once per file. The library's and the command's objects took
# 279 s of CPU instead of 372 s from an empty Release folder (Zen 3, 2026-12-07, GCC 12; the second figure from the
# ninja log of a CI run); a one-file change recompiles its batch. A file-local name (anonymous namespace or
# `static`) must not repeat in another file of the same target. The draw kernels stay one object per file: their
# code is what the benchmarks time.
function(qdmr_unity_build target)
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC takes an included .cpp for a header: a class defined there with a member of a file-local type (a class
    # of the library's own, such as StudyMeasurer::State) is warned about, rightly for a header, not for a batch.
    target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
  endif()
endfunction()

