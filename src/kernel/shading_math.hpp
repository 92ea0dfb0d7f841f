#pragma once
// Vector algebra on batches and the steps every shading program shares: the tangent frame from the
// varyings and UV derivatives (lighting: lighting_models.hpp). Lane-wise IEEE only, so SSE and AVX2 agree.
#include "core/det_math.hpp"
#include "core/simd.hpp"
#include "qdmr/core/sampling.hpp"
#include "program/light_rig.hpp"
#include "kernel/batch.hpp"
#include "kernel/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::shading {

using simd::Float;

struct Vec3 {
  Float x, y, z;
};

inline Float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Vec3 scale(const Vec3& a, const Float& s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 add(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 normalize(const Vec3& v) {
  // Zero vectors (possible only in degenerate helper lanes) stay finite.
  const Float len2 = xsimd::max(dot(v, v), Float(1e-30f));
  return scale(v, Float(1.0f) / xsimd::sqrt(len2));
}

// Orthonormal tangent frame from the interpolated varyings: t along +u, b along +v, n the geometric normal.
struct TangentFrame {
  Vec3 t, b, n;

  static TangentFrame from(const Fragments& in) {
    TangentFrame f;
    f.n = normalize({in.varyings[kNormalX], in.varyings[kNormalY], in.varyings[kNormalZ]});
    const Vec3 t{in.varyings[kTangentX], in.varyings[kTangentY], in.varyings[kTangentZ]};
    f.t = normalize(add(t, scale(f.n, Float(0.0f) - dot(t, f.n))));
    const Float sign = xsimd::select(in.varyings[kTangentW] < Float(0.0f), Float(-1.0f), Float(1.0f));
    f.b = scale(cross(f.n, f.t), sign);
    return f;
  }
  Vec3 to_world(const Vec3& v) const { return add(add(scale(t, v.x), scale(b, v.y)), scale(n, v.z)); }
  Vec3 to_tangent(const Vec3& v) const { return {dot(v, t), dot(v, b), dot(v, n)}; }
};

struct UvDerivatives {
  Float dudx, dvdx, dudy, dvdy;

  static UvDerivatives from(const Float& u, const Float& v, LodMode mode) {
    if (mode == LodMode::PerQuad) return {simd::quad_ddx(u), simd::quad_ddx(v), simd::quad_ddy(u), simd::quad_ddy(v)};
    return {simd::pixel_ddx(u), simd::pixel_ddx(v), simd::pixel_ddy(u), simd::pixel_ddy(v)};
  }
  // The UV offset to the same lane of the quad below (two pixel rows down), a prefetch hint for samplers.
  UvAhead quad_below() const { return {dudy + dudy, dvdy + dvdy}; }
};

inline Vec3 view_vector(const Fragments& in, const LightRig& lights) {
  return normalize({Float(lights.camera_position.x) - in.varyings[kWorldX],
                    Float(lights.camera_position.y) - in.varyings[kWorldY],
                    Float(lights.camera_position.z) - in.varyings[kWorldZ]});
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::shading
