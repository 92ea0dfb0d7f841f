#pragma once
// The exact reference: the first intersection of a ray with a heightfield surface, in fp64, by grid
// traversal with an analytic solve per cell. It is the ground truth every technique is measured against.
#include "qdmr/texture/heightfield.hpp"

namespace qdmr {

// The smallest t >= 0 with ray depth >= surface_depth(field, depth_scale, u(t), v(t), surface) (see
// heightfield.hpp): Box columns are closed, so grazing a column's edge or corner is a hit. Cells are visited in
// ray order (Amanatides-Woo, each boundary crossing computed from its integer index, never accumulated) and
// solved in closed form: a linear equation per texel for Box, a quadratic per centre-to-centre cell for
// Bilinear.
// hit = false when the ray can no longer meet the surface — it rises above depth 0 (heights are assumed in
// [0, 1], so nothing lies above the polygon), it is vertical and does not go down, or it has no more cells —
// or when max_cells cells were solved without a hit (rays parallel to the polygon never reach the bottom).
// A ray going down always hits by depth_scale, the depth of height 0, whatever the address mode.
// depth_scale 0 makes the surface the polygon. Requires width, height >= 1, h.size() == width * height and
// |u| * width, |v| * height < 2^52 along the ray.
ReferenceHit intersect_reference(const HeightField& field, double depth_scale, const SurfaceRay& ray,
                                 ReferenceSurface surface, std::int64_t max_cells = 1 << 22);

// Whether a point on the Box surface sees a directional light: the hard self-shadow (kernel/self_shadow.hpp
// implements the same rule in fp32). The light ray climbs from start = (u, v, depth): after climbing c it is
// at (u + climb.x c, v + climb.y c, depth - c), climb being the UV change per unit of depth climbed
// (light_tangent.xy / light_tangent.z). Each level-0 texel is a column below its top depth
// depth_scale * (1 - h) (address mode applied); the ray is shadowed iff it passes through the interior of a
// column other than the start texel T0: it enters a texel (its open square) strictly below that texel's top.
// Grazing a top face, an edge or a corner, or running along a wall, is lit; at depth <= 0 nothing occludes.
// T0 holds (u, v); on a texel boundary it is the texel behind along the light direction (a start on a wall
// is shadowed by the column beyond the wall when the light lies beyond it; the start's own column never
// shadows it). Texels are walked in ray order with each crossing computed from its integer boundary, as
// intersect_reference does.
struct LightVisibility {
  bool visible = true;
  bool capped = false;             // max_cells texels were tested without an answer (visible stays true)
  std::int64_t blocker_i = 0, blocker_j = 0;  // the shadowing texel (address mode not applied)
  double blocker_climb = 0;        // c where the ray enters it
  std::int64_t cells_visited = 0;  // texels tested, T0 excluded
};

LightVisibility light_visibility(const HeightField& field, double depth_scale, const glm::dvec3& start,
                                 const glm::dvec2& climb, std::int64_t max_cells = 1 << 22);

}  // namespace qdmr
