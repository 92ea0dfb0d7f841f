#include "kernel/self_shadow.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>

#include "kernel/blended_surface.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/traversal.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using simd::Float;
using simd::Int;
using simd::IntMask;
using simd::Mask;

using simd::count;
using simd::float_mask;
using simd::int_mask;


Mask finite(const Float& x) { return xsimd::abs(x) <= Float(std::numeric_limits<float>::max()); }

// The ray with its guards applied; lanes that are not active carry harmless values.
struct Prepared {
  Float u, v, s, du, dv, ds;
  Mask active;
};

Prepared prepare(const ShadowRay& ray, Mask active) {
  const Float zero(0.0f);
  active = active & finite(ray.u) & finite(ray.v) & finite(ray.s) & finite(ray.du) & finite(ray.dv) &
           finite(ray.ds) & (ray.ds > zero);
  Prepared p;
  p.active = active;
  p.u = xsimd::select(active, ray.u, zero);
  p.v = xsimd::select(active, ray.v, zero);
  p.ds = xsimd::select(active, ray.ds, Float(1.0f));
  p.s = xsimd::min(xsimd::max(xsimd::select(active, ray.s, zero), zero), p.ds);
  Float du = xsimd::select(active, ray.du, zero), dv = xsimd::select(active, ray.dv, zero);
  // Longer than kMaxLightSlope: scaled down, the direction taken from (du, dv) / max(|du|, |dv|) so that no
  // square overflows.
  const Float m = xsimd::max(xsimd::abs(du), xsimd::abs(dv));
  const Float limit(kMaxLightSlope);
  const Mask big = (m > limit) | (du * du + dv * dv > limit * limit);
  const Float nu = du / xsimd::max(m, Float(1.0f)), nv = dv / xsimd::max(m, Float(1.0f));
  const Float k = limit / xsimd::sqrt(xsimd::max(nu * nu + nv * nv, Float(1.0f)));
  p.du = xsimd::select(big, nu * k, du);
  p.dv = xsimd::select(big, nv * k, dv);
  return p;
}

// Hard: the first texel after the start texel that the rising ray enters below its top (see the header).
// The traversals work in the texel space of the repeat holding the start (exact and small numbers); cells are
// addressed in absolute indices, since a blended surface's weights do not repeat with the layers' heights.
struct RepeatOrigin {
  Int base_x, base_y;  // first texel of the start's repeat
  RepeatOrigin(const Prepared& p, int width, int height) {
    const Float limit(float((1 << 30) / std::max(width, height)));
    base_x = xsimd::to_int(xsimd::max(xsimd::min(xsimd::floor(p.u), limit), Float(0.0f) - limit)) * Int(width);
    base_y = xsimd::to_int(xsimd::max(xsimd::min(xsimd::floor(p.v), limit), Float(0.0f) - limit)) * Int(height);
  }
  // Cell c of `level` in the start's repeat (sizes are powers of two: the repeat's first cell is base >> level).
  Int x(const Int& level, const Int& c) const { return (base_x >> level) + c; }
  Int y(const Int& level, const Int& c) const { return (base_y >> level) + c; }
};

template <class Surface>
ShadowResult hard(const Surface& surface, const ShadowParams& desc, const Prepared& p) {
  const int top = surface.top_level();
  const Float zero(0.0f), inf(std::numeric_limits<float>::infinity());
  const Float width(float(surface.width())), height(float(surface.height()));
  // Texel space, the start wrapped into the first repeat (exact: u - floor(u) loses no bits, sizes are
  // powers of two in the quadtree and scale exactly).
  const Float x0 = (p.u - xsimd::floor(p.u)) * width, y0 = (p.v - xsimd::floor(p.v)) * height;
  const RepeatOrigin origin(p, surface.width(), surface.height());
  const Float dx = p.du * width, dy = p.dv * height;  // texels per unit of depth climbed
  const GridRay ray(x0, y0, dx, dy);

  // Along a wall the ray is never inside a column.
  const Mask along_wall = ((dx == zero) & (x0 == xsimd::floor(x0))) | ((dy == zero) & (y0 == xsimd::floor(y0)));
  // The start texel T0 (on a boundary the one behind along the light) and where the ray leaves it; each wall
  // crossing is computed from its integer wall, (wall - x0) * inv_dx (crossing()), at every level alike.
  const Int t0x = xsimd::to_int(xsimd::select(dx > zero, xsimd::ceil(x0) - Float(1.0f), xsimd::floor(x0)));
  const Int t0y = xsimd::to_int(xsimd::select(dy > zero, xsimd::ceil(y0) - Float(1.0f), xsimd::floor(y0)));
  const Float wall_x0 = xsimd::to_float(t0x + ray.exit_x);
  const Float wall_y0 = xsimd::to_float(t0y + ray.exit_y);
  const Float tx0 = xsimd::select(dx != zero, crossing<false>(wall_x0, x0, dx, ray.inv_dx), inf);
  const Float ty0 = xsimd::select(dy != zero, crossing<false>(wall_y0, y0, dy, ray.inv_dy), inf);
  Float c = xsimd::min(tx0, ty0);
  const IntMask first_x = int_mask(tx0 <= ty0), first_y = int_mask(ty0 <= tx0);
  Int level(0);
  Int cx = xsimd::select(first_x, t0x + ray.step_x, t0x), cy = xsimd::select(first_y, t0y + ray.step_y, t0y);
  climb_aligned(level, cx, cy, int_mask(p.active), first_x, first_y, ray.pos_x, ray.pos_y, top);

  // Where the ray is above every column: the depth of the highest texel when the top level covers the map
  // (one fetch per batch, not counted: a per-material constant), else the polygon.
  Float floor_depth = zero;
  if ((1 << top) >= std::max(surface.width(), surface.height()))
    floor_depth = p.ds * (Float(1.0f) - surface.max_height());

  Mask active = p.active & ~along_wall & ~(p.s - c <= floor_depth);
  Mask occluded = zero != zero;
  CappedLoop loop(Int(desc.max_iterations), FetchPhase::Shadow);
  while (loop.next(active)) {
    const Float hmax = surface.cell_max(level, origin.x(level, cx), origin.y(level, cy), active);
    const Float top_depth = p.ds * (Float(1.0f) - hmax);
    // A rising ray is lowest where it enters the cell, at c.
    const Mask below = active & (p.s - c > top_depth);
    const Mask hit = below & float_mask(level == Int(0));
    occluded = occluded | hit;
    active = active & ~hit;
    // Below the cell's maximum above level 0: descend into the child that holds the ray at c (QDM's rule).
    const IntMask descend = int_mask(below & ~hit);
    if (xsimd::any(descend)) descend_to_child(descend, c, ray, level, cx, cy);
    // At or above the cell's maximum where it enters: above it all the way through; on to the next cell.
    const Mask advance = active & ~below;
    if (!xsimd::any(advance)) continue;
    Float tx, ty;
    exit_walls(level, cx, cy, ray, tx, ty);
    c = xsimd::select(advance, xsimd::max(xsimd::min(tx, ty), c), c);
    const IntMask moving = int_mask(advance);
    const IntMask cross_x = moving & int_mask(tx <= ty), cross_y = moving & int_mask(ty <= tx);
    cx = xsimd::select(cross_x, cx + ray.step_x, cx);
    cy = xsimd::select(cross_y, cy + ray.step_y, cy);
    climb_aligned(level, cx, cy, moving, cross_x, cross_y, ray.pos_x, ray.pos_y, top);
    active = active & ~(advance & (p.s - c <= floor_depth));
  }
  return {xsimd::select(occluded, zero, Float(1.0f)), loop.iterations()};
}

// The profile operator over the occlusion of the samples taken, and the strength rule.
class Profile {
public:
  explicit Profile(ProfileOperator op) : op_(op) {}

  void add(const Mask& taken, const Float& occlusion) {
    switch (op_) {
      case ProfileOperator::Max: acc_ = xsimd::select(taken, xsimd::max(acc_, occlusion), acc_); break;
      case ProfileOperator::Min:
        acc_ = xsimd::select(taken, xsimd::select(n_ > Float(0.0f), xsimd::min(acc_, occlusion), occlusion), acc_);
        break;
      case ProfileOperator::Average: acc_ = xsimd::select(taken, acc_ + occlusion, acc_); break;
    }
    n_ += count(taken);
  }
  const Float& taken() const { return n_; }

  // 1 - saturate(strength * combined); no sample taken: lit.
  Float visibility(float strength) const {
    const Float combined = op_ == ProfileOperator::Average ? acc_ / xsimd::max(n_, Float(1.0f)) : acc_;
    return Float(1.0f) - xsimd::min(xsimd::max(Float(strength) * combined, Float(0.0f)), Float(1.0f));
  }

private:
  ProfileOperator op_;
  Float acc_ = Float(0.0f), n_ = Float(0.0f);
};

// How far the surface at depth surface_depth rises above the light ray at climb c, in depth-scale units and
// clamped at 0, softened by the distance: max(0, ray depth - surface depth) / ds / (1 + penumbra c / ds).
Float occlusion(const Prepared& p, const Float& c, const Float& surface_depth, float penumbra) {
  const Float gap = xsimd::max((p.s - c) - surface_depth, Float(0.0f));
  return gap / p.ds / (Float(1.0f) + Float(penumbra) * (c / p.ds));
}

// The longest climb sampled: to the polygon, or `length` UV units of horizontal reach when length > 0.
Float shadow_reach(const ShadowParams& desc, const Prepared& p) {
  if (desc.length <= 0.0f) return p.s;
  const Float slope = xsimd::sqrt(p.du * p.du + p.dv * p.dv);  // 0 (light overhead): length / 0 = inf
  return xsimd::min(p.s, Float(desc.length) / slope);
}

template <class Surface>
ShadowResult horizon(const Surface& surface, const ShadowParams& desc, const Prepared& p, const Float& lod) {
  const Float c_max = shadow_reach(desc, p);
  const Mask taken = p.active & (c_max > Float(0.0f));
  Profile profile(desc.profile);
  const int n = std::max(desc.samples, 1);
  FetchLanes lanes(FetchPhase::Shadow);
  lanes.narrow(taken);
  for (int k = 1; k <= n && xsimd::any(taken); ++k) {
    const Float c = c_max * Float(float(k) / float(n));
    const Float h = surface.height(p.u + p.du * c, p.v + p.dv * c, lod);
    profile.add(taken, occlusion(p, c, p.ds * (Float(1.0f) - h), desc.penumbra));
  }
  return {profile.visibility(desc.strength), profile.taken()};
}

template <class Surface>
ShadowResult qdm_soft(const Surface& surface, const ShadowParams& desc, const Prepared& p) {
  const Float zero(0.0f);
  const Float width(float(surface.width())), height(float(surface.height()));
  const Float x0 = (p.u - xsimd::floor(p.u)) * width, y0 = (p.v - xsimd::floor(p.v)) * height;
  const RepeatOrigin origin(p, surface.width(), surface.height());
  const Float dx = p.du * width, dy = p.dv * height;
  const Float texels_per_climb = xsimd::sqrt(dx * dx + dy * dy);  // 0 (light overhead): every tap at c = inf
  const Float c_max = shadow_reach(desc, p);
  const int taps = std::min(int(desc.tap_weights.size()), surface.top_level() + 1);
  const Float bound(kMaxTexelCoordinate);
  Profile profile(desc.profile);
  FetchLanes lanes(FetchPhase::Shadow);
  for (int k = 0; k < taps; ++k) {
    const Float c = Float(float(1 << k)) / texels_per_climb;
    const Mask taken = p.active & (c <= c_max);
    if (!xsimd::any(taken)) break;  // c grows with k: no later tap is taken either
    lanes.narrow(taken);
    const Float px = xsimd::min(xsimd::max(xsimd::select(taken, x0 + dx * c, zero), Float(0.0f) - bound), bound);
    const Float py = xsimd::min(xsimd::max(xsimd::select(taken, y0 + dy * c, zero), Float(0.0f) - bound), bound);
    const Int level(k);
    const Float hmax = surface.cell_max(level, origin.x(level, xsimd::to_int(xsimd::floor(px)) >> k),
                                        origin.y(level, xsimd::to_int(xsimd::floor(py)) >> k));
    const Float occ = occlusion(p, c, p.ds * (Float(1.0f) - hmax), desc.penumbra);
    profile.add(taken, Float(desc.tap_weights[std::size_t(k)]) * occ);
  }
  return {profile.visibility(desc.strength), profile.taken()};
}

}  // namespace

template <class Surface>
ShadowResult self_shadow(const Surface& surface, ShadowMode mode, const ShadowParams& desc, const ShadowRay& ray,
                         const Float& lod, Mask active) {
  ShadowResult r{Float(1.0f), Float(0.0f)};
  if (mode == ShadowMode::Off) return r;
  const Prepared p = prepare(ray, active);
  if (!xsimd::any(p.active)) return r;
  FetchLanes lanes(FetchPhase::Shadow);
  lanes.narrow(p.active);
  switch (mode) {
    case ShadowMode::Off: break;
    case ShadowMode::Hard: r = hard(surface, desc, p); break;
    case ShadowMode::Horizon: r = horizon(surface, desc, p, lod); break;
    case ShadowMode::QdmSoft: r = qdm_soft(surface, desc, p); break;
  }
  return {xsimd::select(p.active, r.visibility, Float(1.0f)), xsimd::select(p.active, r.iterations, Float(0.0f))};
}

template ShadowResult self_shadow<SingleLayerSurface>(const SingleLayerSurface&, ShadowMode, const ShadowParams&, const ShadowRay&,
                                                      const Float&, Mask);
template ShadowResult self_shadow<BlendedSurface>(const BlendedSurface&, ShadowMode, const ShadowParams&, const ShadowRay&,
                                                 const simd::Float&, simd::Mask);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
