#include "raster/tile_raster.hpp"

#include <algorithm>
#include <bit>

#include "program/batch.hpp"
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

struct EdgeSteps {
  std::int64_t lane[3][kLanes];  // edge value offset of each lane from the batch origin
};

EdgeSteps edge_steps(const TriangleSetup& s) {
  EdgeSteps e;
  for (int i = 0; i < 3; ++i)
    for (int l = 0; l < kLanes; ++l)
      e.lane[i][l] = -std::int64_t(s.dy[i]) * limits::kSubpixelScale * lane_dx(l) +
                     std::int64_t(s.dx[i]) * limits::kSubpixelScale * lane_dy(l);
  return e;
}

// w as the nearest float, as float(w) rounds it, in operations a compiler vectorises (no int64 -> float
// instruction before AVX-512): w + 1.5 * 2^52 as a double is exact for |w| < 2^51, and rounding that exact double
// to float is the one rounding float(w) makes. Edge values stay below 2^50 (limits::kGuardBandPixels).
inline float edge_to_float(std::int64_t w) {
  constexpr double kMagic = 6755399441055744.0;  // 1.5 * 2^52, bits 0x4338000000000000
  return float(std::bit_cast<double>(std::uint64_t(w) + std::bit_cast<std::uint64_t>(kMagic)) - kMagic);
}

// Classifies an 8x8 block: 0 = outside, 1 = partially covered, 2 = fully inside.
int classify_block(const TriangleSetup& s, int bx, int by) {
  bool full = true;
  for (int i = 0; i < 3; ++i) {
    std::int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (int corner = 0; corner < 4; ++corner) {
      const std::int64_t X = pixel_centre_fixed(bx + (corner & 1) * (kBlock - 1));
      const std::int64_t Y = pixel_centre_fixed(by + (corner >> 1) * (kBlock - 1));
      const std::int64_t w = s.edge(i, X, Y) + s.bias[i];
      lo = std::min(lo, w);
      hi = std::max(hi, w);
    }
    if (hi < 0) return 0;
    if (lo < 0) full = false;
  }
  return full ? 2 : 1;
}

class TileRasterizer {
public:
  TileRasterizer(const RasterContext& context, const PixelRect& tile, TileCounters& counters, FetchRecorder* recorder)
      : ctx_(context), fb_(*context.framebuffer), tile_(tile), counters_(counters), recorder_(recorder) {
    for (int a = 0; a < kAovCount; ++a) any_aov_ |= !fb_.aov[std::size_t(a)].empty() && Aov(a) != Aov::CacheMisses;
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
    for (int v = 0; v < 3; ++v) vertex_[v] = &ctx_.geometry->vertices[s.vertex[v]];

    pair_batches_ = recorder_ == nullptr && program_->pairs_batches();
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
    if (waiting_) {  // the triangle's last batch had no partner
      waiting_ = false;
      ShadeOutput out;
      program_->shade(pending_[0].in, out);
      finish(pending_[0], out);
    }
  }

private:
  // A batch that passed the early depth test, with what its shading needs and what its writing needs.
  struct PendingBatch {
    int x = 0, y = 0;
    std::uint32_t pass = 0;  // lanes to write
    Float z;                 // the polygon's window depth
    alignas(64) float stored_depth[kLanes];
    Fragments in;
  };

  void batch(int x, int y, bool full) {
    PendingBatch& p = pending_[waiting_ ? 1 : 0];
    if (!prepare(x, y, full, p)) return;
    if (pair_batches_) {
      // Batches of one triangle share no pixel, so the second one's early depth test may run before the first
      // one's write.
      if (!waiting_) {
        waiting_ = true;
        return;
      }
      waiting_ = false;
      ShadeOutput out[2];
      program_->shade_pair(pending_[0].in, out[0], pending_[1].in, out[1]);
      finish(pending_[0], out[0]);
      finish(pending_[1], out[1]);
      return;
    }
    ShadeOutput out;
    if (recorder_ != nullptr) {
      // The texture cache sees the quads a GPU would run: every lane of a quad with a pixel to write.
      std::uint32_t issuing = 0;
      for (int q = 0; q < simd::kQuadsPerBatch; ++q)
        if ((p.pass >> (4 * q)) & 0xFu) issuing |= 0xFu << (4 * q);
      int lane_x[kLanes], lane_y[kLanes];
      for (int l = 0; l < kLanes; ++l) {
        lane_x[l] = x + lane_dx(l);
        lane_y[l] = y + lane_dy(l);
      }
      recorder_->begin_batch(kLanes, lane_x, lane_y, issuing);
      program_->shade(p.in, out);
      recorder_->end_batch();
    } else {
      program_->shade(p.in, out);
    }
    finish(p, out);
  }

  // Coverage, early depth test and interpolation of the batch at (x, y) into p; false when no lane passes.
  bool prepare(int x, int y, bool full, PendingBatch& p) {
    const TriangleSetup& s = *setup_;
    const std::int64_t X = pixel_centre_fixed(x), Y = pixel_centre_fixed(y);
    alignas(64) std::int64_t w[3][kLanes];
    for (int i = 0; i < 3; ++i) {
      const std::int64_t base = s.edge(i, X, Y);
      for (int l = 0; l < kLanes; ++l) w[i][l] = base + steps_.lane[i][l];
    }
    // Batches that lie wholly in the tile (all but those on its right or bottom edge) skip the per-lane bounds.
    const bool whole = x + kBatchWidth - 1 <= tile_.x1 && y + 1 <= tile_.y1;
    std::uint32_t inside = 0;
    if (full && whole) {
      inside = (1u << kLanes) - 1u;
    } else {
      for (int l = 0; l < kLanes; ++l) {
        const int px = x + lane_dx(l), py = y + lane_dy(l);
        if (px > tile_.x1 || py > tile_.y1) continue;
        const bool in = full || ((w[0][l] + s.bias[0]) | (w[1][l] + s.bias[1]) | (w[2][l] + s.bias[2])) >= 0;
        inside |= std::uint32_t(in) << l;
      }
      if (inside == 0) return false;
    }

    alignas(64) float e[3][kLanes];
    float* stored_depth = p.stored_depth;
    for (int i = 0; i < 3; ++i)
      for (int l = 0; l < kLanes; ++l) e[i][l] = edge_to_float(w[i][l]);
    if (whole) {
      // Lanes outside the triangle read their pixel's depth too: harmless, every test below is masked by inside.
      const float* row = fb_.depth.data() + fb_.index(x, y);
      for (int l = 0; l < kLanes; ++l) stored_depth[l] = row[lane_dy(l) * fb_.width + lane_dx(l)];
    } else {
      for (int l = 0; l < kLanes; ++l)
        stored_depth[l] = (inside >> l) & 1u ? fb_.depth[fb_.index(x + lane_dx(l), y + lane_dy(l))] : 0.0f;
    }
    const Float e0 = Float::load_aligned(e[0]), e1 = Float::load_aligned(e[1]), e2 = Float::load_aligned(e[2]);
    const Float z = e0 * Float(s.z_over_area[0]) + e1 * Float(s.z_over_area[1]) + e2 * Float(s.z_over_area[2]);
    const std::uint32_t pass = inside & simd::to_bits(z < Float::load_aligned(stored_depth));
    counters_.pixels_depth_failed += std::popcount(inside) - std::popcount(pass);
    if (pass == 0) return false;

    // Perspective-correct barycentrics: edge values weighted by 1/w, normalised.
    const Float p0 = e0 * Float(s.inv_w[0]), p1 = e1 * Float(s.inv_w[1]), p2 = e2 * Float(s.inv_w[2]);
    const Float sum = p0 + p1 + p2;
    const Float inv_sum = Float(1.0f) / sum;
    const Float b0 = p0 * inv_sum, b1 = p1 * inv_sum, b2 = p2 * inv_sum;

    Fragments& in = p.in;
    alignas(64) float px[kLanes], py[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      px[l] = float(x + lane_dx(l)) + 0.5f;
      py[l] = float(y + lane_dy(l)) + 0.5f;
    }
    in.pixel_x = Float::load_aligned(px);
    in.pixel_y = Float::load_aligned(py);
    for (int k = 0; k < program_->varying_count(); ++k)
      in.varyings[k] = b0 * Float(vertex_[0]->varyings[k]) + b1 * Float(vertex_[1]->varyings[k]) +
                       b2 * Float(vertex_[2]->varyings[k]);
    in.view_depth = Float(float(s.area2)) * inv_sum;
    in.covered = simd::from_bits(pass);
    p.x = x;
    p.y = y;
    p.pass = pass;
    p.z = z;
    return true;
  }

  // The late depth test of a program that moved the surface, then the write.
  void finish(PendingBatch& p, const ShadeOutput& out) {
    if (out.writes_depth) {
      const std::uint32_t late = p.pass & simd::to_bits(out.depth < Float::load_aligned(p.stored_depth));
      counters_.pixels_depth_failed += std::popcount(p.pass) - std::popcount(late);
      if (late == 0) return;
      p.in.view_depth = out.view_depth;
      write(p.x, p.y, late, out.depth, p.in, out);
      return;
    }
    write(p.x, p.y, p.pass, p.z, p.in, out);
  }

  void write(int x, int y, std::uint32_t pass, const Float& z, const Fragments& in, const ShadeOutput& out) {
    alignas(64) float zs[kLanes], color[3][kLanes];
    z.store_aligned(zs);
    for (int c = 0; c < 3; ++c) out.color[c].store_aligned(color[c]);
    const std::size_t origin = fb_.index(x, y);
    for (int l = 0; l < kLanes; ++l) {
      if (!((pass >> l) & 1u)) continue;
      const std::size_t i = origin + std::size_t(lane_dy(l) * fb_.width + lane_dx(l));
      fb_.depth[i] = zs[l];
      for (int c = 0; c < 3; ++c) fb_.color[3 * i + c] = color[c][l];
    }
    if (any_aov_) write_aovs(x, y, pass, in, out);
    count(pass, out);
  }

  void write_aovs(int x, int y, std::uint32_t pass, const Fragments& in, const ShadeOutput& out) {
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
        const std::size_t i = fb_.index(x + lane_dx(l), y + lane_dy(l));
        for (int c = 0; c < channels; ++c) plane[std::size_t(channels) * i + std::size_t(c)] = values[c][l];
      }
    }
  }

  void count(std::uint32_t pass, const ShadeOutput& out) {
    alignas(64) float iterations[kLanes];
    out.iterations.store_aligned(iterations);
    float longest = iterations[0], shortest = iterations[0];
    for (int l = 1; l < kLanes; ++l) {
      longest = std::max(longest, iterations[l]);
      shortest = std::min(shortest, iterations[l]);
    }
    if (longest == shortest) {  // every lane alike (always, for a program without a trace): one bin
      const auto n = std::uint64_t(longest);
      const auto lanes = std::uint64_t(std::popcount(pass));
      counters_.iterations_useful += n * lanes;
      counters_.iteration_histogram[std::min<std::uint64_t>(n, TileCounters::kIterationBins)] += lanes;
    } else {
      for (int l = 0; l < kLanes; ++l) {
        if (!((pass >> l) & 1u)) continue;
        const auto n = std::uint64_t(iterations[l]);
        counters_.iterations_useful += n;
        ++counters_.iteration_histogram[std::min<std::uint64_t>(n, TileCounters::kIterationBins)];
      }
    }
    counters_.iterations_executed += std::uint64_t(longest) * kLanes;
    ++counters_.batches_shaded;
    counters_.pixels_shaded += std::popcount(pass);
    for (int q = 0; q < simd::kQuadsPerBatch; ++q) counters_.quads_shaded += ((pass >> (4 * q)) & 0xFu) != 0;
  }

  const RasterContext& ctx_;
  Framebuffer& fb_;
  PixelRect tile_;
  TileCounters& counters_;
  const TriangleSetup* setup_ = nullptr;
  EdgeSteps steps_{};
  const ShadingProgram* program_ = nullptr;
  const ScreenVertex* vertex_[3] = {};
  FetchRecorder* recorder_;
  bool pair_batches_ = false;  // the program shades batches in pairs (and no recorder listens)
  bool waiting_ = false;       // pending_[0] waits for a partner
  PendingBatch pending_[2];
  bool any_aov_ = false;  // an AOV plane other than cache_misses (filled after the tile) is asked for
};

}  // namespace


void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                 TileCounters& counters) {
  Framebuffer& fb = *context.framebuffer;
  fb.clear_rect(tile.x0, tile.y0, tile.x1, tile.y1);
  if (context.cache == nullptr) {
    TileRasterizer rasterizer(context, tile, counters, nullptr);
    bins.for_each_in_tile(tile_index, [&](std::uint32_t index) { rasterizer.triangle((*context.setups)[index]); });
    return;
  }
  // With the texture cache: record the tile's fetches, then replay them through the cache.
  FetchRecorder recorder(*context.cache, *context.cache_addresses, tile.x0, tile.y0, tile.x1, tile.y1);
  {
    const FetchRecorder::Listening listening(recorder);
    TileRasterizer rasterizer(context, tile, counters, &recorder);
    bins.for_each_in_tile(tile_index, [&](std::uint32_t index) { rasterizer.triangle((*context.setups)[index]); });
  }
  TextureCache cache(*context.cache);
  CacheCounters cache_counters;
  PixelBuffer& misses = fb.aov[std::size_t(Aov::CacheMisses)];
  recorder.replay(cache, cache_counters, fb.width, fb.height, fb.depth.data(), misses.empty() ? nullptr : misses.data());
  counters.cache_accesses += cache_counters.accesses;
  counters.cache_hits += cache_counters.hits;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
