#include "raster/geometry.hpp"

#include <cmath>

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <tbb/parallel_for.h>

#include "qdmr/core/limits.hpp"

namespace qdmr {
namespace {

// Planes as (a, b, c, d): inside when a*x + b*y + c*z + d*w >= 0 in clip space.
struct ClipPlane {
  glm::vec4 coefficients;
  double distance(const glm::vec4& v) const {
    return double(coefficients.x) * v.x + double(coefficients.y) * v.y + double(coefficients.z) * v.z +
           double(coefficients.w) * v.w;
  }
};

constexpr int kMaxPolygon = 3 + 6;  // a triangle clipped by 6 planes gains at most one vertex per plane

ClipVertex lerp(const ClipVertex& a, const ClipVertex& b, float t) {
  ClipVertex r;
  r.clip = a.clip + (b.clip - a.clip) * t;
  for (int i = 0; i < kVaryingCount; ++i) r.varyings[i] = a.varyings[i] + (b.varyings[i] - a.varyings[i]) * t;
  return r;
}

// Sutherland-Hodgman against one plane; returns the new vertex count.
int clip_polygon(const ClipVertex* in, int count, ClipVertex* out, const ClipPlane& plane) {
  int n = 0;
  for (int i = 0; i < count; ++i) {
    const ClipVertex& a = in[i];
    const ClipVertex& b = in[(i + 1) % count];
    const double da = plane.distance(a.clip);
    const double db = plane.distance(b.clip);
    if (da >= 0.0) out[n++] = a;
    if ((da >= 0.0) != (db >= 0.0)) out[n++] = lerp(a, b, float(da / (da - db)));
  }
  return n;
}

std::int64_t orient2d(const ScreenTriangle& t) {
  return std::int64_t(t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - std::int64_t(t.y[1] - t.y[0]) * (t.x[2] - t.x[0]);
}

class GeometryBuilder {
public:
  GeometryBuilder(const glm::mat4& view_projection, const Viewport& viewport, GeometryResult& result)
      : view_projection_(view_projection), viewport_(viewport), result_(result) {
    // Guard band: in NDC the viewport spans [-1, 1]; the band extends it by kGuardBandPixels on each side.
    const float gx = 1.0f + 2.0f * float(limits::kGuardBandPixels) / float(viewport.width);
    const float gy = 1.0f + 2.0f * float(limits::kGuardBandPixels) / float(viewport.height);
    clip_planes_ = {{
        {{0, 0, 1, 1}},     // near: z >= -w
        {{0, 0, -1, 1}},    // far:  z <= w
        {{1, 0, 0, gx}},    // guard band left
        {{-1, 0, 0, gx}},   // guard band right
        {{0, 1, 0, gy}},    // guard band bottom
        {{0, -1, 0, gy}},   // guard band top
    }};
  }

  void add(const DrawItem& item) {
    const MeshData& mesh = *item.mesh;
    const glm::mat3 linear(item.model);
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(linear));
    const bool mirrored = glm::determinant(linear) < 0.0f;
    const std::size_t vertex_count = mesh.vertex_count();

    std::vector<ClipVertex> clip(vertex_count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 4096), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const glm::vec4 world = item.model * glm::vec4(mesh.positions[i], 1.0f);
        const glm::vec3 n = glm::normalize(normal_matrix * mesh.normals[i]);
        const glm::vec4& t4 = mesh.tangents[i];
        const glm::vec3 t = glm::normalize(linear * glm::vec3(t4));
        ClipVertex& v = clip[i];
        v.clip = view_projection_ * world;
        v.varyings = {world.x, world.y, world.z, n.x, n.y, n.z, t.x, t.y, t.z, mirrored ? -t4.w : t4.w,
                      mesh.uvs[i].x, mesh.uvs[i].y};
      }
    });

    std::vector<std::uint32_t> screen_index(vertex_count, kUnmapped);
    const std::size_t triangles = mesh.triangle_count();
    result_.counters.triangles_in += triangles;
    for (std::size_t t = 0; t < triangles; ++t) {
      const std::uint32_t material =
          mesh.triangle_materials.empty() ? item.material : item.mesh_materials[mesh.triangle_materials[t]];
      const std::uint32_t i0 = mesh.indices[3 * t], i1 = mesh.indices[3 * t + 1], i2 = mesh.indices[3 * t + 2];
      const ClipVertex* v[3] = {&clip[i0], &clip[i1], &clip[i2]};

      unsigned outside_all = ~0u, outside_any = 0;
      for (const ClipVertex* cv : v) {
        const unsigned frustum = outcode(cv->clip, 1.0f, 1.0f);
        const unsigned band = outcode(cv->clip, guard_x(), guard_y());
        outside_all &= frustum;
        outside_any |= band;
      }
      if (outside_all != 0) {
        ++result_.counters.culled_outside;
        continue;
      }
      if (outside_any == 0) {
        const std::uint32_t s0 = map_vertex(screen_index, i0, *v[0]);
        const std::uint32_t s1 = map_vertex(screen_index, i1, *v[1]);
        const std::uint32_t s2 = map_vertex(screen_index, i2, *v[2]);
        emit(s0, s1, s2, material, mirrored);
        continue;
      }
      ++result_.counters.clipped;
      ClipVertex polygon_a[kMaxPolygon], polygon_b[kMaxPolygon];
      polygon_a[0] = *v[0];
      polygon_a[1] = *v[1];
      polygon_a[2] = *v[2];
      int count = 3;
      ClipVertex* in = polygon_a;
      ClipVertex* out = polygon_b;
      for (const ClipPlane& plane : clip_planes_) {
        count = clip_polygon(in, count, out, plane);
        std::swap(in, out);
        if (count < 3) break;
      }
      if (count < 3) {
        ++result_.counters.culled_outside;
        continue;
      }
      std::uint32_t first = add_vertex(in[0]);
      std::uint32_t previous = add_vertex(in[1]);
      for (int k = 2; k < count; ++k) {
        const std::uint32_t current = add_vertex(in[k]);
        emit(first, previous, current, material, mirrored);
        previous = current;
      }
    }
  }

private:
  static constexpr std::uint32_t kUnmapped = ~0u;
  float guard_x() const { return clip_planes_[2].coefficients.w; }
  float guard_y() const { return clip_planes_[4].coefficients.w; }

  // Bits: near, far, left, right, bottom, top; x/y tested against the band +-g*w.
  static unsigned outcode(const glm::vec4& c, float gx, float gy) {
    unsigned code = 0;
    if (!(c.z >= -c.w)) code |= 1u;
    if (!(c.z <= c.w)) code |= 2u;
    if (!(c.x >= -gx * c.w)) code |= 4u;
    if (!(c.x <= gx * c.w)) code |= 8u;
    if (!(c.y >= -gy * c.w)) code |= 16u;
    if (!(c.y <= gy * c.w)) code |= 32u;
    return code;
  }

  std::uint32_t map_vertex(std::vector<std::uint32_t>& screen_index, std::uint32_t i, const ClipVertex& v) {
    if (screen_index[i] == kUnmapped) screen_index[i] = add_vertex(v);
    return screen_index[i];
  }

  std::uint32_t add_vertex(const ClipVertex& v) {
    const double inv_w = 1.0 / double(v.clip.w);
    const double ndc_x = v.clip.x * inv_w, ndc_y = v.clip.y * inv_w, ndc_z = v.clip.z * inv_w;
    const double sx = (ndc_x * 0.5 + 0.5) * viewport_.width;
    const double sy = (0.5 - ndc_y * 0.5) * viewport_.height;
    ScreenVertex s;
    s.inv_w = float(inv_w);
    s.z = float(ndc_z * 0.5 + 0.5);
    s.varyings = v.varyings;
    result_.vertices.push_back(s);
    fixed_x_.push_back(std::int32_t(std::floor(sx * limits::kSubpixelScale + 0.5)));
    fixed_y_.push_back(std::int32_t(std::floor(sy * limits::kSubpixelScale + 0.5)));
    return std::uint32_t(result_.vertices.size() - 1);
  }

  void emit(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t material, bool mirrored) {
    ScreenTriangle t;
    t.vertex = {a, b, c};
    t.x = {fixed_x_[a], fixed_x_[b], fixed_x_[c]};
    t.y = {fixed_y_[a], fixed_y_[b], fixed_y_[c]};
    t.material = material;
    // Front faces are counter-clockwise as seen on screen, which is negative orient2d in y-down screen
    // space; a mirroring model matrix flips that. Setup wants positive orientation, so front faces are swapped.
    const std::int64_t area = orient2d(t);
    const std::int64_t front_area = mirrored ? area : -area;
    if (front_area <= 0) {
      ++result_.counters.culled_backface;
      return;
    }
    if (area < 0) {
      std::swap(t.vertex[1], t.vertex[2]);
      std::swap(t.x[1], t.x[2]);
      std::swap(t.y[1], t.y[2]);
    }
    result_.triangles.push_back(t);
    ++result_.counters.triangles_out;
  }

  glm::mat4 view_projection_;
  Viewport viewport_;
  GeometryResult& result_;
  std::array<ClipPlane, 6> clip_planes_;
  std::vector<std::int32_t> fixed_x_, fixed_y_;
};

}  // namespace

GeometryResult run_geometry(const std::vector<DrawItem>& items, const glm::mat4& view, const glm::mat4& projection,
                            const Viewport& viewport) {
  GeometryResult result;
  GeometryBuilder builder(projection * view, viewport, result);
  for (const DrawItem& item : items) builder.add(item);
  return result;
}

}  // namespace qdmr
