// Lighting models: Blinn-Phong bit for bit as the programs' former blinn_phong, Cook-Torrance against a double-precision
// evaluation of the same formulas and a white-furnace bound, visibility and AO factors, specular from albedo.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include <glm/geometric.hpp>

#include "kernel/lighting_models.hpp"
#include "plan/program_choice.hpp"

namespace qdmr::shading {
namespace {

// The Blinn-Phong the programs used before lighting_models.hpp (kept here as the oracle: the golden images
// were made with it; since bits version 4 with the highlight's power by detmath::pow_uniform): directional lights
// plus ambient; `geometric` gates highlights below the polygon.
inline void blinn_phong(const Vec3& shading_normal, const Vec3& geometric, const Vec3& view, const Float* albedo,
                        const LightingDesc& lighting, const LightRig& lights, Float* color) {
  Float diffuse[3] = {Float(lights.ambient.x), Float(lights.ambient.y), Float(lights.ambient.z)};
  Float specular[3] = {Float(0.0f), Float(0.0f), Float(0.0f)};
  const Float zero(0.0f);
  for (const auto& light : lights.directional) {
    const Vec3 l{Float(light.direction.x), Float(light.direction.y), Float(light.direction.z)};
    const Float n_dot_l = xsimd::max(dot(shading_normal, l), zero);
    const Vec3 h = normalize(add(l, view));
    const Float facing = xsimd::select(dot(geometric, l) > zero, Float(1.0f), zero);
    const Float spec = detmath::pow_uniform(xsimd::max(dot(shading_normal, h), zero), lighting.shininess) *
                       Float(lighting.specular) * facing * xsimd::min(n_dot_l * Float(8.0f), Float(1.0f));
    const float radiance[3] = {light.radiance.x, light.radiance.y, light.radiance.z};
    for (int c = 0; c < 3; ++c) {
      diffuse[c] += n_dot_l * Float(radiance[c]);
      specular[c] += spec * Float(radiance[c]);
    }
  }
  for (int c = 0; c < 3; ++c) color[c] = albedo[c] * diffuse[c] + specular[c];
}

using Lanes = std::array<float, simd::kLanes>;

Float batch(const Lanes& a) { return Float::load_unaligned(a.data()); }
Lanes lanes(const Float& f) {
  Lanes a;
  f.store_unaligned(a.data());
  return a;
}

// Per lane unit vectors with z >= min_z (rejection sampling), and their batch.
struct Directions {
  std::vector<glm::vec3> lane;
  Vec3 batch;
};

Directions random_directions(std::mt19937& rng, float min_z) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  Directions d;
  Lanes x, y, z;
  for (int l = 0; l < simd::kLanes; ++l) {
    glm::vec3 v;
    do v = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::length(v) < 0.1f || glm::length(v) > 1.0f || glm::normalize(v).z < min_z);
    v = glm::normalize(v);
    d.lane.push_back(v);
    x[std::size_t(l)] = v.x;
    y[std::size_t(l)] = v.y;
    z[std::size_t(l)] = v.z;
  }
  d.batch = {batch(x), batch(y), batch(z)};
  return d;
}

LightRig random_rig(std::mt19937& rng, int lights) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  LightRig rig;
  rig.ambient = {unit(rng) * 0.3f, unit(rng) * 0.3f, unit(rng) * 0.3f};
  for (int i = 0; i < lights; ++i) {
    const glm::vec3 dir = glm::normalize(glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.2f));
    rig.directional.push_back({dir, {unit(rng) * 2.0f, unit(rng) * 2.0f, unit(rng) * 2.0f}});
  }
  return rig;
}

std::array<Float, 3> random_albedo(std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::array<Float, 3> a;
  for (Float& c : a) {
    Lanes v;
    for (float& x : v) x = unit(rng);
    c = batch(v);
  }
  return a;
}

bool same_bits(const Float* a, const Float* b) {
  for (int c = 0; c < 3; ++c) {
    const Lanes x = lanes(a[c]), y = lanes(b[c]);
    if (std::memcmp(x.data(), y.data(), sizeof x) != 0) return false;
  }
  return true;
}

TEST(LightingModels, BlinnPhongIsShadingMathBitForBit) {
  std::mt19937 rng(11);
  for (int round = 0; round < 200; ++round) {
    const Directions n = random_directions(rng, -0.3f), g = random_directions(rng, 0.0f), v = random_directions(rng, -0.1f);
    const LightRig rig = random_rig(rng, round % 4);
    const std::array<Float, 3> albedo = random_albedo(rng);
    LightingDesc lighting;
    lighting.specular = std::uniform_real_distribution<float>(0.0f, 2.0f)(rng);
    lighting.shininess = std::array<float, 4>{1.0f, 8.0f, 32.0f, 100.5f}[std::size_t(round % 4)];
    Float expected[3], got[3], got_lit[3];
    blinn_phong(n.batch, g.batch, v.batch, albedo.data(), lighting, rig, expected);
    const SurfaceSample surface{albedo.data(), Float(lighting.specular), Float(1.0f)};
    shade_lights(n.batch, g.batch, v.batch, surface, nullptr, lighting.model, lighting_params(lighting), rig, got);
    EXPECT_TRUE(same_bits(expected, got)) << round;
    const std::vector<Float> all_lit(rig.directional.size(), Float(1.0f));
    shade_lights(n.batch, g.batch, v.batch, surface, all_lit.data(), lighting.model, lighting_params(lighting), rig, got_lit);
    EXPECT_TRUE(same_bits(expected, got_lit)) << round;
  }
}

TEST(LightingModels, AoScalesAmbientAndVisibilityRemovesLights) {
  std::mt19937 rng(5);
  for (LightingModel model : {LightingModel::BlinnPhong, LightingModel::CookTorrance})
    for (int round = 0; round < 50; ++round) {
      const Directions n = random_directions(rng, 0.2f), v = random_directions(rng, 0.1f);
      const LightRig rig = random_rig(rng, 3);
      const std::array<Float, 3> albedo = random_albedo(rng);
      LightingDesc lighting;
      lighting.model = model;
      const Float ao(0.375f);
      const SurfaceSample surface{albedo.data(), Float(0.5f), ao};
      // No lights: exactly albedo * ambient * ao.
      LightRig ambient_only = rig;
      ambient_only.directional.clear();
      Float color[3];
      shade_lights(n.batch, n.batch, v.batch, surface, nullptr, lighting.model, lighting_params(lighting), ambient_only, color);
      const float ambient[3] = {rig.ambient.x, rig.ambient.y, rig.ambient.z};
      for (int c = 0; c < 3; ++c) {
        const Float expected = albedo[std::size_t(c)] * (Float(ambient[c]) * ao) + Float(0.0f);
        EXPECT_TRUE(xsimd::all(color[c] == expected));
      }
      // Visibility 0 for the middle light: the bits of the rig without it (adding 0 * radiance changes nothing).
      const Float visibility[3] = {Float(1.0f), Float(0.0f), Float(1.0f)};
      LightRig two = rig;
      two.directional.erase(two.directional.begin() + 1);
      Float shadowed[3], removed[3];
      shade_lights(n.batch, n.batch, v.batch, surface, visibility, lighting.model, lighting_params(lighting), rig, shadowed);
      shade_lights(n.batch, n.batch, v.batch, surface, nullptr, lighting.model, lighting_params(lighting), two, removed);
      EXPECT_TRUE(same_bits(shadowed, removed)) << round;
    }
}

// The Cook-Torrance term of the header in double, from the same float inputs: pi D Vis F n.l, gated by the
// geometric normal.
double cook_torrance_reference(const glm::dvec3& n, const glm::dvec3& g, const glm::dvec3& v, const glm::dvec3& l,
                               double f0, double roughness) {
  if (glm::dot(g, l) <= 0.0) return 0.0;
  const glm::dvec3 h = glm::normalize(l + v);
  const double nl = std::max(glm::dot(n, l), 0.0), nv = std::max(glm::dot(n, v), 0.0);
  const double nh = std::max(glm::dot(n, h), 0.0), vh = std::max(glm::dot(v, h), 0.0);
  const double a2 = std::pow(roughness, 4.0);
  const double d = a2 / (std::numbers::pi * std::pow(nh * nh * (a2 - 1.0) + 1.0, 2.0));
  const double vis = 0.5 / (nl * std::sqrt(nv * nv * (1.0 - a2) + a2) + nv * std::sqrt(nl * nl * (1.0 - a2) + a2));
  const double f = f0 + (1.0 - f0) * std::pow(1.0 - vh, 5.0);
  return std::numbers::pi * d * vis * f * nl;
}

TEST(LightingModels, CookTorranceMatchesDoublePrecision) {
  std::mt19937 rng(3);
  const Float black[3] = {Float(0.0f), Float(0.0f), Float(0.0f)};
  for (float roughness : {0.5f, 0.75f, 1.0f})
    for (float f0 : {0.04f, 0.5f, 1.0f})
      for (int round = 0; round < 40; ++round) {
        // Normals, views and lights at least ~3 degrees above the shading plane: near grazing, the float and
        // double clamps of n.l and n.v to 0 decide differently and the comparison would test the clamp.
        const Directions n = random_directions(rng, 0.3f), v = random_directions(rng, 0.05f);
        LightRig rig;
        const glm::vec3 l = glm::normalize(glm::vec3(std::uniform_real_distribution<float>(-1, 1)(rng),
                                                     std::uniform_real_distribution<float>(-1, 1)(rng), 0.6f));
        rig.directional.push_back({l, {1.0f, 1.0f, 1.0f}});
        LightingDesc lighting;
        lighting.model = LightingModel::CookTorrance;
        lighting.roughness = roughness;
        const Vec3 up{Float(0.0f), Float(0.0f), Float(1.0f)};
        Float color[3];
        shade_lights(n.batch, up, v.batch, {black, Float(f0), Float(1.0f)}, nullptr, lighting.model, lighting_params(lighting), rig, color);
        const Lanes got = lanes(color[0]);
        for (int lane = 0; lane < simd::kLanes; ++lane) {
          const glm::dvec3 nd(n.lane[std::size_t(lane)]), vd(v.lane[std::size_t(lane)]), ld(l);
          if (glm::dot(nd, ld) < 0.05 || glm::dot(nd, vd) < 0.05) continue;
          const double expected = cook_torrance_reference(nd, {0, 0, 1}, vd, ld, f0, roughness);
          // fp32 dot products and the normalised half vector carry <= ~4 ulp (5e-7) absolute error. D amplifies
          // an error in n.h by |d ln D / d n.h| <= 4 / alpha^2 (alpha^2 = roughness^4 >= 1/16: <= 64); Vis, F
          // (5 (1 - v.h)^4 <= 5), the square roots and products add < 64 ulps of relative error (n.l, n.v >= 0.05).
          const double bound = (4.0 / std::pow(roughness, 4.0) + 64.0) * 5e-7;
          EXPECT_NEAR(got[std::size_t(lane)], expected, bound * expected + 1e-7)
              << roughness << " " << f0 << " " << round << " " << lane;
        }
      }
}

// White furnace for the specular lobe alone (F0 = 1, black albedo, no ambient): the directional albedo
// E = (1/pi) * integral over the light hemisphere of the shaded value (= pi f_spec n.l) is at most 1 and falls with
// roughness (single scattering loses the energy of multiple bounces, up to ~70 % here). Head-on at roughness 1
// (alpha = 1: pi D = 1, Vis = 0.5 / (n.l + 1)) it is integral_0^1 mu / (1 + mu) d mu * 2 = ... = 1 - ln 2 exactly.
TEST(LightingModels, CookTorranceWhiteFurnace) {
  const Float black[3] = {Float(0.0f), Float(0.0f), Float(0.0f)};
  const Vec3 up{Float(0.0f), Float(0.0f), Float(1.0f)};
  // Views at elevations 90 .. 10 degrees over the lanes.
  Lanes vx, vz;
  for (int l = 0; l < simd::kLanes; ++l) {
    const double elevation = (90.0 - 80.0 * l / (simd::kLanes - 1)) * std::numbers::pi / 180.0;
    vx[std::size_t(l)] = float(std::cos(elevation));
    vz[std::size_t(l)] = float(std::sin(elevation));
  }
  const Vec3 view{batch(vx), Float(0.0f), batch(vz)};
  LightingDesc lighting;
  lighting.model = LightingModel::CookTorrance;
  LightRig rig;
  rig.directional.push_back({{0.0f, 0.0f, 1.0f}, {1.0f, 1.0f, 1.0f}});
  // Midpoint rule in (cos theta, phi): d omega = d cos theta d phi. In double, refining this grid 4x per axis
  // changes E by < 3e-5 at roughness 0.5 (the sharpest lobe here) and 1 at 90 and 10 degrees; the fp32 terms
  // add ~1e-6 relative each. Tolerance 1e-3.
  const int steps_mu = 384, steps_phi = 192;
  std::vector<double> energy_before(simd::kLanes, 1.0);
  for (float roughness : {0.5f, 0.75f, 1.0f}) {
    lighting.roughness = roughness;
    std::vector<double> energy(simd::kLanes, 0.0);
    for (int a = 0; a < steps_mu; ++a)
      for (int b = 0; b < steps_phi; ++b) {
        const double mu = (a + 0.5) / steps_mu, phi = 2 * std::numbers::pi * (b + 0.5) / steps_phi;
        const double sine = std::sqrt(1.0 - mu * mu);
        rig.directional[0].direction = {float(sine * std::cos(phi)), float(sine * std::sin(phi)), float(mu)};
        Float color[3];
        shade_lights(up, up, view, {black, Float(1.0f), Float(1.0f)}, nullptr, lighting.model, lighting_params(lighting), rig, color);
        const Lanes c = lanes(color[0]);
        for (int l = 0; l < simd::kLanes; ++l) energy[std::size_t(l)] += double(c[std::size_t(l)]);
      }
    for (int l = 0; l < simd::kLanes; ++l) {
      const double e = energy[std::size_t(l)] * (1.0 / steps_mu) * (2.0 / steps_phi);
      EXPECT_LE(e, energy_before[std::size_t(l)] + 1e-3) << roughness << " " << l;  // <= 1, then falling
      energy_before[std::size_t(l)] = e;
    }
    if (roughness == 1.0f) {
      EXPECT_NEAR(energy_before[0], 1.0 - std::log(2.0), 1e-3);
    }
    if (roughness == 0.5f) {
      EXPECT_NEAR(energy_before[0], 0.91581, 1e-3);  // head-on, the double quadrature on a 4x finer grid
    }
  }
}

TEST(LightingModels, SpecularFromAlbedo) {
  std::mt19937 rng(8);
  SpecularFromAlbedo coeffs;
  const std::array<Float, 3> albedo = random_albedo(rng);
  EXPECT_TRUE(xsimd::all(specular_from_albedo(albedo.data(), coeffs, 0.3f) == Float(0.3f)));  // disabled
  coeffs.enabled = true;
  for (float power : {0.5f, 1.0f, 2.5f, 4.0f})
    for (bool invert : {false, true})
      for (int round = 0; round < 20; ++round) {
        coeffs.power = power;
        coeffs.invert = invert;
        coeffs.scale = 0.7f;
        const std::array<Float, 3> a = random_albedo(rng);
        const Lanes got = lanes(specular_from_albedo(a.data(), coeffs, 0.3f));
        const Lanes r = lanes(a[0]), g = lanes(a[1]), b = lanes(a[2]);
        for (int l = 0; l < simd::kLanes; ++l) {
          const std::size_t k = std::size_t(l);
          const double luminance = 0.2126 * r[k] + 0.7152 * g[k] + 0.0722 * b[k];
          const double x = invert ? 1.0 - luminance : luminance;
          const double expected = 0.7 * std::pow(x, double(power));
          // detmath::pow (powers 0.5, 2.5): log2 within 2e-7 absolute, times power <= 4, and exp2 within 3e-7
          // relative (~1.1e-6); pow_whole (powers 1, 4): 3 roundings (1.8e-7);
          // the fp32 luminance (3 products, 2 sums: <= 4 ulp = 5e-7 relative) raised to power <= 4 (2e-6).
          // For x near 0 after inversion the relative rounding of 1 - luminance grows: an absolute 1e-6 covers it.
          EXPECT_NEAR(got[k], expected, 4e-6 * expected + 1e-6) << power << invert << l;
        }
      }
  // Luminance clamps to [0, 1]; x = 0 gives 0 for any power.
  coeffs.power = 2.0f;
  coeffs.scale = 0.5f;
  coeffs.invert = false;
  const Float bright[3] = {Float(3.0f), Float(3.0f), Float(3.0f)};
  EXPECT_TRUE(xsimd::all(specular_from_albedo(bright, coeffs, 0.0f) == Float(0.5f)));
  coeffs.invert = true;
  EXPECT_TRUE(xsimd::all(specular_from_albedo(bright, coeffs, 0.0f) == Float(0.0f)));
}

}  // namespace
}  // namespace qdmr::shading
