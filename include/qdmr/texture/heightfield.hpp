#pragma once
// The displaced surface as the techniques and the exact reference see it, in tangent/UV space:
// u, v in texture repeats; depth measured down from the polygon (depth 0) to depth_scale; a texel of height
// h in [0,1] lies at depth depth_scale * (1 - h). Level-0 texel (i, j) covers [i/W, (i+1)/W) x [j/H, (j+1)/H)
// and its centre is ((i + 0.5)/W, (j + 0.5)/H).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "qdmr/core/sampling.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

struct HeightField {
  int width = 0, height = 0;
  ZeroedBuffer<double> h;                  // row-major, row 0 at v = 0; values in [0, 1]; zero pages until written
  AddressMode address = AddressMode::Wrap;  // wrap repeats the map; clamp extends the edge texels; mirror reflects

  // Texel (i, j) with the address mode applied: wrap i mod W; clamp to [0, W); mirror with period 2W
  // (i = -1 reads texel 0, i = W reads texel W - 1). Any int64 index is valid. Inline: the bakes and the exact
  // reference read millions of texels.
  double at(std::int64_t i, std::int64_t j) const {
    return h[std::size_t(texel_index(j, height, address) * width + texel_index(i, width, address))];
  }

  // Index i of a row or column of n texels under the address mode, in [0, n): at's rule, for the bakes too.
  static std::int64_t texel_index(std::int64_t i, std::int64_t n, AddressMode mode) {
    if (i >= 0 && i < n) return i;  // every mode: inside
    switch (mode) {
      case AddressMode::Wrap: {
        const std::int64_t m = i % n;
        return m < 0 ? m + n : m;
      }
      case AddressMode::Clamp: return std::clamp<std::int64_t>(i, 0, n - 1);
      case AddressMode::Mirror: {
        std::int64_t m = i % (2 * n);
        if (m < 0) m += 2 * n;
        return m < n ? m : 2 * n - 1 - m;
      }
    }
    return 0;
  }
};

// A ray in UV/depth space: p(t) = origin + t * direction, t >= 0. Rays of interest enter at depth 0 and go
// down (direction.z > 0); direction.z == 0 is a ray parallel to the polygon.
struct SurfaceRay {
  glm::dvec3 origin;     // (u, v, depth)
  glm::dvec3 direction;  // (du, dv, ddepth)
};

enum class ReferenceSurface {
  Box,      // each level-0 texel a flat cell at its depth (what point sampling sees)
  Bilinear  // the bilinear patch through the texel centres (what bilinear filtering sees)
};

// Depth of the surface at (u, v), what a ray must reach there to hit it:
// - Box: the depth of texel (floor(u W), floor(v H)). The columns are closed boxes, so on a texel edge or corner
//   the highest (least deep) of the texels touching it counts; the exact reference uses the same rule.
// - Bilinear: the bilinear interpolation of the four texel centres around (u, v).
double surface_depth(const HeightField& field, double depth_scale, double u, double v, ReferenceSurface surface);

// surface_depth(field, depth_scale, u, v, ReferenceSurface::Bilinear), inline for the bakes' inner loops; for any
// field with HeightField's width, height and at() (the AO bake's views of float heights too: the same operations).
template <class Field>
double bilinear_surface_depth(const Field& field, double depth_scale, double u, double v) {
  const double x = u * field.width - 0.5, y = v * field.height - 0.5;
  const double fi = std::floor(x), fj = std::floor(y);
  const double fx = x - fi, fy = y - fj;
  const auto i = std::int64_t(fi), j = std::int64_t(fj);
  const double h00 = field.at(i, j), h10 = field.at(i + 1, j), h01 = field.at(i, j + 1), h11 = field.at(i + 1, j + 1);
  const double h = h00 + (h10 - h00) * fx + (h01 - h00) * fy + (h00 - h10 - h01 + h11) * fx * fy;
  return depth_scale * (1.0 - h);
}

// Per level-0 texel, the maximum of its 3x3 neighbourhood (address mode applied), as a 1-channel float image:
// the bilinear surface over a texel's square interpolates only those texels, so a max-quadtree built from this
// bound is conservative for the bilinear surface (QDM with bilinear-patch refinement traverses it).
Image bilinear_upper_bound(const HeightField& field);

struct ReferenceHit {
  bool hit = false;  // false: the ray left the [0, depth_scale] slab or exceeded max_cells without a hit
  double t = 0;
  glm::dvec3 point{0.0};  // (u, v, depth) of the first intersection: origin + t * direction, except that the
                          // coordinate on the surface is pinned to it (the depth of a top face or of the bilinear
                          // patch, the u or v of a box wall); the origin itself when inside_at_start
  bool inside_at_start = false;  // the origin lies strictly below the surface (t = 0 is the answer); an origin
                                 // exactly on the surface also hits at t = 0, with inside_at_start = false
  std::int64_t cells_visited = 0;  // grid cells solved (texels for Box, centre-to-centre cells for Bilinear),
                                   // including the one holding the hit; 0 when settled at the origin
};

}  // namespace qdmr
