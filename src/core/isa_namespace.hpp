#pragma once
// Code compiled once per ISA (the draw kernels and the SIMD helpers they use) lives in qdmr::<isa>, an inline
// namespace named by the build (-DQDMR_ISA=avx2), so the SSE4.2 and AVX2 copies of one function link into one
// binary side by side and never stand in for each other. Code outside the kernels that uses SIMD helpers is
// built for the baseline (x86-64) in qdmr::baseline.
#ifndef QDMR_ISA
#define QDMR_ISA baseline
#endif
#define QDMR_ISA_NAMESPACE inline QDMR_ISA
