#pragma once
// The exact reference: the first intersection of a ray with a heightfield surface, in fp64, by grid
// traversal with an analytic solve per cell. It is the ground truth every technique is measured against.
#include "qdmr/study/heightfield.hpp"

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

}  // namespace qdmr
