#pragma once
// Mip-level reduction shared by the baseline chain builder (mip_texture.cpp) and the per-ISA max/min reducers
// (mip_reduce.cpp, compiled once per ISA like the draw kernels): texel access, the taps of an output texel, and
// rows in parallel. In the ISA namespace, so each copy is compiled for the code that uses it.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/isa_namespace.hpp"
#include "qdmr/texture/format.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::mip {

template <class T>
inline T load(const std::uint8_t* p, std::size_t index) {
  T v;
  std::memcpy(&v, p + index * sizeof(T), sizeof(T));
  return v;
}

template <class T>
inline void store(std::uint8_t* p, std::size_t index, T v) {
  std::memcpy(p + index * sizeof(T), &v, sizeof(T));
}

// Channel c of a texel as float and back, for the format (and sRGB flag) of a texture.
struct Taps {
  int first;
  int count;  // 1 (an axis of size 1), 2, or 3 (last texel of an odd axis)
};

inline Taps taps(int i, int in_size, int out_size) {
  if (in_size == 1) return {0, 1};
  return {2 * i, (i == out_size - 1 && (in_size & 1)) ? 3 : 2};
}

// f(first_row, end_row) over the rows of a level; in parallel only when the level is big enough to pay for it.
// Each row is computed the same way whatever the split, so results do not depend on the thread count.
template <class F>
void for_rows(int rows, std::size_t row_bytes, F&& f) {
  // Below ~256 KB a level takes a few microseconds: splitting it costs more than it saves (measured).
  constexpr std::size_t kChunkBytes = 32 * 1024;
  if (std::size_t(rows) * row_bytes < 8 * kChunkBytes) {
    f(0, rows);
    return;
  }
  const int grain = int(std::max<std::size_t>(1, kChunkBytes / row_bytes));
  tbb::parallel_for(tbb::blocked_range<int>(0, rows, grain),
                    [&](const tbb::blocked_range<int>& r) { f(r.begin(), r.end()); });
}


// Max (or min) of each output texel's taps, level `in` (in_w x in_h) to level `out`; the same bits on every ISA.
void reduce_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                     int out_w, int out_h);

}  // namespace qdmr::QDMR_ISA_NAMESPACE::mip

namespace qdmr {

// mip::reduce_extremum of the best reducer this CPU runs (the results are the same bits on every ISA).
void reduce_extremum_best(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                          int out_w, int out_h);

}  // namespace qdmr
