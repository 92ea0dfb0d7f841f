#include "shade/displacement.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "qdmr/core/error.hpp"
#include "qdmr/study/reference.hpp"
#include "qdmr/core/limits.hpp"
#include "shade/ambient_occlusion.hpp"
#include "shade/self_shadow.hpp"
#include "shade/shading_math.hpp"
#include "shade/traversal.hpp"

namespace qdmr {
namespace {

using namespace shading;
using simd::Int;
using simd::IntMask;
using simd::kLanes;
using simd::Mask;

using simd::count;
using simd::float_mask;
using simd::int_mask;


// Smallest depth step that moves the ray by one level-0 texel (the scale of refinement brackets).
Float texel_step(const DisplacementProgram::Ray& ray, float width, float height) {
  const Float reach = xsimd::max(xsimd::abs(ray.du) * Float(width), xsimd::abs(ray.dv) * Float(height));
  return Float(1.0f) / xsimd::max(reach, Float(1e-6f));
}

// The texel a ray at texel coordinate p is over: the one ahead along the ray (direction dir) when p lies on a
// texel boundary, so a step that ends on a wall moves on. Finite for any p (a NaN clamps to the bound).
Int texel_ahead(const Float& p, const Float& dir) {
  const Float c = xsimd::max(xsimd::min(p, Float(kMaxTexelCoordinate)), Float(-kMaxTexelCoordinate));
  return xsimd::to_int(xsimd::select(dir < Float(0.0f), Float(-1.0f) - xsimd::floor(Float(0.0f) - c), xsimd::floor(c)));
}

// Texel index i (|i| < 2^24) to [0, n) by the address mode, as HeightField::at: wrap, clamp, mirror (period 2n).
Int address_texel(const Int& i, int n, AddressMode mode) {
  const Int last(n - 1);
  if (mode == AddressMode::Clamp) return xsimd::min(xsimd::max(i, Int(0)), last);
  const int period = mode == AddressMode::Mirror ? 2 * n : n;
  // i and period are exact floats and the quotient is rounded to nearest, so its floor is floor(i / period) or
  // one more: r lands in [-period, period) and one correction puts it in [0, period).
  const Int q = xsimd::to_int(xsimd::floor(xsimd::to_float(i) / Float(float(period))));
  Int r = i - q * Int(period);
  r = xsimd::select(r < Int(0), r + Int(period), r);
  if (mode == AddressMode::Mirror) r = xsimd::select(r >= Int(n), Int(period - 1) - r, r);
  return xsimd::min(xsimd::max(r, Int(0)), last);
}

}  // namespace

DisplacementProgram::DisplacementProgram(const DisplacementInputs& inputs, const MaterialDesc& material,
                                         const LightRig& lights)
    : ShadingProgram(inputs.layers.size() > 1 && material.blend.weights.mode == WeightMode::Vertex
                         ? kWeight0 + int(inputs.layers.size())
                         : kBaseVaryingCount),
      cones_(inputs.cones), reference_(inputs.reference), reference_scale_(inputs.reference_scale), surface_(inputs.surface),
      sampler_(SamplerState::from(material.sampling)), lod_mode_(material.sampling.lod), math_(material.sampling.math),
      technique_(material.technique), lighting_(material.lighting), blend_(material.blend),
      shadow_(material.shadow), ao_(material.ao), lights_(lights) {
  if (inputs.layers.empty() || inputs.layers.size() > std::size_t(BlendedSurface::kMaxLayers))
    throw Error("displacement program", "needs 1 to 4 layers");
  for (std::size_t i = 0; i < inputs.layers.size(); ++i) {
    const LayerInputs& l = inputs.layers[i];
    Layer layer{TextureView(*l.albedo), TextureView(*l.normal), std::nullopt, std::nullopt, std::nullopt,
                i < material.layers.size() ? material.layers[i].specular : SpecularFromAlbedo{}};
    if (l.height) layer.height.emplace(*l.height);
    if (l.height_max) layer.height_max.emplace(*l.height_max);
    if (l.ao) layer.ao.emplace(*l.ao);
    layers_.push_back(std::move(layer));
  }
  if (inputs.blend_ao) {
    blend_ao_.emplace(*inputs.blend_ao);
    blend_ao_scale_ = inputs.blend_ao_scale;
  }
  if (ao_.mode == AoMode::Baked && !blend_ao_ &&
      std::any_of(layers_.begin(), layers_.end(), [](const Layer& l) { return !l.ao; }))
    throw Error("displacement program", "baked AO needs an AO map per layer or one of the blend");
  if (inputs.weights) weights_.emplace(*inputs.weights);
  if (inputs.combined) {
    combined_.emplace(*inputs.combined);
    combined_period_ = inputs.combined_period;
  }
  if (layers_.size() > 1 && blend_.weights.mode == WeightMode::Pixel && !weights_)
    throw Error("displacement program", "per-pixel blending needs a weight texture");
  const Texture* height0 = inputs.layers[0].height;
  if (cones_ && (!height0 || cones_->width != height0->width() || cones_->height != height0->height()))
    throw Error("cone map", "needs the height map it was baked from (same level-0 size)");
}

SingleLayerSurface DisplacementProgram::layer_surface(int i) const {
  const Layer& l = layers_[std::size_t(i)];
  return SingleLayerSurface(*l.height, l.height_max ? &*l.height_max : nullptr, sampler_, technique_.height_fetch);
}

// Relief mapping (Policarpo 2005): fixed linear steps from the top, then a binary search in the last step.
template <class Surface>
DisplacementProgram::Hit DisplacementProgram::relief(const Surface& surface, const Ray& ray, const Float& ds,
                                                    const Float& lod, Mask active) const {
  const int steps = technique_.linear_steps;
  const Float step = ds / Float(float(steps));
  Float lo(0.0f), hi = ds, iterations(0.0f);
  for (int i = 0; i <= steps && xsimd::any(active); ++i) {
    const Float s = step * Float(float(i));
    const Float h = surface.height(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod);
    const Mask found = active & (s >= ds * (Float(1.0f) - h));
    iterations += count(active);
    hi = xsimd::select(found, s, hi);
    lo = xsimd::select(found, xsimd::max(s - step, Float(0.0f)), lo);
    active = active & !found;
  }
  lo = xsimd::select(active, ds - step, lo);  // never below: the bottom (h >= 0 everywhere) is the hit
  Mask searching = lo < hi;
  for (int i = 0; i < technique_.binary_steps && xsimd::any(searching); ++i) {
    const Float mid = (lo + hi) * Float(0.5f);
    const Float h = surface.height(ray.u0 + ray.du * mid, ray.v0 + ray.dv * mid, lod);
    const Mask below = mid >= ds * (Float(1.0f) - h);
    iterations += count(searching);
    hi = xsimd::select(searching & below, mid, hi);
    lo = xsimd::select(searching & !below, mid, lo);
  }
  return {hi, iterations, Float(0.0f)};
}

// Parallax occlusion mapping (Tatarchuk 2006): step count lerped by the view angle, then the intersection of
// the ray with the line through the last two height samples.
template <class Surface>
DisplacementProgram::Hit DisplacementProgram::pom(const Surface& surface, const Ray& ray, const Float& ds,
                                                 const Float& lod, const Float& cos_view, Mask active) const {
  const Float lerp = xsimd::min(xsimd::max(cos_view, Float(0.0f)), Float(1.0f));
  const Float n = xsimd::floor(Float(float(technique_.max_steps)) +
                               (Float(float(technique_.min_steps)) - Float(float(technique_.max_steps))) * lerp +
                               Float(0.5f));
  const Float step = ds / n;
  Float prev_s(0.0f), prev_gap(0.0f), s_hit = ds, iterations(0.0f);
  // gap = surface depth - ray depth: > 0 while the ray is above the surface.
  {
    const Float gap0 = ds * (Float(1.0f) - surface.height(ray.u0, ray.v0, lod));
    iterations += count(active);
    const Mask at_top = active & (gap0 <= Float(0.0f));
    s_hit = xsimd::select(at_top, Float(0.0f), s_hit);
    active = active & !at_top;
    prev_gap = gap0;
  }
  for (int i = 1; i <= technique_.max_steps && xsimd::any(active); ++i) {
    const Float fi = Float(static_cast<float>(i));
    const Mask in_range = active & (fi <= n);
    const Float s = step * fi;
    const Float gap = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod)) - s;
    iterations += count(in_range);
    const Mask found = in_range & (gap <= Float(0.0f));
    const Float t = prev_gap / (prev_gap - gap);  // prev_gap > 0 >= gap: denominator > 0
    s_hit = xsimd::select(found, prev_s + (s - prev_s) * t, s_hit);
    active = in_range & !found;
    prev_s = s;
    prev_gap = gap;
  }
  return {s_hit, iterations, Float(0.0f)};
}

// Quadtree displacement mapping (Drobot 2009) over the max-quadtree: from the root, advance to the nearer of
// the cell's top plane and its wall while the ray is above the cell's highest point, descend otherwise; a
// level-0 cell the ray is at or below is the hit on the box surface. Cells are integer indices (SM4) stepped
// exactly across walls, or recomputed from the fp32 position (SM3 emulation).
template <class Surface>
DisplacementProgram::Hit DisplacementProgram::qdm(const Surface& surface, const Ray& ray, const Float& ds,
                                                 const Float& stop_level, const Int& cap, Mask active) const {
  const int top = surface.top_level();
  const float width = float(surface.width()), height = float(surface.height());
  const bool sm3 = math_ == MathMode::Sm3;
  const IntMask none = Int(0) != Int(0);
  const Float x0 = ray.u0 * Float(width), y0 = ray.v0 * Float(height);
  const Float dx = ray.du * Float(width), dy = ray.dv * Float(height);  // texels per unit of depth
  const IntMask step_x_pos = int_mask(dx > Float(0.0f)), step_y_pos = int_mask(dy > Float(0.0f));
  const Float inf(std::numeric_limits<float>::infinity());

  Int level(top);
  Int cx = xsimd::to_int(xsimd::floor(x0)) >> top, cy = xsimd::to_int(xsimd::floor(y0)) >> top;
  Float s(0.0f);
  const Int stop = xsimd::to_int(stop_level);
  CappedLoop loop{cap};
  while (loop.next(active)) {

    // The cell's highest point (wrap addressing: power-of-two level sizes), or LinearMipMapLinear at the ray's
    // position on this level, which smooths the maxima and so can miss features.
    const Float hmax = technique_.height_fetch != HeightFetch::Trilinear
                           ? surface.cell_max(level, cx, cy)
                           : surface.cell_max_filtered(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, xsimd::to_float(level));
    const Float top_depth = ds * (Float(1.0f) - hmax);
    const Mask below = active & (s >= top_depth);
    const IntMask at_stop = level <= stop;
    const Mask hit = below & float_mask(at_stop);
    active = active & !hit;
    // Below the cell's top but not at the last level: descend into the child that holds the ray.
    const IntMask descend = int_mask(below & !hit);
    if (xsimd::any(descend)) descend_to_child(descend, s, x0, y0, dx, dy, level, cx, cy);
    // Above the cell's top: advance to its top plane or its wall, whichever comes first.
    const Mask above = active & !below;
    if (!xsimd::any(above)) continue;
    const Float cell = xsimd::to_float(Int(1) << level);
    const Float wall_x = xsimd::to_float(xsimd::select(step_x_pos, cx + Int(1), cx)) * cell;
    const Float wall_y = xsimd::to_float(xsimd::select(step_y_pos, cy + Int(1), cy)) * cell;
    const Float tx = xsimd::select(dx != Float(0.0f), (wall_x - x0) / dx, inf);
    const Float ty = xsimd::select(dy != Float(0.0f), (wall_y - y0) / dy, inf);
    const Float t_wall = xsimd::max(xsimd::min(tx, ty), s);
    const Mask to_plane = above & (top_depth <= t_wall);
    s = xsimd::select(to_plane, top_depth, s);
    const Mask cross = above & !to_plane;
    s = xsimd::select(cross, t_wall, s);
    const IntMask cross_i = int_mask(cross);
    const IntMask cross_x = cross_i & int_mask(tx <= ty);
    const IntMask cross_y = cross_i & int_mask(ty <= tx);
    if (sm3) {
      // fp32 emulation: the cell is found again from the position, nudged 1/64 texel along the ray.
      const Float nudge = Float(1.0f / 64.0f);
      const Float px = x0 + dx * s + xsimd::select(dx > Float(0.0f), nudge, Float(0.0f) - nudge);
      const Float py = y0 + dy * s + xsimd::select(dy > Float(0.0f), nudge, Float(0.0f) - nudge);
      cx = xsimd::select(cross_x, xsimd::to_int(xsimd::floor(px / cell)), cx);
      cy = xsimd::select(cross_y, xsimd::to_int(xsimd::floor(py / cell)), cy);
    } else {
      cx = xsimd::select(cross_x, xsimd::select(step_x_pos, cx + Int(1), cx - Int(1)), cx);
      cy = xsimd::select(cross_y, xsimd::select(step_y_pos, cy + Int(1), cy - Int(1)), cy);
    }
    // After a crossing: stay, go up one level (the talk's fix for degeneration into linear search), or go up
    // while the wall just crossed is also a wall of the parent.
    IntMask up = cross_i & (level < Int(top));
    switch (technique_.level_up) {
      case QdmLevelUp::Stay: up = none; break;
      case QdmLevelUp::One: break;
      case QdmLevelUp::Aligned: {
        // Entering a cell through its low wall (+ direction) that wall is the parent's iff the index is even;
        // through its high wall (- direction) iff the index is odd.
        IntMask climbing = up;
        for (int k = 0; k < top && xsimd::any(climbing); ++k) {
          const IntMask odd_x = (cx & Int(1)) == Int(1), odd_y = (cy & Int(1)) == Int(1);
          const IntMask aligned_x = step_x_pos ^ odd_x, aligned_y = step_y_pos ^ odd_y;
          const IntMask ok = climbing & ((!cross_x) | aligned_x) & ((!cross_y) | aligned_y);
          level = xsimd::select(ok, level + Int(1), level);
          cx = xsimd::select(ok, cx >> 1, cx);
          cy = xsimd::select(ok, cy >> 1, cy);
          climbing = ok & (level < Int(top));
        }
        up = none;
        break;
      }
    }
    level = xsimd::select(up, level + Int(1), level);
    cx = xsimd::select(up, cx >> 1, cx);
    cy = xsimd::select(up, cy >> 1, cy);
  }
  return {xsimd::min(s, ds), loop.iterations(), Float(0.0f)};
}

void DisplacementProgram::cone_texel(const Int& x, const Int& y, Float& height, Float& ratio) const {
  const Int ax = address_texel(x, cones_->width, sampler_.address);
  const Int ay = address_texel(y, cones_->height, sampler_.address);
  Float texel[4];
  load(*layers_[0].height, Int(0), ax, ay, sampler_.fetch, texel);
  height = texel[0];
  ratio = simd::load_f32(cones_->ratio.data(), ay * Int(cones_->width) + ax, sampler_.fetch);
}

// Cone step mapping over the box surface (Dummer 2006; relaxed cones: Policarpo & Oliveira 2007). The ray reads
// the cone of the level-0 texel p it is over; the cone stands for S_p, the union of cones with apex anywhere on
// p's top face (cone_map.hpp), and the ray steps to where it leaves S_p. Along the ray S_p is: p's air column
// up to the first wall, then, outside one wall, distance (alpha (s - sa)) <= r (top - s) / depth_scale, then,
// outside both, the Euclidean distance to p's square; so the exit is p's top (a hit), a linear solve or a
// quadratic. With r = 0 the step still reaches p's wall (or top): the march never stalls on rough maps.
// Conservative cones never let a step pass through the surface: the first texel top the ray is at or below is
// the hit. Relaxed cones let a step enter the surface at most once and not leave it before the step's end: a
// step that ends below the surface brackets the first hit, found by binary search on the box surface.
DisplacementProgram::Hit DisplacementProgram::cone_step(const Ray& ray, const Float& ds, Mask active) const {
  const bool relaxed = technique_.kind == TechniqueKind::Rcsm;
  const float width = float(cones_->width), height = float(cones_->height);
  const Float zero(0.0f), inf(std::numeric_limits<float>::infinity());
  const Float x0 = ray.u0 * Float(width), y0 = ray.v0 * Float(height);
  const Float dx = ray.du * Float(width), dy = ray.dv * Float(height);  // texels per unit of depth
  const Float ax = xsimd::abs(ray.du) * ds, ay = xsimd::abs(ray.dv) * ds;  // UV per unit of height, as the ratios
  const IntMask step_x_pos = int_mask(dx > zero), step_y_pos = int_mask(dy > zero);
  const Int step_x = xsimd::select(step_x_pos, Int(1), Int(-1)), step_y = xsimd::select(step_y_pos, Int(1), Int(-1));

  Int cx = texel_ahead(x0, dx), cy = texel_ahead(y0, dy);
  Float s(0.0f), s_prev(0.0f);
  Mask search = zero != zero;  // rcsm: the last step entered the surface
  CappedLoop loop{Int(technique_.max_iterations)};
  while (loop.next(active)) {

    Float hp, r;
    cone_texel(cx, cy, hp, r);
    const Float top = ds * (Float(1.0f) - hp);
    // At or below the top of the texel the ray is over: the hit (conservative, and any ray starting on or in
    // the surface), or a relaxed step that went in.
    const Mask below = active & (s >= top);
    if (relaxed) search = search | (below & (s_prev < s));
    active = active & !below;

    // The walls of p ahead, each crossing computed from the integer wall as in QDM.
    const Float wall_x = xsimd::to_float(xsimd::select(step_x_pos, cx + Int(1), cx));
    const Float wall_y = xsimd::to_float(xsimd::select(step_y_pos, cy + Int(1), cy));
    const Float sx = xsimd::select(dx != zero, xsimd::max((wall_x - x0) / dx, s), inf);
    const Float sy = xsimd::select(dy != zero, xsimd::max((wall_y - y0) / dy, s), inf);
    const Mask x_first = sx <= sy;
    const Float alpha = xsimd::select(x_first, ax, ay), beta = xsimd::select(x_first, ay, ax);
    const Mask to_top = active & (top <= xsimd::min(sx, sy));
    // Finite stand-ins (a wall never crossed lies beyond the top): lanes going to the top ignore the rest.
    const Float sa = xsimd::min(xsimd::min(sx, sy), top), sb = xsimd::min(xsimd::max(sx, sy), top);
    // Outside the first wall only: alpha (s - sa) = r (top - s).
    const Float exit1 =
        xsimd::max((alpha * sa + r * top) / xsimd::max(alpha + r, Float(1e-30f)), sa);
    // Outside both: with tau = s - sb, delta = sb - sa, T = top - sb,
    //   alpha^2 (tau + delta)^2 + beta^2 tau^2 = r^2 (T - tau)^2,
    // a2 tau^2 + 2 b1 tau + c0 = 0 with c0 <= 0 (the ray is in S_p at sb): the root in [0, T] in the stable form.
    const Float delta = sb - sa, T = top - sb;
    const Float a2 = alpha * alpha + beta * beta - r * r;
    const Float b1 = alpha * alpha * delta + r * r * T;
    const Float c0 = (alpha * delta - r * T) * (alpha * delta + r * T);
    const Float disc = xsimd::max(b1 * b1 - a2 * c0, zero);
    const Float tau = xsimd::min(xsimd::max((zero - c0) / xsimd::max(b1 + xsimd::sqrt(disc), Float(1e-30f)), zero), T);
    const Float next = xsimd::select(to_top, top, xsimd::min(xsimd::select(exit1 <= sb, exit1, sb + tau), top));
    active = active & !to_top;  // on p's top while over p: the hit

    // The texel at the step's end: the one ahead of the position, at least one past each wall crossed.
    const Mask stepping = active;
    const Int ahead_x = texel_ahead(x0 + dx * next, dx), ahead_y = texel_ahead(y0 + dy * next, dy);
    const Int moved_x = xsimd::select(step_x_pos, xsimd::max(ahead_x, cx + step_x), xsimd::min(ahead_x, cx + step_x));
    const Int moved_y = xsimd::select(step_y_pos, xsimd::max(ahead_y, cy + step_y), xsimd::min(ahead_y, cy + step_y));
    cx = xsimd::select(int_mask(stepping & (next >= sx)), moved_x, cx);
    cy = xsimd::select(int_mask(stepping & (next >= sy)), moved_y, cy);
    s_prev = xsimd::select(stepping, s, s_prev);
    s = xsimd::select(stepping | to_top, next, s);
  }
  Float iterations = loop.iterations();
  if (relaxed) {
    // The first hit lies in (s_prev, s]: below the surface is false before it and true after it up to s.
    Float lo = s_prev, hi = s;
    for (int i = 0; i < technique_.binary_steps && xsimd::any(search); ++i) {
      const Float mid = (lo + hi) * Float(0.5f);
      Float h, unused;
      cone_texel(texel_ahead(x0 + dx * mid, zero), texel_ahead(y0 + dy * mid, zero), h, unused);
      const Mask below = mid >= ds * (Float(1.0f) - h);
      iterations += count(search);
      hi = xsimd::select(search & below, mid, hi);
      lo = xsimd::select(search & !below, mid, lo);
    }
    s = xsimd::select(search, hi, s);
  }
  return {xsimd::min(s, ds), iterations, Float(0.0f)};
}

// Between the last texel step before a box-surface hit and the hit, against the filtered (bilinear) surface.
template <class Surface>
Float DisplacementProgram::refine(const Surface& surface, const Ray& ray, const Float& ds, const Float& s_hit,
                                  Float& iterations, Mask active) const {
  if (technique_.refinement == QdmRefinement::None) return s_hit;
  const Float lod0(0.0f);
  const Float step = texel_step(ray, float(surface.width()), float(surface.height()));
  Float lo = xsimd::max(s_hit - step, Float(0.0f)), hi = s_hit;
  const Float gap_lo = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * lo, ray.v0 + ray.dv * lo, lod0)) - lo;
  const Float gap_hi = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * hi, ray.v0 + ray.dv * hi, lod0)) - hi;
  iterations += count(active) * Float(2.0f);
  if (technique_.refinement == QdmRefinement::Linear) {
    const Mask bracket = active & (gap_lo > Float(0.0f)) & (gap_hi <= Float(0.0f));
    const Float t = gap_lo / (gap_lo - gap_hi);
    return xsimd::select(bracket, lo + (hi - lo) * t, xsimd::select(gap_lo <= Float(0.0f), lo, hi));
  }
  if (technique_.refinement == QdmRefinement::BilinearPatch && surface_) return bilinear_patch(ray, ds, s_hit, iterations, active);
  // Binary (and the bilinear patch without its fp64 surface): bisection on the filtered surface.
  const int steps = technique_.refinement == QdmRefinement::Binary ? 8 : 24;
  Mask searching = active & (gap_lo > Float(0.0f));
  hi = xsimd::select(gap_lo > Float(0.0f), hi, lo);
  for (int i = 0; i < steps && xsimd::any(searching); ++i) {
    const Float mid = (lo + hi) * Float(0.5f);
    const Float gap = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * mid, ray.v0 + ray.dv * mid, lod0)) - mid;
    iterations += count(searching);
    const Mask below = gap <= Float(0.0f);
    hi = xsimd::select(searching & below, mid, hi);
    lo = xsimd::select(searching & !below, mid, lo);
  }
  return hi;
}

// The exact bilinear-patch hit: from the point where the ray reached the conservative bound, the patches are
// walked cell by cell and solved analytically in fp64 (the reference's traversal), per lane.
Float DisplacementProgram::bilinear_patch(const Ray& ray, const Float& ds, const Float& s_start, Float& iterations,
                                          Mask active) const {
  alignas(64) float u0[kLanes], v0[kLanes], du[kLanes], dv[kLanes], depth[kLanes], s[kLanes], cells[kLanes];
  ray.u0.store_aligned(u0);
  ray.v0.store_aligned(v0);
  ray.du.store_aligned(du);
  ray.dv.store_aligned(dv);
  ds.store_aligned(depth);
  s_start.store_aligned(s);
  const std::uint32_t lanes = simd::to_bits(active);
  for (int l = 0; l < kLanes; ++l) {
    cells[l] = 0.0f;
    if (!((lanes >> l) & 1u)) continue;
    const double start = s[l];
    const SurfaceRay r{{u0[l] + double(du[l]) * start, v0[l] + double(dv[l]) * start, start}, {du[l], dv[l], 1.0}};
    const ReferenceHit hit = intersect_reference(*surface_, depth[l], r, ReferenceSurface::Bilinear,
                                                 std::max(1, technique_.max_iterations));
    cells[l] = float(hit.cells_visited);
    if (hit.hit) s[l] = float(hit.point.z);
  }
  iterations += Float::load_aligned(cells);
  return Float::load_aligned(s);
}

// The hit in world space: the UV offset through dP/du and dP/dv (from the quad derivatives of the world
// position and the UVs), the depth along -n scaled by sqrt(|dP/du| |dP/dv|) world units per UV unit; then its
// window depth through the camera's view-projection.
void DisplacementProgram::displaced_depth(const Fragments& in, const UvDerivatives& d, const TangentFrame& frame,
                                          const Ray& ray, const Float& s, ShadeOutput& out) const {
  const Vec3 p{in.varyings[kWorldX], in.varyings[kWorldY], in.varyings[kWorldZ]};
  const Vec3 dpdx{simd::quad_ddx(p.x), simd::quad_ddx(p.y), simd::quad_ddx(p.z)};
  const Vec3 dpdy{simd::quad_ddy(p.x), simd::quad_ddy(p.y), simd::quad_ddy(p.z)};
  const Float det = d.dudx * d.dvdy - d.dudy * d.dvdx;
  const Mask usable = xsimd::abs(det) > Float(1e-30f);
  const Float inv = xsimd::select(usable, Float(1.0f) / det, Float(0.0f));
  const Vec3 dpdu = scale(add(scale(dpdx, d.dvdy), scale(dpdy, Float(0.0f) - d.dvdx)), inv);
  const Vec3 dpdv = scale(add(scale(dpdy, d.dudx), scale(dpdx, Float(0.0f) - d.dudy)), inv);
  const Float k = xsimd::sqrt(xsimd::sqrt(dot(dpdu, dpdu)) * xsimd::sqrt(dot(dpdv, dpdv)));
  const Vec3 hit = add(add(p, add(scale(dpdu, ray.du * s), scale(dpdv, ray.dv * s))), scale(frame.n, Float(0.0f) - s * k));
  const glm::mat4& m = lights_.view_projection;
  const auto row = [&](int r) {
    return Float(m[0][r]) * hit.x + Float(m[1][r]) * hit.y + Float(m[2][r]) * hit.z + Float(m[3][r]);
  };
  const Float clip_z = row(2), clip_w = row(3);
  out.depth = (clip_z / clip_w) * Float(0.5f) + Float(0.5f);
  out.view_depth = clip_w;
  out.writes_depth = true;
}

void DisplacementProgram::reference_errors(const Ray& ray, const Float& ds, const Hit& hit, const Mask& covered,
                                           ShadeOutput& out) const {
  alignas(64) float u0[kLanes], v0[kLanes], du[kLanes], dv[kLanes], depth[kLanes], s[kLanes], error[kLanes],
      missed[kLanes];
  ray.u0.store_aligned(u0);
  ray.v0.store_aligned(v0);
  ray.du.store_aligned(du);
  ray.dv.store_aligned(dv);
  ds.store_aligned(depth);
  hit.s.store_aligned(s);
  const std::uint32_t lanes = simd::to_bits(covered);
  // QDM and cone stepping without refinement see the box surface; everything else the filtered surface.
  const bool box = (technique_.kind == TechniqueKind::Qdm || technique_.kind == TechniqueKind::Csm ||
                    technique_.kind == TechniqueKind::Rcsm) &&
                   technique_.refinement == QdmRefinement::None;
  const ReferenceSurface surface = box ? ReferenceSurface::Box : ReferenceSurface::Bilinear;
  for (int l = 0; l < kLanes; ++l) {
    error[l] = missed[l] = 0.0f;
    if (!((lanes >> l) & 1u)) continue;
    // The reference may span several texture repeats (a blend's weights): its UV is the layers' / scale.
    const double k = 1.0 / reference_scale_;
    const SurfaceRay r{{u0[l] * k, v0[l] * k, 0.0}, {du[l] * k, dv[l] * k, 1.0}};
    const ReferenceHit ref = intersect_reference(*reference_, depth[l], r, surface, 1 << 16);
    if (!ref.hit) continue;
    const double eu = ((double(u0[l]) + double(du[l]) * s[l]) * k - ref.point.x) * reference_->width;
    const double ev = ((double(v0[l]) + double(dv[l]) * s[l]) * k - ref.point.y) * reference_->height;
    error[l] = float(std::sqrt(eu * eu + ev * ev));
    missed[l] = error[l] > 1.0f ? 1.0f : 0.0f;
  }
  out.error_texels = Float::load_aligned(error);
  out.missed = Float::load_aligned(missed);
}

struct DisplacementProgram::Setup {
  UvDerivatives d;
  TangentFrame frame;
  Vec3 view, view_tangent;
  Float ds;  // depth scale after the distance fade
  Ray ray;
  Mask active;  // the covered lanes (helper lanes are not traced)
  Float height_lod = Float(0.0f);  // mip LOD of the (first) height map: relief and POM steps, blend heights, soft shadows
};

template <class Surface>
DisplacementProgram::Hit DisplacementProgram::trace(const Surface& surface, const Setup& setup, Float& ds) const {
  const UvDerivatives& d = setup.d;
  const Ray& ray = setup.ray;
  const Mask active = setup.active;
  Hit hit{Float(0.0f), Float(0.0f), Float(0.0f)};
  switch (technique_.kind) {
    case TechniqueKind::Normal: break;
    case TechniqueKind::Relief:
      hit = relief(surface, ray, ds, setup.height_lod, active);
      hit.box_s = hit.s;
      break;
    case TechniqueKind::Pom: {
      const Float& lod = setup.height_lod;
      // Far away (high LOD) POM fades to normal mapping.
      const Float fade = xsimd::min(
          xsimd::max((lod - Float(technique_.lod_threshold)) / Float(std::max(technique_.lod_fade, 1e-6f)), Float(0.0f)),
          Float(1.0f));
      ds = ds * (Float(1.0f) - fade);
      hit = pom(surface, ray, ds, lod, setup.view_tangent.z, active);
      hit.box_s = hit.s;
      break;
    }
    case TechniqueKind::Csm:
    case TechniqueKind::Rcsm:
      hit = cone_step(ray, ds, active);
      hit.box_s = hit.s;
      hit.s = refine(surface, ray, ds, hit.s, hit.iterations, active);
      break;
    case TechniqueKind::Qdm: {
      Float stop(0.0f);
      if (technique_.lod_stop)
        stop = xsimd::max(xsimd::floor(lod_from_derivatives(*layers_[0].height_max, d.dudx, d.dvdx, d.dudy, d.dvdy)),
                          Float(0.0f));
      Int cap(technique_.max_iterations);
      if (technique_.min_iterations > 0) {
        const Float grazing = Float(1.0f) - xsimd::min(xsimd::max(setup.view_tangent.z, Float(0.0f)), Float(1.0f));
        cap = xsimd::to_int(Float(float(technique_.min_iterations)) +
                            Float(float(technique_.max_iterations - technique_.min_iterations)) * grazing);
      }
      hit = qdm(surface, ray, ds, stop, cap, active);
      hit.box_s = hit.s;
      hit.s = refine(surface, ray, ds, hit.s, hit.iterations, active);
      break;
    }
  }
  return hit;
}

namespace {

// Albedo and tangent-space normal (unnormalised) of one layer at the hit.
void layer_colour(const TextureView& albedo_view, const TextureView& normal_view, const SamplerState& sampler,
                  const UvDerivatives& d, const Float& u, const Float& v, Float* albedo, Float* normal) {
  sample(albedo_view, sampler, u, v, lod_from_derivatives(albedo_view, d.dudx, d.dvdx, d.dudy, d.dvdy), albedo);
  Float n[4];
  sample(normal_view, sampler, u, v, lod_from_derivatives(normal_view, d.dudx, d.dvdx, d.dudy, d.dvdy), n);
  for (int c = 0; c < 3; ++c) normal[c] = n[c] * Float(2.0f) - Float(1.0f);
}

// The colour blend factors of the layers at one point (they sum to 1 where any layer has weight):
//   alpha:        w_i / sum(w)
//   height:       the talk's operator, w_i h_i / sum(w h), with heights floored at 1/256 so that all-zero
//                 heights still blend by weight instead of dividing by the talk's epsilon
//   height_width: the widely used transition-width form: b_i = max(h_i + w_i - (max_j(h_j + w_j) - width), 0)
//                 over layers with weight, normalised
void blend_factors(BlendOperator op, float width, int count, const Float* h, const Float* w, Float* f) {
  const Float zero(0.0f);
  Float sum(0.0f);
  if (op == BlendOperator::Alpha) {
    for (int i = 0; i < count; ++i) f[i] = w[i];
  } else if (op == BlendOperator::Height) {
    for (int i = 0; i < count; ++i) f[i] = w[i] * xsimd::max(h[i], Float(1.0f / 256.0f));
  } else {
    Float top(-1.0f);
    for (int i = 0; i < count; ++i) top = xsimd::max(top, xsimd::select(w[i] > zero, h[i] + w[i], Float(-1.0f)));
    const Float floor_level = top - Float(width);
    for (int i = 0; i < count; ++i) f[i] = xsimd::select(w[i] > zero, xsimd::max(h[i] + w[i] - floor_level, zero), zero);
  }
  for (int i = 0; i < count; ++i) sum += f[i];
  const Float inv = xsimd::select(sum > zero, Float(1.0f) / sum, zero);
  for (int i = 0; i < count; ++i) f[i] = f[i] * inv;
}

}  // namespace

template <class Surface>
void DisplacementProgram::shade_surface(const Fragments& in, const Setup& setup, const Surface& surface,
                                        ShadeOutput& out) const {
  const UvDerivatives& d = setup.d;
  const Ray& ray = setup.ray;
  Float ds = setup.ds;
  const Hit hit = trace(surface, setup, ds);

  const Float hu = ray.u0 + ray.du * hit.s, hv = ray.v0 + ray.dv * hit.s;
  // Baked AO is read per layer and blended like the colours.
  SamplerState ao_sampler = sampler_;
  ao_sampler.filter = Filter::Bilinear;
  const auto baked_ao = [&](const Layer& l) {
    Float a[4];
    sample(*l.ao, ao_sampler, hu, hv, Float(0.0f), a);
    return a[0];
  };
  Float albedo[4], tangent_normal[3], specular(0.0f), ao(1.0f);
  if constexpr (std::is_same_v<Surface, SingleLayerSurface>) {
    const Layer& l = layers_[0];
    layer_colour(l.albedo, l.normal, sampler_, d, hu, hv, albedo, tangent_normal);
    specular = specular_from_albedo(albedo, l.specular, lighting_.specular);
    if (l.ao) ao = baked_ao(l);
  } else {
    const int count = surface.layer_count();
    Float h[BlendedSurface::kMaxLayers], w[BlendedSurface::kMaxLayers], f[BlendedSurface::kMaxLayers];
    if (blend_.op != BlendOperator::Alpha) {
      for (int i = 0; i < count; ++i) h[i] = surface.layer(i).height(hu, hv, setup.height_lod);
    }
    surface.weights_at(hu, hv, w);
    blend_factors(blend_.op, blend_.width, count, h, w, f);
    for (int c = 0; c < 4; ++c) albedo[c] = Float(0.0f);
    for (int c = 0; c < 3; ++c) tangent_normal[c] = Float(0.0f);
    if (blend_ao_) {
      const Float inv(1.0f / float(blend_ao_scale_));
      Float a[4];
      sample(*blend_ao_, ao_sampler, hu * inv, hv * inv, Float(0.0f), a);
      ao = a[0];
    } else if (ao_.mode == AoMode::Baked) {
      ao = Float(0.0f);
    }
    for (int i = 0; i < count; ++i) {
      if (!xsimd::any(f[i] > Float(0.0f))) continue;  // a layer absent from the whole batch costs no fetch
      const Layer& l = layers_[std::size_t(i)];
      Float a[4], n[3];
      layer_colour(l.albedo, l.normal, sampler_, d, hu, hv, a, n);
      for (int c = 0; c < 4; ++c) albedo[c] += f[i] * a[c];
      for (int c = 0; c < 3; ++c) tangent_normal[c] += f[i] * n[c];
      specular += f[i] * specular_from_albedo(a, l.specular, lighting_.specular);
      if (l.ao) ao += f[i] * baked_ao(l);
    }
  }
  const TangentFrame& frame = setup.frame;
  const Vec3 shading_normal = normalize(frame.to_world({tangent_normal[0], tangent_normal[1], tangent_normal[2]}));
  light(in, setup, surface, hit, ds, albedo, specular, ao, shading_normal, out);
  out.normal[0] = shading_normal.x;
  out.normal[1] = shading_normal.y;
  out.normal[2] = shading_normal.z;
  out.iterations = hit.iterations;
  out.hit_u = hu;
  out.hit_v = hv;
  out.hit_depth = hit.s;
  out.error_texels = out.missed = Float(0.0f);
  if (reference_ && technique_.kind != TechniqueKind::Normal) reference_errors(ray, ds, hit, in.covered, out);
  if (technique_.write_depth) displaced_depth(in, d, frame, ray, hit.s, out);
}

// Self-shadowing per light and ambient occlusion at the hit, then the lighting model.
template <class Surface>
void DisplacementProgram::light(const Fragments& in, const Setup& setup, const Surface& surface, const Hit& hit,
                                const Float& ds, const Float* albedo, const Float& specular, const Float& baked_ao,
                                const Vec3& shading_normal, ShadeOutput& out) const {
  const Ray& ray = setup.ray;
  // Hard shadows trace the box surface, so they start from the hit on it: a refined hit between texel centres
  // can lie below a neighbouring column's top and would be shadowed by it (staircase acne).
  // The bias lifts the start along the light ray (towards depth 0) by a fraction of the depth scale.
  const Float s_hit = shadow_.mode == ShadowMode::Hard ? hit.box_s : hit.s;
  const Float lift = xsimd::min(Float(shadow_.bias) * ds, s_hit);
  const Float su_hit = ray.u0 + ray.du * s_hit, sv_hit = ray.v0 + ray.dv * s_hit;
  const Float hu = ray.u0 + ray.du * hit.s, hv = ray.v0 + ray.dv * hit.s;
  const Float zero(0.0f);
  Float visibility[limits::kMaxDirectionalLights];
  const bool shadows = shadow_.mode != ShadowMode::Off;
  if (shadows) {
    for (std::size_t j = 0; j < lights_.directional.size(); ++j) {
      const glm::vec3& l = lights_.directional[j].direction;
      const Vec3 lt = setup.frame.to_tangent({Float(l.x), Float(l.y), Float(l.z)});
      const Mask above = lt.z > zero;  // a light below the polygon leaves the whole relief in shadow
      const Float lz = xsimd::max(lt.z, Float(1e-6f));
      const Float du = lt.x / lz, dv = lt.y / lz;
      const Float su = su_hit + du * lift, sv = sv_hit + dv * lift, s0 = s_hit - lift;
      const Float u1 = su + du * s0, v1 = sv + dv * s0;
      const Surface towards_light =
          surface.around(xsimd::min(su, u1), xsimd::max(su, u1), xsimd::min(sv, v1), xsimd::max(sv, v1));
      const ShadowResult r =
          self_shadow(towards_light, shadow_, ShadowRay{su, sv, s0, du, dv, ds}, setup.height_lod, setup.active & above);
      visibility[j] = xsimd::select(above, r.visibility, zero);
    }
  }
  Float ao = baked_ao;
  if (ao_.mode == AoMode::Frame) {
    const Float radius(ao_.radius);
    ao = ambient_occlusion(surface.around(hu - radius, hu + radius, hv - radius, hv + radius), ao_, hu, hv, hit.s, ds,
                           in.pixel_x, in.pixel_y, setup.active);
  }
  if (ao_.mode != AoMode::Off) ao = apply_ao_strength(ao, ao_.strength);
  // The lighting AOVs: what the lighting model multiplies by, for the first directional light.
  out.shadow = shadows && !lights_.directional.empty() ? visibility[0] : Float(1.0f);
  out.ao = ao;
  shade_lights(shading_normal, setup.frame.n, setup.view, SurfaceSample{albedo, specular, ao},
               shadows ? visibility : nullptr, lighting_, lights_, out.color);
}

void DisplacementProgram::shade(const Fragments& in, ShadeOutput& out) const {

  const Float& u = in.varyings[kU];
  const Float& v = in.varyings[kV];
  Setup setup;
  setup.d = UvDerivatives::from(u, v, lod_mode_);
  setup.frame = TangentFrame::from(in);
  setup.view = view_vector(in, lights_);
  setup.view_tangent = setup.frame.to_tangent(setup.view);

  // Depth scale, faded with camera distance when asked; the ray leaves the polygon along -view.
  setup.ds = Float(technique_.depth_scale);
  if (technique_.fade_end > 0.0f) {
    const Float range(std::max(technique_.fade_end - technique_.fade_start, 1e-6f));
    const Float fade = xsimd::min(xsimd::max((in.view_depth - Float(technique_.fade_start)) / range, Float(0.0f)), Float(1.0f));
    setup.ds = setup.ds * (Float(1.0f) - fade);
  }
  const Float vz = xsimd::max(setup.view_tangent.z, Float(1e-4f));  // grazing and back-facing views: nearly parallel rays
  setup.ray = Ray{u, v, (Float(0.0f) - setup.view_tangent.x) / vz, (Float(0.0f) - setup.view_tangent.y) / vz};
  setup.active = in.covered;
  if (layers_[0].height)
    setup.height_lod = lod_from_derivatives(*layers_[0].height, setup.d.dudx, setup.d.dvdx, setup.d.dudy, setup.d.dvdy);

  const int count = int(layers_.size());
  if (count == 1) {
    shade_surface(in, setup, layer_surface(0), out);
    return;
  }
  const SingleLayerSurface surfaces[BlendedSurface::kMaxLayers] = {
      layer_surface(0), layer_surface(1), layer_surface(std::min(2, count - 1)), layer_surface(std::min(3, count - 1))};
  if (blend_.weights.mode == WeightMode::Vertex) {
    const Float w[BlendedSurface::kMaxLayers] = {in.varyings[kWeight0], in.varyings[kWeight1],
                                                 count > 2 ? in.varyings[kWeight2] : Float(0.0f),
                                                 count > 3 ? in.varyings[kWeight3] : Float(0.0f)};
    shade_surface(in, setup, BlendedSurface(surfaces, count, blend_.op, w), out);
    return;
  }
  // Per-pixel weights: bounded over the UV box the view ray crosses down to depth_scale.
  const Ray& ray = setup.ray;
  const Float u1 = ray.u0 + ray.du * setup.ds, v1 = ray.v0 + ray.dv * setup.ds;
  const WeightTexture weights{&*weights_, blend_.weights.scale, combined_ ? &*combined_ : nullptr, combined_period_};
  const BlendedSurface surface(surfaces, count, blend_.op, weights,
                               xsimd::min(ray.u0, u1), xsimd::max(ray.u0, u1), xsimd::min(ray.v0, v1),
                               xsimd::max(ray.v0, v1));
  shade_surface(in, setup, surface, out);
}

}  // namespace qdmr
