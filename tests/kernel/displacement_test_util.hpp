#pragma once
// Runs a displacement technique on chosen rays: each lane gets its own UV origin and UV-space direction on a
// flat tangent frame (t = +x, b = +y, n = +z), with the camera placed along the view ray.
#include <array>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/reference/reference.hpp"
#include "texture/height_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "kernel/displacement.hpp"
#include "support/test_support.hpp"
#include "plan/program_choice.hpp"

namespace qdmr::test {

struct TechniqueRay {
  double u0, v0, du, dv;  // uv(s) = uv0 + (du, dv) * s
};

struct TechniqueResult {
  double hit_u, hit_v, hit_depth, iterations;
};

// Height fields and rays the technique tests share.
inline Image pattern(ProceduralPattern kind, int size, int cells) {
  ProceduralDesc p;
  p.pattern = kind;
  p.size = size;
  p.cells = cells;
  return generate_procedural(p);
}

inline Image filled(int size, float value) {
  Image img(size, size, 1);
  for (float& t : img.texels) t = value;
  return img;
}

// One-texel features: a pillar (one texel at 1 on a floor at 0) and a slit (one texel column at 0 in a plateau at 1).
inline Image pillar(int size) {
  Image img = filled(size, 0.0f);
  img.at(size / 2, size / 2, 0) = 1.0f;
  return img;
}
inline Image slit(int size) {
  Image img = filled(size, 1.0f);
  for (int y = 0; y < size; ++y) img.at(size / 2, y, 0) = 0.0f;
  return img;
}

struct Field {
  const char* name;
  Image heights;
};

inline std::vector<Field> fields() {
  return {{"flat", filled(32, 0.5f)},
          {"steps", pattern(ProceduralPattern::Steps, 64, 8)},
          {"sine", pattern(ProceduralPattern::Sine, 64, 3)},
          {"spikes", pattern(ProceduralPattern::Spikes, 64, 4)},
          {"checker", pattern(ProceduralPattern::Checker, 32, 32)},  // alternates at the finest level
          {"pillar", pillar(32)},
          {"slit", slit(32)}};
}

// Rays from 90 down to 1 degree above the surface, all around, from deterministic random origins.
inline std::vector<TechniqueRay> rays(int per_angle, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<TechniqueRay> out;
  for (double elevation : {90.0, 60.0, 30.0, 10.0, 3.0, 1.0})
    for (int i = 0; i < per_angle; ++i) {
      const double azimuth = 2.0 * std::numbers::pi * unit(rng);
      const double reach = elevation == 90.0 ? 0.0 : 1.0 / std::tan(elevation * std::numbers::pi / 180.0);
      out.push_back({unit(rng), unit(rng), reach * std::cos(azimuth), reach * std::sin(azimuth)});
    }
  return out;
}

// Distance in level-0 texels between a technique's hit and the reference's.
inline double error_texels(const HeightField& f, const TechniqueResult& r, const ReferenceHit& ref) {
  return std::hypot((r.hit_u - ref.point.x) * f.width, (r.hit_v - ref.point.y) * f.height);
}

// Points QDMR_CACHE_DIR (where renders keep cone maps) at a temporary folder while it lives, so tests that
// render csm or rcsm never touch the user's cache.
class TemporaryConeCache {
public:
  TemporaryConeCache() {
    if (const char* v = std::getenv("QDMR_CACHE_DIR")) previous_ = v;
    ::setenv("QDMR_CACHE_DIR", dir_.path().c_str(), 1);
  }
  ~TemporaryConeCache() {
    if (previous_)
      ::setenv("QDMR_CACHE_DIR", previous_->c_str(), 1);
    else
      ::unsetenv("QDMR_CACHE_DIR");
  }
  TemporaryConeCache(const TemporaryConeCache&) = delete;
  TemporaryConeCache& operator=(const TemporaryConeCache&) = delete;

private:
  TempDir dir_;
  std::optional<std::string> previous_;
};

// Runs `program` on per-lane rays on a flat tangent frame (t = +x, b = +y, n = +z): each lane's world point
// sits at -direction * 10 from a camera at the origin, so the view vector in tangent space is (-du, -dv, 1).
// weights: per ray, the interpolated vertex blend weights (programs that blend per vertex), or empty.
inline std::vector<TechniqueResult> trace_rays(const DisplacementProgram& program, const std::vector<TechniqueRay>& rays,
                                               const std::vector<std::array<float, 4>>& weights = {}) {
  std::vector<TechniqueResult> results;
  for (std::size_t first = 0; first < rays.size(); first += simd::kLanes) {
    alignas(64) float var[kVaryingCount][simd::kLanes] = {};
    std::uint32_t covered = 0;
    for (int l = 0; l < simd::kLanes; ++l) {
      const std::size_t k = std::min(first + std::size_t(l), rays.size() - 1);
      const TechniqueRay& r = rays[k];
      if (first + std::size_t(l) < rays.size()) covered |= 1u << l;
      var[kWorldX][l] = float(r.du) * 10.0f;
      var[kWorldY][l] = float(r.dv) * 10.0f;
      var[kWorldZ][l] = -10.0f;
      var[kNormalZ][l] = 1.0f;
      var[kTangentX][l] = 1.0f;
      var[kTangentW][l] = 1.0f;
      var[kU][l] = float(r.u0);
      var[kV][l] = float(r.v0);
      if (!weights.empty())
        for (int i = 0; i < 4; ++i) var[kWeight0 + i][l] = weights[k][std::size_t(i)];
    }
    Fragments in;
    for (int k = 0; k < kVaryingCount; ++k) in.varyings[k] = simd::Float::load_aligned(var[k]);
    in.pixel_x = in.pixel_y = simd::Float(0.0f);
    in.view_depth = simd::Float(10.0f);
    in.covered = simd::from_bits(covered);
    ShadeOutput out;
    program.shade_one(in, out);
    alignas(64) float hu[simd::kLanes], hv[simd::kLanes], hd[simd::kLanes], it[simd::kLanes];
    out.hit_u.store_aligned(hu);
    out.hit_v.store_aligned(hv);
    out.hit_depth.store_aligned(hd);
    out.iterations.store_aligned(it);
    for (int l = 0; l < simd::kLanes && first + std::size_t(l) < rays.size(); ++l)
      results.push_back({hu[l], hv[l], hd[l], it[l]});
  }
  return results;
}

class TechniqueHarness {
public:
  // heights: level 0 of a power-of-two height map in [0,1], stored R32F so the technique and the reference
  // see exactly the same values.
  TechniqueHarness(const Image& heights, const TechniqueDesc& technique, Filter filter = Filter::Bilinear)
      : height_(make_mip_texture(heights, TexelFormat::R32F, false, MipReduce::Box)),
        height_max_(make_mip_texture(heights, TexelFormat::R32F, false, MipReduce::Max)),
        flat_(make_mip_texture(Image(1, 1, 4), TexelFormat::RGBA8, false, MipReduce::Box)) {
    material_.technique = technique;
    material_.sampling.filter = filter;
    material_.layers.resize(1);
    field_.width = heights.width;
    field_.height = heights.height;
    field_.h.assign(heights.texels.begin(), heights.texels.end());
    // csm, rcsm: the exact cones of these heights, baked here (never through the user's cache).
    if (technique.kind == TechniqueKind::Csm || technique.kind == TechniqueKind::Rcsm)
      cones_ = bake_cone_map(field_, technique.kind == TechniqueKind::Csm ? ConeKind::Conservative : ConeKind::Relaxed);
    // qdm with bilinear patches walks the quadtree of the 3x3 maxima, as prepare_assets builds it.
    if (technique.refinement == QdmRefinement::BilinearPatch)
      height_max_ = make_mip_texture(bilinear_upper_bound(field_), TexelFormat::R32F, false, MipReduce::Max);
  }

  const HeightField& field() const { return field_; }
  void set_math(MathMode math) { material_.sampling.math = math; }

  std::vector<TechniqueResult> run(const std::vector<TechniqueRay>& rays) const {
    DisplacementInputs inputs;
    inputs.layers.push_back({&flat_, &flat_, &height_, &height_max_});
    if (!cones_.ratio.empty()) inputs.cones = &cones_;
    if (material_.technique.refinement == QdmRefinement::BilinearPatch) inputs.surface = &field_;
    // One camera per batch is not enough for per-lane directions: the view vector is built from world
    // positions instead (see trace_rays).
    LightRig rig;
    rig.camera_position = glm::vec3(0.0f);
    return trace_rays(DisplacementProgram(inputs, program_key(material_), program_params(material_), rig), rays);
  }

private:
  Texture height_, height_max_, flat_;
  MaterialDesc material_;
  HeightField field_;
  ConeMap cones_;
};

}  // namespace qdmr::test
