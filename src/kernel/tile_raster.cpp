#include "kernel/tile_raster.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include <immintrin.h>

#include "kernel/batch.hpp"
#include "kernel/kernel_calls.hpp"
#include "kernel/quad_rows.hpp"
#include "qdmr/core/limits.hpp"
#include "texture/fetch_recorder.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using simd::Float;
using simd::kLanes;

constexpr int kBatchWidth = 2 * simd::kQuadsPerBatch;  // pixels per batch row
constexpr int kBlock = limits::kCoarseBlockSize;
static_assert(kBlock % kBatchWidth == 0, "coarse blocks hold whole batches in every build");

// Lane layout: quad q covers pixels (2q, 0) .. (2q+1, 1) of the batch, lanes 0 1 / 2 3 inside the quad.
constexpr int lane_dx(int lane) { return (lane / 4) * 2 + (lane % 2); }
constexpr int lane_dy(int lane) { return (lane % 4) / 2; }
constexpr std::uint32_t kAllLanes = (1u << kLanes) - 1u;  // kLanes <= 16

// A plane of the tile's pixels, Channels floats each, rows `stride` pixels apart, pixel (x0, y0) at data.
template <int Channels>
struct TilePlane {
  float* data;
  int x0, y0;
  std::size_t stride;
  float* at(int x, int y) const {
    return data + std::size_t(Channels) * (std::size_t(y - y0) * stride + std::size_t(x - x0));
  }
  std::size_t row_floats() const { return std::size_t(Channels) * stride; }  // from a pixel to the one below
};

// The tile's depth plane: its pixels' window depths, tested and written while the tile is drawn, in cache (a
// frame-sized plane would cost a fresh frame its first touch and every frame its memory traffic). Its stride is
// the tile's width rounded up to whole batches.
using TileDepth = TilePlane<1>;

// Where the tile's colours go while it is drawn, linear rgb: a thread's own tile colour plane (in cache while the
// tile draws, then streamed to the frame), or, for tiles too large for that to pay, the frame's colour plane.
using TileColor = TilePlane<3>;

using Int64 = xsimd::batch<std::int64_t, simd::Arch>;  // half a batch's lanes
using Double = xsimd::batch<double, simd::Arch>;
constexpr int kHalf = kLanes / 2;
static_assert(int(Int64::size) == kHalf && int(Double::size) == kHalf);

struct EdgeSteps {
  Int64 lane[3][2];  // edge value offset of each lane from the batch origin, per half batch
};

// All-ones in the lanes where bit `bit` of lane_dx (or lane_dy, for bit -1) is set: a lane's offset times an edge
// step is a sum of the step's shifted copies, selected by these.
constexpr std::array<std::int64_t, kLanes> lane_bit_mask(int bit) {
  std::array<std::int64_t, kLanes> m{};
  for (int l = 0; l < kLanes; ++l) m[std::size_t(l)] = ((bit < 0 ? lane_dy(l) : lane_dx(l) >> bit) & 1) ? -1 : 0;
  return m;
}
alignas(64) constexpr std::array<std::int64_t, kLanes> kLaneDx1 = lane_bit_mask(0), kLaneDx2 = lane_bit_mask(1),
                                                      kLaneDx4 = lane_bit_mask(2), kLaneDy1 = lane_bit_mask(-1);
static_assert(2 * simd::kQuadsPerBatch <= 8, "lane_dx fits in three bits");

// -dy * scale * lane_dx + dx * scale * lane_dy for each lane, exactly, in vector operations: scalar stores read back
// as vectors stalled on store forwarding at every triangle (a frame of small triangles spent a third of its
// triangle setup there).
EdgeSteps edge_steps(const TriangleSetup& s) {
  EdgeSteps e;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t a = -std::int64_t(s.dy[i]) * limits::kSubpixelScale;
    const std::int64_t b = std::int64_t(s.dx[i]) * limits::kSubpixelScale;
    for (int h = 0; h < 2; ++h) {
      const auto mask = [&](const auto& m) { return Int64::load_aligned(m.data() + h * kHalf); };
      e.lane[i][h] = (Int64(a) & mask(kLaneDx1)) + (Int64(a * 2) & mask(kLaneDx2)) + (Int64(a * 4) & mask(kLaneDx4)) +
                     (Int64(b) & mask(kLaneDy1));
    }
  }
  return e;
}

// w as the nearest float, as float(w) rounds it, for every lane (low: lanes 0 .. kHalf - 1), in vector operations
// (no int64 -> float instruction before AVX-512): w + 1.5 * 2^52 as a double is exact for |w| < 2^51, and rounding
// that exact double to float is the one rounding float(w) makes. Edge values stay below 2^50
// (limits::kGuardBandPixels).
Float edges_to_float(const Int64& low, const Int64& high) {
  constexpr double kMagic = 6755399441055744.0;  // 1.5 * 2^52, bits 0x4338000000000000
  const Int64 magic_bits(std::bit_cast<std::int64_t>(kMagic));
  return simd::narrow(xsimd::bitwise_cast<Double>(low + magic_bits) - Double(kMagic),
                      xsimd::bitwise_cast<Double>(high + magic_bits) - Double(kMagic));
}

// Bit j set where lane j of v is negative (its sign bit). Raw intrinsics: xsimd 8 has no mask-to-bits.
std::uint32_t negative_lanes(const Int64& v) {
#if defined(__AVX512F__)
  return std::uint32_t(_mm512_movepi64_mask(__m512i(v)));
#elif defined(__AVX__)
  return std::uint32_t(_mm256_movemask_pd(_mm256_castsi256_pd(__m256i(v))));
#else
  return std::uint32_t(_mm_movemask_pd(_mm_castsi128_pd(__m128i(v))));
#endif
}

// Classifies an 8x8 block: 0 = outside, 1 = partially covered, 2 = fully inside. An edge value is affine in the
// pixel, so its least and greatest over the block's corner pixels are the top-left corner's plus the negative
// (or positive) parts of its two steps across the block.
int classify_block(const TriangleSetup& s, int bx, int by) {
  constexpr std::int64_t kSpan = std::int64_t(kBlock - 1) * limits::kSubpixelScale;
  const std::int64_t X = pixel_centre_fixed(bx), Y = pixel_centre_fixed(by);
  bool full = true;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t w = s.edge(i, X, Y) + s.bias[i];
    const std::int64_t across_x = -std::int64_t(s.dy[i]) * kSpan, across_y = std::int64_t(s.dx[i]) * kSpan;
    const std::int64_t lo = w + std::min<std::int64_t>(across_x, 0) + std::min<std::int64_t>(across_y, 0);
    const std::int64_t hi = w + std::max<std::int64_t>(across_x, 0) + std::max<std::int64_t>(across_y, 0);
    if (hi < 0) return 0;
    if (lo < 0) full = false;
  }
  return full ? 2 : 1;
}

class TileRasterizer {
public:
  TileRasterizer(const RasterContext& context, const PixelRect& tile, const TileDepth& depth, const TileColor& color,
                 TileCounters& counters, FetchRecorder* recorder)
      : ctx_(context), fb_(*context.framebuffer), tile_(tile), depth_(depth), color_(color), counters_(counters),
        recorder_(recorder) {
    for (int a = 0; a < kAovCount; ++a) any_aov_ |= !fb_.aov[std::size_t(a)].empty() && Aov(a) != Aov::CacheMisses;
    alignas(64) float cx[kLanes], cy[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      cx[l] = float(lane_dx(l)) + 0.5f;
      cy[l] = float(lane_dy(l)) + 0.5f;
    }
    lane_centre_x_ = Float::load_aligned(cx);
    lane_centre_y_ = Float::load_aligned(cy);
  }

  void triangle(const TriangleSetup& s) {
    ++counters_.bin_entries;
    PixelRect r;
    r.x0 = std::max(s.bounds.x0, tile_.x0);
    r.y0 = std::max(s.bounds.y0, tile_.y0);
    r.x1 = std::min(s.bounds.x1, tile_.x1);
    r.y1 = std::min(s.bounds.y1, tile_.y1);
    if (r.empty()) return;
    setup_ = &s;
    steps_ = edge_steps(s);
    program_ = static_cast<const ShadingProgram*>(ctx_.programs[s.material]);
    varyings_ = program_->varying_count();
    for (int v = 0; v < 3; ++v) vertex_[v] = &ctx_.geometry->vertices[s.vertex[v]];
    // Broadcast once where a few batches will read them (a 1-pixel triangle of a dense mesh would pay for nothing).
    broadcast_once_ = (r.x1 - r.x0 + 1) * (r.y1 - r.y0 + 1) >= 4 * kLanes;
    if (broadcast_once_)
      for (int v = 0; v < 3; ++v)
        for (int k = 0; k < varyings_; ++k) vertex_varyings_[v][k] = Float(vertex_[v]->varyings[k]);

    // Quads of different triangles share a batch only among triangles of one program.
    if (packed_quads_ > 0 && slots_[packing_].program != program_) flush_packed();
    for (int by = r.y0 - r.y0 % kBlock; by <= r.y1; by += kBlock) {
      for (int bx = r.x0 - r.x0 % kBlock; bx <= r.x1; bx += kBlock) {
        const int kind = classify_block(s, bx, by);
        if (kind == 0) {
          ++counters_.blocks_rejected;
          continue;
        }
        ++(kind == 2 ? counters_.blocks_full : counters_.blocks_partial);
        const int y_begin = std::max(by, r.y0 & ~1), y_end = std::min(by + kBlock - 1, r.y1);
        const int x_begin = std::max(bx, r.x0 - r.x0 % kBatchWidth), x_end = std::min(bx + kBlock - 1, r.x1);
        for (int y = y_begin; y <= y_end; y += 2)
          for (int x = x_begin; x <= x_end; x += kBatchWidth) batch(x, y, kind == 2);
      }
    }
  }

  // Shades what is still held back: call once after the tile's last triangle.
  void flush() {
    flush_packed();
    if (held_count_ > 0) shade_held();
  }

private:
  // A batch that passed the early depth test, with what its shading needs and what its writing needs. Its quads
  // may lie anywhere in the tile (a packed batch: quads of different triangles of one program).
  struct PendingBatch {
    int quad_x[simd::kQuadsPerBatch] = {}, quad_y[simd::kQuadsPerBatch] = {};  // each quad's top-left pixel
    std::uint32_t pass = 0;  // lanes to write
    bool side_by_side = false;  // quad k at (quad_x[0] + 2k, quad_y[0]), as prepare() makes them (not packed)
    int lane_pixel_x(int lane) const { return quad_x[lane / 4] + lane % 2; }  // each lane's pixel
    int lane_pixel_y(int lane) const { return quad_y[lane / 4] + lane_dy(lane); }
    Float z;                 // the polygon's window depth
    alignas(64) float stored_depth[kLanes];
    Fragments in;
    const ShadingProgram* program = nullptr;
  };

  // The slot neither held back, nor packing, nor `busy`.
  int free_slot(int busy) const {
    int slot = 0;
    while (((held_slots_ >> slot) & 1u) != 0 || slot == packing_ || slot == busy) ++slot;
    return slot;
  }

  void batch(int x, int y, bool full) {
    const int slot = free_slot(-1);
    PendingBatch& p = slots_[slot];
    if (!prepare(x, y, full, slot)) return;
    if (packs_quads_ && live_quads(p.pass) < simd::kQuadsPerBatch) {
      pack(slot);
      return;
    }
    ready(slot);
  }

  static int live_quads(std::uint32_t pass) {
    int n = 0;
    for (int q = 0; q < simd::kQuadsPerBatch; ++q) n += ((pass >> (4 * q)) & 0xFu) != 0;
    return n;
  }

  // Whether held-back batch p will write a pixel of the batch at (x, y) that has its lane in `inside`.
  static bool writes_any_of(const PendingBatch& p, int x, int y, std::uint32_t inside) {
    for (int k = 0; k < simd::kQuadsPerBatch; ++k) {
      const std::uint32_t held = (p.pass >> (4 * k)) & 0xFu;
      const int q = (p.quad_x[k] - x) / 2;
      if (held != 0 && p.quad_y[k] == y && p.quad_x[k] >= x && q < simd::kQuadsPerBatch &&
          (held & (inside >> (4 * q))) != 0)
        return true;
    }
    return false;
  }

  // Moves the live quads of slots_[slot] into the packing batch, which is shaded whenever it is full.
  void pack(int slot) {
    const PendingBatch& from = slots_[slot];
    for (int q = 0; q < simd::kQuadsPerBatch; ++q) {
      if (((from.pass >> (4 * q)) & 0xFu) == 0) continue;
      PendingBatch& to = slots_[packing_];
      copy_quad(from, q, to, packed_quads_);
      ++packed_quads_;
      if (packed_quads_ == simd::kQuadsPerBatch) flush_packed(slot);
    }
  }

  // Quad q of `from` becomes quad k of `to`: every lane value, its position and its lanes to write.
  void copy_quad(const PendingBatch& from, int q, PendingBatch& to, int k) const {
    // Four lanes' bytes at once: a round trip through an array (store, copy, load) stalls on store forwarding.
    static_assert(sizeof(Float) == kLanes * sizeof(float) && std::is_trivially_copyable_v<Float>);
    const auto lanes = [&](const Float& source, Float& target) {
      std::memcpy(reinterpret_cast<char*>(&target) + 4 * k * sizeof(float),
                  reinterpret_cast<const char*>(&source) + 4 * q * sizeof(float), 4 * sizeof(float));
    };
    lanes(from.in.pixel_x, to.in.pixel_x);
    lanes(from.in.pixel_y, to.in.pixel_y);
    const int varyings = from.program->varying_count();  // read once: the copies might alias it
    for (int v = 0; v < varyings; ++v) lanes(from.in.varyings[v], to.in.varyings[v]);
    lanes(from.in.view_depth, to.in.view_depth);
    lanes(from.z, to.z);
    std::copy(from.stored_depth + 4 * q, from.stored_depth + 4 * q + 4, to.stored_depth + 4 * k);
    to.quad_x[k] = from.quad_x[q];
    to.quad_y[k] = from.quad_y[q];
    const std::uint32_t quad_mask = 0xFu << (4 * k);
    to.pass = (to.pass & ~quad_mask) | (((from.pass >> (4 * q)) & 0xFu) << (4 * k));
    to.program = from.program;
  }

  // Shades the packing batch, its empty quads filled with copies of its first quad (helper lanes, never
  // written); `busy` is a slot the caller still reads.
  void flush_packed(int busy = -1) {
    if (packed_quads_ == 0) return;
    PendingBatch& p = slots_[packing_];
    for (int k = packed_quads_; k < simd::kQuadsPerBatch; ++k) {
      const std::uint32_t pass = p.pass;
      copy_quad(p, 0, p, k);
      p.pass = pass & ~(0xFu << (4 * k));
    }
    p.in.covered = simd::from_bits(p.pass);
    p.side_by_side = false;
    const int slot = packing_;
    packed_quads_ = 0;
    packing_ = -1;
    ready(slot);
    packing_ = free_slot(busy);
    slots_[packing_].pass = 0;
  }

  // A batch ready to shade: held back for a group (ShadingProgram::grouping: a pair, or more), and the group
  // shaded once it is full. A program that shades one batch at a time, and every program while the texture-cache
  // recorder listens (it attributes fetches to the batch in flight), has groups of one: shaded at once.
  void ready(int slot) {
    PendingBatch& p = slots_[slot];
    if (p.program != grouping_of_) {  // asked once per program, not per batch
      grouping_of_ = p.program;
      grouping_ = recorder_ == nullptr ? p.program->grouping() : BatchGrouping{};
      grouping_.batches = std::min(grouping_.batches, kMaxGroupBatches);
    }
    // Batches held back write no pixel in common (prepare() writes a held-back batch before a batch with one of
    // its pixels is tested), so a later one's early depth test may run before an earlier one's write.
    const int lanes = std::popcount(p.pass);
    if (held_count_ > 0 && (slots_[held_[0]].program != p.program || held_lanes_ + lanes > grouping_.lanes))
      shade_held();
    held_[held_count_++] = slot;
    held_slots_ |= 1u << slot;
    held_lanes_ += lanes;
    if (held_count_ >= grouping_.batches) shade_held();
  }

  // Shades the batches held back, as one group: one batch (under the recorder's eyes when it listens) or a pair,
  // the usual cases, here; more in shade_held_group (its arrays would make every pair's frame bigger).
  void shade_held() {
    const ShadingProgram& program = *slots_[held_[0]].program;
    if (held_count_ <= 2) {
      ShadeOutput out[2];
      PendingBatch& first = slots_[held_[0]];
      if (held_count_ == 1) {
        if (recorder_ != nullptr) begin_recorded_batch(first);
        program.shade_one(first.in, out[0]);
        if (recorder_ != nullptr) recorder_->end_batch();
      } else {
        const Fragments* const in[2] = {&first.in, &slots_[held_[1]].in};
        ShadeOutput* const out_of[2] = {&out[0], &out[1]};
        program.shade(in, out_of, 2);
      }
      finish(first, out[0]);
      if (held_count_ == 2) finish(slots_[held_[1]], out[1]);
    } else {
      shade_held_group(program);
    }
    held_count_ = 0;
    held_lanes_ = 0;
    held_slots_ = 0;
  }

  // The texture cache sees the quads a GPU would run: every lane of a quad with a pixel to write.
  void begin_recorded_batch(const PendingBatch& p) {
    std::uint32_t issuing = 0;
    for (int q = 0; q < simd::kQuadsPerBatch; ++q)
      if ((p.pass >> (4 * q)) & 0xFu) issuing |= 0xFu << (4 * q);
    int lane_x[kLanes], lane_y[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      lane_x[l] = p.lane_pixel_x(l);
      lane_y[l] = p.lane_pixel_y(l);
    }
    recorder_->begin_batch(kLanes, lane_x, lane_y, issuing);
  }

  // shade_held() of more than two batches (a function of its own: its arrays would make every pair's frame bigger).
  [[gnu::noinline]] void shade_held_group(const ShadingProgram& program) {
    const Fragments* in[kMaxGroupBatches];
    ShadeOutput out[kMaxGroupBatches];
    ShadeOutput* out_of[kMaxGroupBatches];
    for (int k = 0; k < held_count_; ++k) {
      in[k] = &slots_[held_[k]].in;
      out_of[k] = &out[k];
    }
    program.shade(in, out_of, held_count_);
    for (int k = 0; k < held_count_; ++k) finish(slots_[held_[k]], out[k]);
  }

  // Whether a batch held back will write a pixel of the batch at (x, y) that has its lane in `inside`.
  bool held_writes_any_of(int x, int y, std::uint32_t inside) const {
    for (int k = 0; k < held_count_; ++k)
      if (writes_any_of(slots_[held_[k]], x, y, inside)) return true;
    return false;
  }

  // Coverage, early depth test and interpolation of the batch at (x, y) into slots_[slot]; false when no lane
  // passes. Inlined into the triangle's loop: its per-triangle values stay in registers (AVX2: the canonical
  // frame 23 instructions a batch fewer).
  [[gnu::always_inline]] bool prepare(int x, int y, bool full, int slot) {
    PendingBatch& p = slots_[slot];
    const TriangleSetup& s = *setup_;
    const std::int64_t X = pixel_centre_fixed(x), Y = pixel_centre_fixed(y);
    Int64 w[3][2];  // each edge's value at every lane, in halves
    for (int i = 0; i < 3; ++i) {
      const Int64 base(s.edge(i, X, Y));
      for (int h = 0; h < 2; ++h) w[i][h] = base + steps_.lane[i][h];
    }
    // Batches that lie wholly in the tile (all but those on its right or bottom edge) skip the per-lane bounds.
    const bool whole = x + kBatchWidth - 1 <= tile_.x1 && y + 1 <= tile_.y1;
    std::uint32_t inside = 0;
    if (full && whole) {
      inside = kAllLanes;
    } else {
      // A lane is inside where no biased edge value is negative: where their OR has no sign bit.
      std::uint32_t covered = kAllLanes;
      if (!full) {
        covered = 0;
        for (int h = 0; h < 2; ++h) {
          const Int64 any = (w[0][h] + Int64(s.bias[0])) | (w[1][h] + Int64(s.bias[1])) | (w[2][h] + Int64(s.bias[2]));
          covered |= (~negative_lanes(any) & ((1u << kHalf) - 1u)) << (h * kHalf);
        }
      }
      std::uint32_t in_tile = kAllLanes;
      if (!whole)
        for (int l = 0; l < kLanes; ++l)
          if (x + lane_dx(l) > tile_.x1 || y + lane_dy(l) > tile_.y1) in_tile &= ~(1u << l);
      inside = covered & in_tile;
      if (inside == 0) return false;
    }
    // A held-back batch that will write one of these pixels writes it before the early depth test reads it.
    // Quads at the same place with no pixel in common (two triangles sharing a quad) stay held back together.
    if (packed_quads_ > 0 && writes_any_of(slots_[packing_], x, y, inside)) flush_packed(slot);
    if (held_count_ > 0 && held_writes_any_of(x, y, inside)) shade_held();

    Float stored;
    if (whole) {
      // Lanes outside the triangle read their pixel's depth too: harmless, every test below is masked by inside.
      const float* row = depth_.at(x, y);
      stored = simd::load_quad_rows(row, row + depth_.row_floats());
      stored.store_aligned(p.stored_depth);
    } else {
      for (int l = 0; l < kLanes; ++l)
        p.stored_depth[l] = (inside >> l) & 1u ? *depth_.at(x + lane_dx(l), y + lane_dy(l)) : 0.0f;
      stored = Float::load_aligned(p.stored_depth);
    }
    const Float e0 = edges_to_float(w[0][0], w[0][1]), e1 = edges_to_float(w[1][0], w[1][1]),
                e2 = edges_to_float(w[2][0], w[2][1]);
    const Float z = e0 * Float(s.z_over_area[0]) + e1 * Float(s.z_over_area[1]) + e2 * Float(s.z_over_area[2]);
    const std::uint32_t pass = inside & simd::to_bits(z < stored);
    counters_.pixels_depth_failed += std::popcount(inside) - std::popcount(pass);
    if (pass == 0) return false;

    // Perspective-correct barycentrics: edge values weighted by 1/w, normalised.
    const Float p0 = e0 * Float(s.inv_w[0]), p1 = e1 * Float(s.inv_w[1]), p2 = e2 * Float(s.inv_w[2]);
    const Float sum = p0 + p1 + p2;
    const Float inv_sum = Float(1.0f) / sum;
    const Float b0 = p0 * inv_sum, b1 = p1 * inv_sum, b2 = p2 * inv_sum;

    Fragments& in = p.in;
    // float(x) + (dx + 0.5) is float(x + dx) + 0.5: every value is exact (pixel coordinates far below 2^23).
    in.pixel_x = Float(float(x)) + lane_centre_x_;
    in.pixel_y = Float(float(y)) + lane_centre_y_;
    if (varyings_ == kVaryingCount)
      interpolate<kVaryingCount>(in, b0, b1, b2);
    else
      interpolate<kBaseVaryingCount>(in, b0, b1, b2);
    in.view_depth = Float(float(s.area2)) * inv_sum;
    in.covered = simd::from_bits(pass);
    for (int q = 0; q < simd::kQuadsPerBatch; ++q) {
      p.quad_x[q] = x + 2 * q;
      p.quad_y[q] = y;
    }
    p.pass = pass;
    p.side_by_side = true;
    p.z = z;
    p.program = program_;
    return true;
  }

  // The first Count varyings at every lane from the barycentrics. A program interpolates every varying or all but
  // the blend weights (kBaseVaryingCount): a count known at compile time unrolls the loop. AVX2: 6 instructions a
  // varying with the vertex values broadcast once per triangle, 9 broadcasting them here, 11 before either.
  template <int Count>
  void interpolate(Fragments& in, const Float& b0, const Float& b1, const Float& b2) const {
    if (broadcast_once_) {
      for (int k = 0; k < Count; ++k)
        in.varyings[k] = b0 * vertex_varyings_[0][k] + b1 * vertex_varyings_[1][k] + b2 * vertex_varyings_[2][k];
    } else {
      for (int k = 0; k < Count; ++k)
        in.varyings[k] = b0 * Float(vertex_[0]->varyings[k]) + b1 * Float(vertex_[1]->varyings[k]) +
                         b2 * Float(vertex_[2]->varyings[k]);
    }
  }

  // The late depth test of a program that moved the surface, then the write.
  void finish(PendingBatch& p, const ShadeOutput& out) {
    if (out.writes_depth) {
      const std::uint32_t late = p.pass & simd::to_bits(out.depth < Float::load_aligned(p.stored_depth));
      counters_.pixels_depth_failed += std::popcount(p.pass) - std::popcount(late);
      if (late == 0) return;
      p.in.view_depth = out.view_depth;
      write(p, late, out.depth, out);
      return;
    }
    write(p, p.pass, p.z, out);
  }

  // The framebuffer index of each lane's pixel (for the AOV planes).
  void lane_pixels(const PendingBatch& p, std::size_t* index) const {
    for (int l = 0; l < kLanes; ++l) index[l] = fb_.index(p.lane_pixel_x(l), p.lane_pixel_y(l));
  }

  void write(const PendingBatch& p, std::uint32_t pass, const Float& z, const ShadeOutput& out) {
    const bool whole_rows = pass == kAllLanes && p.side_by_side;  // the usual batch inside a large triangle
    std::size_t index[kLanes];
    if (any_aov_) lane_pixels(p, index);
    if (whole_rows) {  // no test per lane: two rows of pixels, written by row
      float* const depth = depth_.at(p.quad_x[0], p.quad_y[0]);
      simd::store_quad_rows(z, depth, depth + depth_.row_floats());
      float* const row0 = color_.at(p.quad_x[0], p.quad_y[0]);
      simd::store_quad_rows_rgb(out.color[0], out.color[1], out.color[2], row0, row0 + color_.row_floats());
    } else {
      alignas(64) float zs[kLanes], color[3][kLanes];
      for (int c = 0; c < 3; ++c) out.color[c].store_aligned(color[c]);
      z.store_aligned(zs);
      for (int l = 0; l < kLanes; ++l) {
        if (!((pass >> l) & 1u)) continue;
        *depth_.at(p.lane_pixel_x(l), p.lane_pixel_y(l)) = zs[l];
        float* const rgb = color_.at(p.lane_pixel_x(l), p.lane_pixel_y(l));
        for (int c = 0; c < 3; ++c) rgb[c] = color[c][l];
      }
    }
    if (any_aov_) write_aovs(index, pass, p.in, out);
    count(pass, out);
  }

  void write_aovs(const std::size_t* index, std::uint32_t pass, const Fragments& in, const ShadeOutput& out) {
    // AOVs: each requested plane gets its channels, in the order aov_channels() documents.
    const Float* sources[kAovCount][3] = {
        {&in.view_depth},
        {&out.normal[0], &out.normal[1], &out.normal[2]},
        {&in.varyings[kU], &in.varyings[kV]},
        {&out.iterations},
        {&out.hit_u, &out.hit_v},
        {&out.hit_depth},
        {&out.error_texels},
        {&out.missed},
        {&out.shadow},
        {&out.ao},
        {}};  // cache_misses: added by the texture cache's replay after the tile
    for (int a = 0; a < kAovCount; ++a) {
      PixelBuffer& plane = fb_.aov[std::size_t(a)];
      if (plane.empty() || sources[a][0] == nullptr) continue;
      const int channels = aov_channels(Aov(a));
      alignas(64) float values[3][kLanes];
      for (int c = 0; c < channels; ++c) sources[a][c]->store_aligned(values[c]);
      for (int l = 0; l < kLanes; ++l) {
        if (!((pass >> l) & 1u)) continue;
        const std::size_t i = index[l];
        for (int c = 0; c < channels; ++c) plane[std::size_t(channels) * i + std::size_t(c)] = values[c][l];
      }
    }
  }

  void count(std::uint32_t pass, const ShadeOutput& out) {
    alignas(64) float iterations[kLanes];
    out.iterations.store_aligned(iterations);
    // Every lane alike (always, for a program without a trace): one compare instead of a scan.
    const bool alike = xsimd::all(out.iterations == Float(iterations[0]));
    float longest = iterations[0];
    for (int l = 1; l < kLanes && !alike; ++l) longest = std::max(longest, iterations[l]);
    if (alike) {  // one bin
      const auto n = std::uint64_t(longest);
      const auto lanes = std::uint64_t(std::popcount(pass));
      counters_.iterations_useful += n * lanes;
      counters_.count_iterations(n, lanes);
    } else {
      counters_.count_lanes(iterations, pass);
    }
    counters_.iterations_executed +=
        out.executed_lane_iterations >= 0 ? std::uint64_t(out.executed_lane_iterations) : std::uint64_t(longest) * kLanes;
    ++counters_.batches_shaded;
    counters_.pixels_shaded += std::popcount(pass);
    counters_.quads_shaded += std::uint64_t(live_quads(pass));
  }

  const RasterContext& ctx_;
  Framebuffer& fb_;
  PixelRect tile_;
  TileDepth depth_;
  TileColor color_;
  TileCounters& counters_;
  const TriangleSetup* setup_ = nullptr;
  EdgeSteps steps_{};
  const ShadingProgram* program_ = nullptr;
  const ScreenVertex* vertex_[3] = {};
  int varyings_ = 0;  // program_'s varying count
  bool broadcast_once_ = false;  // vertex_varyings_ holds the triangle's
  Float vertex_varyings_[3][kVaryingCount];  // the vertices' first varyings_ varyings, broadcast
  FetchRecorder* recorder_;
  // Batches with an empty quad give their live quads to a packing batch, shared by consecutive triangles of one
  // program (only where a batch holds several quads; not while the recorder attributes fetches to triangles'
  // batches as a GPU issues them).
  const bool packs_quads_ = simd::kQuadsPerBatch > 1 && recorder_ == nullptr;
  // The slots: the batch being prepared, the batches held back for a group (held_count_ of them, in held_, with
  // held_lanes_ covered lanes in all; held_slots_: bit i for slot i), the packing batch with packed_quads_ quads
  // so far.
  PendingBatch slots_[kMaxGroupBatches + 2];
  int held_[kMaxGroupBatches] = {};
  int held_count_ = 0, held_lanes_ = 0;
  const ShadingProgram* grouping_of_ = nullptr;  // the program grouping_ is of
  BatchGrouping grouping_;
  std::uint32_t held_slots_ = 0;
  int packing_ = kMaxGroupBatches + 1;
  int packed_quads_ = 0;
  bool any_aov_ = false;  // an AOV plane other than cache_misses (filled after the tile) is asked for
  Float lane_centre_x_, lane_centre_y_;  // each lane's pixel centre from the batch origin (dx + 0.5, dy + 0.5)
};

// Tiles up to this many pixels draw into a colour plane of their thread's (192 KiB at most, beside the depth plane:
// in L2 while the tile draws); larger ones into the frame.
constexpr int kMaxTileColorPixels = 128 * 128;

// The n floats at src to dst by streaming stores (movntps: the frame's cache lines are written whole, never read
// for ownership), dst's unaligned head and tail by plain stores. Raw intrinsics: xsimd 8 has no streaming store.
// With AVX, 64 bytes a loop from a 32-byte boundary (16 bytes a loop took 7 instructions: 2.7 M of a 960x540 frame).
void stream_floats(float* dst, const float* src, std::size_t n) {
#if defined(__AVX__)
  constexpr std::uintptr_t kAlign = 32;
#else
  constexpr std::uintptr_t kAlign = 16;
#endif
  for (; n > 0 && reinterpret_cast<std::uintptr_t>(dst) % kAlign != 0; --n) *dst++ = *src++;
#if defined(__AVX__)
  for (; n >= 16; n -= 16, dst += 16, src += 16) {
    _mm256_stream_ps(dst, _mm256_loadu_ps(src));
    _mm256_stream_ps(dst + 8, _mm256_loadu_ps(src + 8));
  }
#endif
  for (; n >= 4; n -= 4, dst += 4, src += 4) _mm_stream_ps(dst, _mm_loadu_ps(src));
  for (; n > 0; --n) *dst++ = *src++;
}

}  // namespace

void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                 TileCounters& counters) {
  kernel_calls.tiles.fetch_add(1, std::memory_order_relaxed);
  Framebuffer& fb = *context.framebuffer;
  fb.clear_aovs(tile.x0, tile.y0, tile.x1, tile.y1);
  const int width = tile.x1 - tile.x0 + 1, height = tile.y1 - tile.y0 + 1;
  // The tile's colour, cleared to the background here and written to the frame once, after the tile: into the
  // frame, a tile's pixels were cleared at its start and, by the time its long shading wrote them, often evicted,
  // so each frame line was read from memory twice (measured in docs/performance-history.md).
  thread_local PixelBuffer color_plane;
  const bool own_plane = width * height <= kMaxTileColorPixels;
  if (own_plane && color_plane.size() < 3 * std::size_t(width) * std::size_t(height))
    color_plane.resize(3 * std::size_t(width) * std::size_t(height));
  const TileColor color = own_plane ? TileColor{color_plane.data(), tile.x0, tile.y0, std::size_t(width)}
                                    : TileColor{fb.color.data() + 3 * fb.index(tile.x0, tile.y0), tile.x0, tile.y0,
                                                std::size_t(fb.width)};
  for (int y = tile.y0; y <= tile.y1; ++y) {
    float* const rgb = color.at(tile.x0, y);
    for (int i = 0; i < width; ++i) {
      rgb[3 * i] = fb.background.x;
      rgb[3 * i + 1] = fb.background.y;
      rgb[3 * i + 2] = fb.background.z;
    }
  }
  const auto copy_color_out = [&] {
    if (!own_plane) return;
    for (int y = tile.y0; y <= tile.y1; ++y)
      stream_floats(fb.color.data() + 3 * fb.index(tile.x0, y), color.at(tile.x0, y), 3 * std::size_t(width));
    _mm_sfence();  // streaming stores are weakly ordered: visible before the tile counts as done
  };
  // Each worker thread's tile depth plane, cleared to 1 (uncovered) for each tile; rows of whole batches and an
  // even number of rows, so a batch's lanes past the frame's edge (never tested or written) stay inside it. It
  // lives as long as the thread: 16 KiB at the default tile size, 4 MiB at the largest (limits::kMaxTileSize).
  thread_local PixelBuffer depth_plane;
  const std::size_t stride = std::size_t((tile.x1 - tile.x0 + kBatchWidth) / kBatchWidth * kBatchWidth);
  const std::size_t rows = std::size_t((tile.y1 - tile.y0 + 2) / 2 * 2);
  if (depth_plane.size() < stride * rows) depth_plane.resize(stride * rows);
  std::fill_n(depth_plane.data(), stride * rows, 1.0f);
  const TileDepth depth{depth_plane.data(), tile.x0, tile.y0, stride};
  const Viewport viewport{fb.width, fb.height};
  const auto setup = [&](std::uint32_t index) {
    return setup_triangle(context.geometry->triangles[index], *context.geometry, viewport);
  };
  // What reads depth after the tile (keeps_depth_plane) reads the frame's plane.
  const auto copy_depth_out = [&] {
    if (fb.depth.empty()) return;
    for (int y = tile.y0; y <= tile.y1; ++y)
      std::copy_n(depth.at(tile.x0, y), tile.x1 - tile.x0 + 1, fb.depth.data() + fb.index(tile.x0, y));
  };
  if (context.cache == nullptr) {
    TileRasterizer rasterizer(context, tile, depth, color, counters, nullptr);
    bins.for_each_in_tile(tile_index, [&](std::uint32_t index) { rasterizer.triangle(setup(index)); });
    rasterizer.flush();
    copy_color_out();
    copy_depth_out();
    return;
  }
  // With the texture cache: record the tile's fetches, then replay them through the cache.
  FetchRecorder recorder(*context.cache, *context.cache_addresses, tile.x0, tile.y0, tile.x1, tile.y1);
  {
    const FetchRecorder::Listening listening(recorder);
    TileRasterizer rasterizer(context, tile, depth, color, counters, &recorder);
    bins.for_each_in_tile(tile_index, [&](std::uint32_t index) { rasterizer.triangle(setup(index)); });
    rasterizer.flush();
  }
  copy_color_out();
  copy_depth_out();
  TextureCache cache(*context.cache);
  CacheCounters cache_counters;
  PixelBuffer& misses = fb.aov[std::size_t(Aov::CacheMisses)];
  recorder.replay(cache, cache_counters, fb.width, fb.height, fb.depth.data(), misses.empty() ? nullptr : misses.data());
  counters.cache_accesses += cache_counters.accesses;
  counters.cache_hits += cache_counters.hits;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
