# Flags for project code only (dependencies are compiled by Debian).
function(qdmr_project_flags target simd)
  # -ffp-contract=off: no fused multiply-add behind our back, so SSE and AVX2 builds give the same bits.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror -ffp-contract=off -fno-fast-math)
  if(simd STREQUAL "avx2")
    # AVX2 without FMA: xsimd's default arch becomes avx2, not fma3<avx2> (which fuses inside its math).
    target_compile_options(${target} PRIVATE -mavx2 -mno-fma -mf16c -mpopcnt)
  elseif(simd STREQUAL "sse4.2")
    target_compile_options(${target} PRIVATE -msse4.2 -mno-avx -mno-fma -mpopcnt)
  else()
    message(FATAL_ERROR "QDMR_SIMD must be avx2 or sse4.2, not '${simd}'")
  endif()
  if(QDMR_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()
