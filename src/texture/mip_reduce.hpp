#pragma once
// Mip-level reduction shared by the baseline chain builder (mip_texture.cpp) and the kernels' max/min reducers
// (kernel/mip_reduce.cpp, compiled once per ISA): texel access, the taps of an output texel, rows in parallel, and
// the max/min reduction around the kernels' vector loop. In the ISA namespace, so each copy is compiled for the
// code that uses it.
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


// The scalar forms return what MAXPS / MINPS return (the second operand unless the first wins), so a kernel's
// vector loop and the scalar code agree even on NaN and signed zeros.
struct MaxOp {
  static constexpr bool kMax = true;
  template <class T>
  static T scalar(T a, T b) { return a > b ? a : b; }
};

struct MinOp {
  static constexpr bool kMax = false;
  template <class T>
  static T scalar(T a, T b) { return a < b ? a : b; }
};

// The portable reducer's vector loop: none (Vectors::pairs reduces the first pairs of a row that fill whole
// vectors and returns how many; the scalar code does the rest).
struct NoVectors {
  template <class Op, class T, int C>
  static int pairs(const std::uint8_t*, const std::uint8_t*, std::uint8_t*, int) { return 0; }
};

// One output row from input rows a and b (b == a for a single row) of in_width texels: out texel i = op over
// texels 2i and 2i+1 of rows a and b (vertical first, then horizontal). T is the channel type, C the channel count.
template <class Vectors, class Op, class T, int C>
void reduce_two_rows(const std::uint8_t* a, const std::uint8_t* b, int in_width, std::uint8_t* out, int out_width) {
  if (in_width == 1) {
    for (int c = 0; c < C; ++c) store<T>(out, c, Op::scalar(load<T>(a, c), load<T>(b, c)));
    return;
  }
  for (int i = Vectors::template pairs<Op, T, C>(a, b, out, out_width); i < out_width; ++i)
    for (int c = 0; c < C; ++c) {
      const std::size_t left = std::size_t(2 * i) * C + c, right = left + C;
      const T l = Op::scalar(load<T>(a, left), load<T>(b, left));
      const T r = Op::scalar(load<T>(a, right), load<T>(b, right));
      store<T>(out, std::size_t(i) * C + c, Op::scalar(l, r));
    }
  if (in_width & 1)  // the last texel also covers the leftover column
    for (int c = 0; c < C; ++c) {
      const std::size_t last = std::size_t(in_width - 1) * C + c, o = std::size_t(out_width - 1) * C + c;
      store<T>(out, o, Op::scalar(load<T>(out, o), Op::scalar(load<T>(a, last), load<T>(b, last))));
    }
}

template <class Vectors, class Op, class T, int C>
void reduce_extremum(const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w, int out_h) {
  const std::size_t in_row = std::size_t(in_w) * C * sizeof(T), out_row = std::size_t(out_w) * C * sizeof(T);
  for_rows(out_h, out_row, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const Taps ty = taps(y, in_h, out_h);
      const std::uint8_t* r0 = in + std::size_t(ty.first) * in_row;
      std::uint8_t* o = out + std::size_t(y) * out_row;
      reduce_two_rows<Vectors, Op, T, C>(r0, ty.count > 1 ? r0 + in_row : r0, in_w, o, out_w);
      if (ty.count == 3) {  // the leftover row of an odd height: once per level, scalar
        const std::uint8_t* r2 = r0 + 2 * in_row;
        for (int x = 0; x < out_w; ++x) {
          const Taps tx = taps(x, in_w, out_w);
          for (int c = 0; c < C; ++c) {
            T v = load<T>(r2, std::size_t(tx.first) * C + c);
            for (int i = 1; i < tx.count; ++i) v = Op::scalar(v, load<T>(r2, std::size_t(tx.first + i) * C + c));
            const std::size_t oi = std::size_t(x) * C + c;
            store<T>(o, oi, Op::scalar(load<T>(o, oi), v));
          }
        }
      }
    }
  });
}

template <class Vectors, class Op>
void reduce_format(TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w,
                   int out_h) {
  switch (format) {
    case TexelFormat::R8: reduce_extremum<Vectors, Op, std::uint8_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RG8: reduce_extremum<Vectors, Op, std::uint8_t, 2>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RGBA8: reduce_extremum<Vectors, Op, std::uint8_t, 4>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R16: reduce_extremum<Vectors, Op, std::uint16_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R32F: reduce_extremum<Vectors, Op, float, 1>(in, in_w, in_h, out, out_w, out_h); break;
  }
}

// A MipExtremum (qdmr/texture/mip_texture.hpp) with the vector loop `Vectors`: the same bits with any.
template <class Vectors>
void extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                     int out_w, int out_h) {
  if (max)
    reduce_format<Vectors, MaxOp>(format, in, in_w, in_h, out, out_w, out_h);
  else
    reduce_format<Vectors, MinOp>(format, in, in_w, in_h, out, out_w, out_h);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::mip
