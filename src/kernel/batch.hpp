#pragma once
// The shading program interface inside a draw kernel: one batch of lanes (whole 2x2 quads) in, colour and
// AOVs out. Compiled once per ISA (simd::Float is the kernel's batch type).
#include <cstddef>

#include "core/simd.hpp"
#include "program/program.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Interpolated inputs of one batch of whole quads; the quads may come from different triangles of one program
// (no two of them write the same pixel). Every lane carries values, including helper lanes outside their quad's
// triangle (extrapolated, as on a GPU), so quad derivatives are defined; only `covered` lanes are written.
struct Fragments {
  simd::Float pixel_x, pixel_y;  // pixel centres
  simd::Float varyings[kVaryingCount];
  simd::Float view_depth;        // distance along the view axis
  simd::Mask covered;            // inside the triangle and passed the depth test
};

struct ShadeOutput {
  simd::Float color[3];   // linear RGB
  simd::Float normal[3];  // world-space shading normal (for the "normal" AOV)
  // Displacement AOVs (see Aov in qdmr/core/aov.hpp); every program sets them.
  simd::Float iterations, hit_u, hit_v, hit_depth, error_texels, missed;
  // Lighting AOVs: self-shadow visibility of the first directional light and the AO term on the ambient light,
  // both 1 when the program or material does not compute them. Every program sets them.
  simd::Float shadow, ao;
  // Programs that displace the surface may replace the polygon's depth (window depth, and distance along the
  // view axis for the depth AOV); the rasterizer then tests it again before writing (a late depth test).
  bool writes_depth = false;
  // The lane-iterations the SIMD loops executed for this batch where its lanes ran packed with other batches'
  // (ShadingProgram::shade of a group; each packed batch counted once, with one of its batches); -1: the batch ran as
  // itself, its longest lane's iterations times the lanes.
  int executed_lane_iterations = -1;
  simd::Float depth, view_depth;

  // f(value) for each lane-wise output, value(out) being that Float of an output (ShadeOutput or const): every
  // member but depth and view_depth (set from whole quads, after the lane-wise stages: batch_scheduler.hpp) and
  // the two scalars. What a packed batch hands back to the batches its lanes came from.
  template <class F>
  static constexpr void lane_values(F&& f) {
    for (int c = 0; c < 3; ++c) f([c](auto& o) -> auto& { return o.color[c]; });
    for (int c = 0; c < 3; ++c) f([c](auto& o) -> auto& { return o.normal[c]; });
    f([](auto& o) -> auto& { return o.iterations; });
    f([](auto& o) -> auto& { return o.hit_u; });
    f([](auto& o) -> auto& { return o.hit_v; });
    f([](auto& o) -> auto& { return o.hit_depth; });
    f([](auto& o) -> auto& { return o.error_texels; });
    f([](auto& o) -> auto& { return o.missed; });
    f([](auto& o) -> auto& { return o.shadow; });
    f([](auto& o) -> auto& { return o.ao; });
  }
};
// lane_values() lists every Float but depth and view_depth (the two scalars share one Float's room): a member added
// without it fails here.
static_assert(sizeof(ShadeOutput) == std::size_t([] {
                int count = 0;
                ShadeOutput::lane_values([&](auto) { ++count; });
                return count + 3;
              }()) * sizeof(simd::Float));

// The most batches a program's group (ShadingProgram::shade) may hold.
inline constexpr int kMaxGroupBatches = 8;

// How many batches a program shades at once: up to `batches` that write no pixel in common, with at most `lanes`
// covered lanes in all. A program that gains from interleaving batches (its loops wait on their own fetches, or
// its stages are chains of dependent operations the core can overlap with another batch's) asks for two; one that
// packs sparse batches' covered lanes into fewer asks for more. The rasterizer then hands it groups, except while
// the texture-cache recorder listens (it attributes fetches to the batch in flight).
struct BatchGrouping {
  int batches = 1;  // 1 .. kMaxGroupBatches
  int lanes = simd::kLanes;
};

class ShadingProgram : public Program {
public:
  using Program::Program;
  virtual BatchGrouping grouping() const { return {}; }
  // Batches in[0 .. n-1] into out[0 .. n-1], 1 <= n <= grouping().batches, each with the same results as alone.
  virtual void shade(const Fragments* const* in, ShadeOutput* const* out, int n) const = 0;
  // One batch: a group of one.
  void shade_one(const Fragments& in, ShadeOutput& out) const {
    const Fragments* const one_in[1] = {&in};
    ShadeOutput* const one_out[1] = {&out};
    shade(one_in, one_out, 1);
  }
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
