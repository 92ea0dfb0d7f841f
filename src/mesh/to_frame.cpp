// A glTF primitive's vertices into qdmr's frame (mesh/to_frame.hpp).
#include "mesh/to_frame.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <xsimd/xsimd.hpp>

#include "mesh/builders.hpp"

namespace qdmr::mesh_detail {

void to_frame_one(glm::vec3& position, glm::vec3& normal, glm::vec4& tangent, const glm::dmat4& world,
                  const glm::dmat3& normal_matrix, bool mirrored) {
  position = glm::vec3(world * glm::dvec4(glm::dvec3(position), 1.0));
  const glm::dvec3 n = normal_matrix * glm::dvec3(normal);
  const double len = glm::length(n);
  normal = len > 0.0 && std::isfinite(len) ? glm::vec3(n / len) : glm::vec3(0, 0, 1);
  const glm::vec4 t = tangent;
  const glm::dvec3 tw = glm::dmat3(world) * glm::dvec3(t);
  const double tl = glm::length(tw);
  const float w = (t.w < 0.0f) != mirrored ? -1.0f : 1.0f;
  tangent = glm::vec4(tl > 0.0 && std::isfinite(tl) ? glm::vec3(tw / tl) : any_orthogonal(normal), w);
}

namespace {

// Two vertices side by side in SSE2's double lanes (x86-64's baseline: this file is built once, for every ISA).
using Lanes = xsimd::batch<double, xsimd::sse2>;

// Two vertices' x, y, z (lane 0 the first), in double.
struct Pair {
  Lanes x, y, z;
};

template <class V>
Pair load(const V& a, const V& b) {
  const auto lanes = [](double first, double second) {
    alignas(16) const double v[2] = {first, second};
    return Lanes::load_aligned(v);
  };
  return {lanes(double(a.x), double(b.x)), lanes(double(a.y), double(b.y)), lanes(double(a.z), double(b.z))};
}

// Row i of a 3x3 product: (m[0][i] x + m[1][i] y) + m[2][i] z, as glm's mat3 x vec3.
template <class M>
Lanes row(const M& m, int i, const Pair& v) {
  return (Lanes(m[0][i]) * v.x + Lanes(m[1][i]) * v.y) + Lanes(m[2][i]) * v.z;
}

// glm::length: sqrt((x x + y y) + z z).
Lanes length(const Pair& v) { return xsimd::sqrt((v.x * v.x + v.y * v.y) + v.z * v.z); }

// Per lane: len > 0 and finite (NaN fails both).
xsimd::batch_bool<double, xsimd::sse2> usable(const Lanes& len) {
  return (len > Lanes(0.0)) & (len <= Lanes(std::numeric_limits<double>::max()));
}

// A pair stored; lane `lane` read back as one vertex rounded to float (glm::vec3 of a dvec3).
struct Stored {
  alignas(16) double x[2], y[2], z[2];
  explicit Stored(const Pair& v) {
    v.x.store_aligned(x);
    v.y.store_aligned(y);
    v.z.store_aligned(z);
  }
  glm::vec3 operator[](int lane) const { return glm::vec3(float(x[lane]), float(y[lane]), float(z[lane])); }
};

// v / len per component (three divisions, as a glm vector over a scalar).
Pair over(const Pair& v, const Lanes& len) { return {v.x / len, v.y / len, v.z / len}; }

}  // namespace

void to_frame(std::span<glm::vec3> positions, std::span<glm::vec3> normals, std::span<glm::vec4> tangents,
              const glm::dmat4& world, const glm::dmat3& normal_matrix, bool mirrored) {
  const glm::dmat3 linear(world);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 16384), [&](const auto& range) {
    std::size_t v = range.begin();
    for (; v + 1 < range.end(); v += 2) {
      // Position: (m[0] x + m[1] y) + (m[2] z + m[3] 1), glm's dmat4 x dvec4.
      const Pair p = load(positions[v], positions[v + 1]);
      const auto moved = [&](int i) {
        return (Lanes(world[0][i]) * p.x + Lanes(world[1][i]) * p.y) +
               (Lanes(world[2][i]) * p.z + Lanes(world[3][i]) * Lanes(1.0));
      };
      const Stored position(Pair{moved(0), moved(1), moved(2)});
      positions[v] = position[0];
      positions[v + 1] = position[1];

      const Pair n0 = load(normals[v], normals[v + 1]);
      const Pair n = {row(normal_matrix, 0, n0), row(normal_matrix, 1, n0), row(normal_matrix, 2, n0)};
      const Lanes len = length(n);
      const auto n_ok = usable(len);
      const Stored unit_n(over(n, len));
      for (int lane = 0; lane < 2; ++lane) normals[v + lane] = n_ok.get(std::size_t(lane)) ? unit_n[lane] : glm::vec3(0, 0, 1);

      const glm::vec4 t[2] = {tangents[v], tangents[v + 1]};
      const Pair t0 = load(t[0], t[1]);
      const Pair tw = {row(linear, 0, t0), row(linear, 1, t0), row(linear, 2, t0)};
      const Lanes tl = length(tw);
      const auto t_ok = usable(tl);
      const Stored unit_t(over(tw, tl));
      for (int lane = 0; lane < 2; ++lane) {
        const float w = (t[lane].w < 0.0f) != mirrored ? -1.0f : 1.0f;
        tangents[v + lane] = glm::vec4(t_ok.get(std::size_t(lane)) ? unit_t[lane] : any_orthogonal(normals[v + lane]), w);
      }
    }
    for (; v < range.end(); ++v) to_frame_one(positions[v], normals[v], tangents[v], world, normal_matrix, mirrored);
  });
}

}  // namespace qdmr::mesh_detail
