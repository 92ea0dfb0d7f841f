#include "qdmr/reference/reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace qdmr {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One axis of the traversal grid, in grid units (texels for Box; for Bilinear shifted by half a texel so that
// the cell boundaries are the texel centres): x(t) = origin + t * dir, cell k spans [k, k + 1).
struct Axis {
  double origin, dir;
  std::int64_t cell;
  int step;  // +1, -1, or 0 when the ray does not move along this axis

  Axis(double o, double d) : origin(o), dir(d), cell(std::int64_t(std::floor(o))), step(d > 0 ? 1 : d < 0 ? -1 : 0) {}

  // Where the ray leaves the current cell along this axis, from the integer boundary itself: no error builds up
  // from cell to cell, and successive exits are monotonic.
  double exit() const {
    if (step == 0) return kInf;
    return (double(step > 0 ? cell + 1 : cell) - origin) / dir;
  }
  // The boundary just crossed by a step, in grid units.
  double entered_boundary() const { return double(step > 0 ? cell : cell + 1); }
};

// The first s in [0, length] where g(s) = q2 s^2 + q1 s + q0 reaches 0 from below (g(0) = q0 < 0), or -1.
double first_crossing(double q2, double q1, double q0, double length) {
  double s;
  if (q2 == 0) {
    if (q1 <= 0) return -1;
    s = -q0 / q1;
  } else {
    const double disc = q1 * q1 - 4 * q2 * q0;
    if (disc < 0) return -1;  // g keeps the sign of q0 < 0
    const double root = std::sqrt(disc);
    const double q = -0.5 * (q1 + (q1 >= 0 ? root : -root));  // no cancellation between q1 and root
    if (q == 0) return -1;  // only by underflow: q == 0 needs disc == 0 and q1 == 0, so q0 == 0
    const double r1 = q / q2, r2 = q0 / q;
    const double lo = std::min(r1, r2), hi = std::max(r1, r2);
    // g < 0 at s = 0: between the roots when q2 > 0 (the crossing is the larger one), outside them when q2 < 0
    // (the crossing is the smaller one, if it lies ahead).
    if (q2 < 0 && hi < 0) return -1;
    s = q2 > 0 ? hi : lo;
  }
  // A root a rounding error behind the cell entry is a crossing at the entry.
  s = std::max(s, 0.0);
  return s <= length ? s : -1;
}

}  // namespace

ReferenceHit intersect_reference(const HeightField& field, double depth_scale, const SurfaceRay& ray,
                                 ReferenceSurface surface, std::int64_t max_cells) {
  const glm::dvec3 o = ray.origin, d = ray.direction;
  const double D = depth_scale;
  ReferenceHit r;
  const double start_depth = surface_depth(field, D, o.x, o.y, surface);
  if (o.z >= start_depth) {
    r.hit = true;
    r.point = o;
    r.inside_at_start = o.z > start_depth;
    return r;
  }
  // Above the polygon and not going down, or vertical and not going down: nothing ahead to meet.
  if ((o.z < 0 && d.z <= 0) || (d.x == 0 && d.y == 0 && d.z <= 0)) return r;

  const bool box = surface == ReferenceSurface::Box;
  const double offset = box ? 0.0 : 0.5;
  const double W = field.width, H = field.height;
  Axis ax(o.x * W - offset, d.x * W), ay(o.y * H - offset, d.y * H);
  const auto hit_at = [&](double t, std::int64_t cells) {
    r.hit = true;
    r.t = t;
    r.point = o + t * d;
    r.cells_visited = cells;
  };
  const auto box_depth = [&](std::int64_t i, std::int64_t j) { return D * (1.0 - field.at(i, j)); };

  double ta = 0;  // where the ray entered the current cell
  bool crossed_x = false, crossed_y = false;  // the boundaries crossed to get there
  for (std::int64_t n = 1;; ++n) {
    const double tx = ax.exit(), ty = ay.exit();
    const double tb = std::min(tx, ty);
    if (box) {
      const double s = box_depth(ax.cell, ay.cell);
      if (o.z + ta * d.z >= s) {  // through the wall just crossed (the first cell was settled above)
        hit_at(ta, n);
        if (crossed_x) r.point.x = ax.entered_boundary() / W;
        if (crossed_y) r.point.y = ay.entered_boundary() / H;
        return r;
      }
      if (d.z > 0) {
        const double t = (s - o.z) / d.z;
        if (t <= tb) {  // through the top face
          hit_at(std::max(t, ta), n);
          r.point.z = s;
          return r;
        }
      }
    } else {
      const std::int64_t i = ax.cell, j = ay.cell;
      const double h00 = field.at(i, j), h10 = field.at(i + 1, j), h01 = field.at(i, j + 1),
                   h11 = field.at(i + 1, j + 1);
      const double A = h10 - h00, B = h01 - h00, C = h00 - h10 - h01 + h11;
      const auto depth_at = [&](double fx, double fy) { return D * (1.0 - (h00 + A * fx + B * fy + C * fx * fy)); };
      // Local coordinates at the entry; the clamp only removes rounding (the entry lies in the cell).
      const double fx0 = std::clamp(ax.origin + ta * ax.dir - double(i), 0.0, 1.0);
      const double fy0 = std::clamp(ay.origin + ta * ay.dir - double(j), 0.0, 1.0);
      // ray depth - surface depth along s = t - ta: the surface is bilinear in (fx0 + s bx, fy0 + s by).
      const double bx = ax.dir, by = ay.dir;
      const double q0 = o.z + ta * d.z - depth_at(fx0, fy0);
      const double q1 = d.z + D * (A * bx + B * by + C * (fx0 * by + fy0 * bx));
      const double q2 = D * C * bx * by;
      const double s = q0 >= 0 ? 0.0 : first_crossing(q2, q1, q0, tb - ta);
      if (s >= 0) {
        hit_at(ta + s, n);
        r.point.z = depth_at(std::clamp(fx0 + s * bx, 0.0, 1.0), std::clamp(fy0 + s * by, 0.0, 1.0));
        return r;
      }
    }
    r.cells_visited = n;
    if (n >= max_cells || tb == kInf) return r;
    if (d.z < 0 && o.z + tb * d.z < 0) return r;  // risen above the polygon for good
    crossed_x = tx <= ty;
    crossed_y = ty <= tx;
    if (box && crossed_x && crossed_y) {
      // Through a corner: the ray touches the edges of the two cells beside the diagonal.
      const double z = o.z + tb * d.z;
      if (z >= box_depth(ax.cell + ax.step, ay.cell) || z >= box_depth(ax.cell, ay.cell + ay.step)) {
        hit_at(tb, n);
        r.point.x = double(ax.step > 0 ? ax.cell + 1 : ax.cell) / W;
        r.point.y = double(ay.step > 0 ? ay.cell + 1 : ay.cell) / H;
        return r;
      }
    }
    if (crossed_x) ax.cell += ax.step;
    if (crossed_y) ay.cell += ay.step;
    ta = tb;
  }
}

LightVisibility light_visibility(const HeightField& field, double depth_scale, const glm::dvec3& start,
                                 const glm::dvec2& climb, std::int64_t max_cells) {
  LightVisibility r;
  const double x0 = start.x * field.width, y0 = start.y * field.height, s0 = start.z;
  const double dx = climb.x * field.width, dy = climb.y * field.height;  // texels per unit of depth climbed
  if ((dx == 0 && x0 == std::floor(x0)) || (dy == 0 && y0 == std::floor(y0))) return r;  // along a wall
  const int sx = dx > 0 ? 1 : dx < 0 ? -1 : 0, sy = dy > 0 ? 1 : dy < 0 ? -1 : 0;
  // T0: behind along the light on a boundary (for dx > 0, x0 = i lies in texel i - 1).
  std::int64_t i = std::int64_t(dx > 0 ? std::ceil(x0) - 1 : std::floor(x0));
  std::int64_t j = std::int64_t(dy > 0 ? std::ceil(y0) - 1 : std::floor(y0));
  for (;;) {
    const double tx = sx == 0 ? kInf : (double(sx > 0 ? i + 1 : i) - x0) / dx;
    const double ty = sy == 0 ? kInf : (double(sy > 0 ? j + 1 : j) - y0) / dy;
    const double c = std::min(tx, ty);  // where the ray enters the next texel (diagonally through a corner)
    if (s0 - c <= 0) return r;          // at or above the polygon (also c = inf: the light overhead)
    if (tx <= ty) i += sx;
    if (ty <= tx) j += sy;
    ++r.cells_visited;
    if (s0 - c > depth_scale * (1.0 - field.at(i, j))) {
      r.visible = false;
      r.blocker_i = i;
      r.blocker_j = j;
      r.blocker_climb = c;
      return r;
    }
    if (r.cells_visited >= max_cells) {
      r.capped = true;
      return r;
    }
  }
}

}  // namespace qdmr
