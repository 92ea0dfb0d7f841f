#include "shade/normal_mapping.hpp"

#include "core/det_math.hpp"

namespace qdmr {
namespace {

using simd::Float;

struct Vec3 {
  Float x, y, z;
};

Float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

Vec3 normalize(const Vec3& v) {
  // Zero vectors (possible only in degenerate helper lanes) stay finite.
  const Float len2 = xsimd::max(dot(v, v), Float(1e-30f));
  const Float inv = Float(1.0f) / xsimd::sqrt(len2);
  return {v.x * inv, v.y * inv, v.z * inv};
}

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

}  // namespace

void NormalMappingProgram::shade(const Fragments& in, ShadeOutput& out) const {
  const Float& u = in.varyings[kU];
  const Float& v = in.varyings[kV];
  const bool per_quad = lod_mode_ == LodMode::PerQuad;
  const Float dudx = per_quad ? simd::quad_ddx(u) : simd::pixel_ddx(u);
  const Float dvdx = per_quad ? simd::quad_ddx(v) : simd::pixel_ddx(v);
  const Float dudy = per_quad ? simd::quad_ddy(u) : simd::pixel_ddy(u);
  const Float dvdy = per_quad ? simd::quad_ddy(v) : simd::pixel_ddy(v);

  Float albedo[4];
  sample(albedo_, sampler_, u, v, lod_from_derivatives(albedo_, dudx, dvdx, dudy, dvdy), albedo);
  Float tangent_normal[4];
  sample(normal_, sampler_, u, v, lod_from_derivatives(normal_, dudx, dvdx, dudy, dvdy), tangent_normal);
  for (int c = 0; c < 3; ++c) tangent_normal[c] = tangent_normal[c] * Float(2.0f) - Float(1.0f);

  const Vec3 n = normalize({in.varyings[kNormalX], in.varyings[kNormalY], in.varyings[kNormalZ]});
  Vec3 t{in.varyings[kTangentX], in.varyings[kTangentY], in.varyings[kTangentZ]};
  const Float t_dot_n = dot(t, n);
  t = normalize({t.x - n.x * t_dot_n, t.y - n.y * t_dot_n, t.z - n.z * t_dot_n});
  const Float sign = xsimd::select(in.varyings[kTangentW] < Float(0.0f), Float(-1.0f), Float(1.0f));
  const Vec3 b0 = cross(n, t);
  const Vec3 b{b0.x * sign, b0.y * sign, b0.z * sign};
  const Vec3 shading = normalize({t.x * tangent_normal[0] + b.x * tangent_normal[1] + n.x * tangent_normal[2],
                                  t.y * tangent_normal[0] + b.y * tangent_normal[1] + n.y * tangent_normal[2],
                                  t.z * tangent_normal[0] + b.z * tangent_normal[1] + n.z * tangent_normal[2]});

  const Vec3 view = normalize({Float(lights_.camera_position.x) - in.varyings[kWorldX],
                               Float(lights_.camera_position.y) - in.varyings[kWorldY],
                               Float(lights_.camera_position.z) - in.varyings[kWorldZ]});
  Float diffuse[3] = {Float(lights_.ambient.x), Float(lights_.ambient.y), Float(lights_.ambient.z)};
  Float specular[3] = {Float(0.0f), Float(0.0f), Float(0.0f)};
  const Float zero(0.0f);
  for (const auto& light : lights_.directional) {
    const Vec3 l{Float(light.direction.x), Float(light.direction.y), Float(light.direction.z)};
    const Float n_dot_l = xsimd::max(dot(shading, l), zero);
    const Vec3 h = normalize({l.x + view.x, l.y + view.y, l.z + view.z});
    // No highlight where the light is below the geometric surface.
    const Float facing = xsimd::select(dot(n, l) > zero, Float(1.0f), zero);
    const Float spec = detmath::pow(xsimd::max(dot(shading, h), zero), Float(lighting_.shininess)) *
                       Float(lighting_.specular) * facing * xsimd::min(n_dot_l * Float(8.0f), Float(1.0f));
    const float radiance[3] = {light.radiance.x, light.radiance.y, light.radiance.z};
    for (int c = 0; c < 3; ++c) {
      diffuse[c] += n_dot_l * Float(radiance[c]);
      specular[c] += spec * Float(radiance[c]);
    }
  }
  for (int c = 0; c < 3; ++c) out.color[c] = albedo[c] * diffuse[c] + specular[c];
  out.normal[0] = shading.x;
  out.normal[1] = shading.y;
  out.normal[2] = shading.z;
}

}  // namespace qdmr
