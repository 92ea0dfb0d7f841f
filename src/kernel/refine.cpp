#include "kernel/refine.hpp"

#include <algorithm>

#include "qdmr/reference/reference.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// The exact bilinear-patch hit: from the point where the ray reached the conservative bound, the patches are
// walked cell by cell and solved analytically in fp64 (the reference's traversal), per lane.
Float bilinear_patch(const Ray& ray, const Float& ds, const Float& s_start, Float& iterations, Mask active,
                     const HeightField& surface, int max_iterations) {
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
    const ReferenceHit hit = intersect_reference(surface, depth[l], r, ReferenceSurface::Bilinear,
                                                 std::max(1, max_iterations));
    cells[l] = float(hit.cells_visited);
    if (hit.hit) s[l] = float(hit.point.z);
  }
  iterations += Float::load_aligned(cells);
  return Float::load_aligned(s);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
