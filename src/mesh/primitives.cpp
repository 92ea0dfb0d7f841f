// Plane, box, sphere and grid: parametric patches with analytic tangent frames (the grid derives its
// frames from the displaced surface).
#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "mesh/builders.hpp"
#include "qdmr/texture/texture_level0.hpp"

namespace qdmr::mesh_detail {

namespace {

// A point of a parametric surface: position, outward unit normal and the directions of increasing s and t.
struct SurfacePoint {
  glm::dvec3 p, n, dpds, dpdt;
};

// Tangent along +u = sign(uv_scale.x) * dP/ds; the bitangent along +v must be sign(uv_scale.y) * dP/dt,
// with cross(n, dP/ds) = dP/dt on every surface built here.
glm::vec4 analytic_tangent(const SurfacePoint& sp, glm::vec2 uv_scale) {
  const glm::dvec3 t = glm::normalize(sp.dpds - sp.n * glm::dot(sp.n, sp.dpds));
  const double su = uv_scale.x < 0.0f ? -1.0 : 1.0;
  const double sv = uv_scale.y < 0.0f ? -1.0 : 1.0;
  return glm::vec4(glm::vec3(t * su), float(su * sv));
}

void push_vertex(MeshData& m, const SurfacePoint& sp, glm::dvec2 st, glm::vec2 uv_scale) {
  m.positions.emplace_back(sp.p);
  m.normals.emplace_back(sp.n);
  m.tangents.push_back(analytic_tangent(sp, uv_scale));
  m.uvs.emplace_back(float(st.x * uv_scale.x), float(st.y * uv_scale.y));
}

// Appends an (nu+1) x (nv+1) vertex patch over s, t in [0,1] and its 2*nu*nv triangles, counter-clockwise
// seen from the side cross(dP/ds, dP/dt) points to.
template <class Surface>
void add_patch(MeshData& m, int nu, int nv, glm::vec2 uv_scale, Surface surface) {
  const auto base = std::uint32_t(m.positions.size());
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const glm::dvec2 st(double(i) / nu, double(j) / nv);
      push_vertex(m, surface(st.x, st.y), st, uv_scale);
    }
  const auto row = std::uint32_t(nu + 1);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const std::uint32_t a = base + std::uint32_t(j) * row + std::uint32_t(i), b = a + 1, c = b + row, d = a + row;
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
}

SurfacePoint plane_point(const MeshDesc& desc, double s, double t) {
  return {{(s - 0.5) * desc.size.x, (t - 0.5) * desc.size.y, 0.0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
}

// Bilinear fetch of channel 0, texel centres at (i + 0.5) / N, clamp addressing.
double bilinear_clamp(const Image& img, double u, double v) {
  const double x = u * img.width - 0.5, y = v * img.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const auto clamp_x = [&](double i) { return int(std::clamp(i, 0.0, double(img.width - 1))); };
  const auto clamp_y = [&](double i) { return int(std::clamp(i, 0.0, double(img.height - 1))); };
  const int x0 = clamp_x(fx), x1 = clamp_x(fx + 1), y0 = clamp_y(fy), y1 = clamp_y(fy + 1);
  const double wx = x - fx, wy = y - fy;
  const double top = img.at(x0, y0, 0) * (1 - wx) + img.at(x1, y0, 0) * wx;
  const double bottom = img.at(x0, y1, 0) * (1 - wx) + img.at(x1, y1, 0) * wx;
  return top * (1 - wy) + bottom * wy;
}

}  // namespace

MeshData make_plane(const MeshDesc& desc) {
  MeshData m;
  add_patch(m, 1, 1, desc.uv_scale, [&](double s, double t) { return plane_point(desc, s, t); });
  return m;
}

MeshData make_box(const MeshDesc& desc) {
  struct Face {
    glm::dvec3 n, t;
  };
  // Tangents chosen so every side face has +v pointing up (+z) and the top face matches the plane.
  static const Face kFaces[6] = {{{0, 0, 1}, {1, 0, 0}},  {{0, 0, -1}, {1, 0, 0}}, {{1, 0, 0}, {0, 1, 0}},
                                     {{-1, 0, 0}, {0, -1, 0}}, {{0, 1, 0}, {-1, 0, 0}}, {{0, -1, 0}, {1, 0, 0}}};
  const double h = 0.5 * desc.size.x;
  MeshData m;
  for (const Face& f : kFaces) {
    const glm::dvec3 b = glm::cross(f.n, f.t);
    add_patch(m, 1, 1, desc.uv_scale, [&](double s, double t) {
      return SurfacePoint{h * (f.n + (2 * s - 1) * f.t + (2 * t - 1) * b), f.n, f.t, b};
    });
  }
  return m;
}

MeshData make_sphere(const MeshDesc& desc) {
  const int segments = desc.segments, rings = desc.segments / 2;
  const double r = 0.5 * desc.size.x, pi = std::numbers::pi;
  // Column `segments` repeats column 0 exactly, so the seam is watertight.
  const auto east = [&](double s) {
    const double phi = 2 * pi * (s >= 1.0 ? 0.0 : s);
    return glm::dvec3(-std::sin(phi), std::cos(phi), 0.0);
  };
  const auto point = [&](double s, double t) {
    const double theta = pi * (t - 0.5);  // latitude: v = 0 at the south pole
    const glm::dvec3 e = east(s);
    const glm::dvec3 radial(e.y, -e.x, 0.0);
    const glm::dvec3 n = radial * std::cos(theta) + glm::dvec3(0, 0, std::sin(theta));
    const glm::dvec3 north = -radial * std::sin(theta) + glm::dvec3(0, 0, std::cos(theta));
    return SurfacePoint{r * n, n, e, north};
  };
  MeshData m;
  // Pole rows hold one vertex per segment, at the segment's middle longitude, so each pole triangle has
  // its own tangent along +u.
  const auto pole_row = [&](double t) {
    const auto first = std::uint32_t(m.positions.size());
    const double z = t < 0.5 ? -1.0 : 1.0;
    for (int j = 0; j < segments; ++j) {
      const double s = (j + 0.5) / segments;
      const glm::dvec3 e = east(s);
      const glm::dvec3 radial(e.y, -e.x, 0.0);
      push_vertex(m, {{0, 0, z * r}, {0, 0, z}, e, -z * radial}, {s, t}, desc.uv_scale);
    }
    return first;
  };
  const auto ring_vertex = [&](int ring, int j) {
    return std::uint32_t(segments) + std::uint32_t(ring - 1) * std::uint32_t(segments + 1) + std::uint32_t(j);
  };
  pole_row(0.0);
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      const glm::dvec2 st(double(j) / segments, double(i) / rings);
      push_vertex(m, point(st.x, st.y), st, desc.uv_scale);
    }
  const std::uint32_t north = pole_row(1.0);
  for (int j = 0; j < segments; ++j) {
    const auto uj = std::uint32_t(j);
    m.indices.insert(m.indices.end(), {uj, ring_vertex(1, j + 1), ring_vertex(1, j)});
    for (int i = 1; i + 1 < rings; ++i) {
      const std::uint32_t a = ring_vertex(i, j), b = ring_vertex(i, j + 1);
      const std::uint32_t c = ring_vertex(i + 1, j + 1), d = ring_vertex(i + 1, j);
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
    m.indices.insert(m.indices.end(), {ring_vertex(rings - 1, j), ring_vertex(rings - 1, j + 1), north + uj});
  }
  return m;
}

MeshData make_grid(const MeshDesc& desc, const std::string& where) {
  const int n = desc.resolution;
  MeshData m;
  add_patch(m, n, n, desc.uv_scale, [&](double s, double t) { return plane_point(desc, s, t); });
  if (desc.height_map.source == TextureSource::None) return m;

  const Image heights = make_texture(desc.height_map, TexturePurpose::Height, LayerDesc{}, nullptr,
                                     where + "/height_map");
  const auto row = std::size_t(n + 1);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions[j * row + i].z = float(desc.height * bilinear_clamp(heights, double(i) / n, double(j) / n));

  // Central differences inside, one-sided at the border.
  const auto z = [&](int i, int j) { return double(m.positions[std::size_t(j) * row + std::size_t(i)].z); };
  const double dx = double(desc.size.x) / n, dy = double(desc.size.y) / n;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n), j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n);
      const double dzdx = (z(i1, j) - z(i0, j)) / ((i1 - i0) * dx);
      const double dzdy = (z(i, j1) - z(i, j0)) / ((j1 - j0) * dy);
      m.normals[j * row + i] = glm::vec3(glm::normalize(glm::dvec3(-dzdx, -dzdy, 1.0)));
    }
  compute_tangents(m);
  return m;
}

}  // namespace qdmr::mesh_detail
