#pragma once
// Runs a displacement technique on chosen rays: each lane gets its own UV origin and UV-space direction on a
// flat tangent frame (t = +x, b = +y, n = +z), with the camera placed along the view ray.
#include <array>
#include <vector>

#include "qdmr/study/reference.hpp"
#include "qdmr/texture/height_texture.hpp"
#include "shade/displacement.hpp"

namespace qdmr::test {

struct TechniqueRay {
  double u0, v0, du, dv;  // uv(s) = uv0 + (du, dv) * s
};

struct TechniqueResult {
  double hit_u, hit_v, hit_depth, iterations;
};

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
  }

  const HeightField& field() const { return field_; }
  void set_math(MathMode math) { material_.sampling.math = math; }

  std::vector<TechniqueResult> run(const std::vector<TechniqueRay>& rays) const {
    DisplacementInputs inputs;
    inputs.albedo = &flat_;
    inputs.normal = &flat_;
    inputs.height = &height_;
    inputs.height_max = &height_max_;
    std::vector<TechniqueResult> results;
    for (std::size_t first = 0; first < rays.size(); first += simd::kLanes) {
      LightRig rig;
      // One camera per batch is not enough for per-lane directions: the view vector is built from world
      // positions instead, each lane's world point sitting at -direction from a camera at the origin.
      rig.camera_position = glm::vec3(0.0f);
      DisplacementProgram program(inputs, material_, rig);
      alignas(64) float var[kVaryingCount][simd::kLanes] = {};
      std::uint32_t covered = 0;
      for (int l = 0; l < simd::kLanes; ++l) {
        const TechniqueRay& r = rays[std::min(first + std::size_t(l), rays.size() - 1)];
        if (first + std::size_t(l) < rays.size()) covered |= 1u << l;
        // View vector (towards the camera) in tangent space: (-du, -dv, 1), normalised by the program.
        var[kWorldX][l] = float(r.du) * 10.0f;
        var[kWorldY][l] = float(r.dv) * 10.0f;
        var[kWorldZ][l] = -10.0f;
        var[kNormalZ][l] = 1.0f;
        var[kTangentX][l] = 1.0f;
        var[kTangentW][l] = 1.0f;
        var[kU][l] = float(r.u0);
        var[kV][l] = float(r.v0);
      }
      Fragments in;
      for (int k = 0; k < kVaryingCount; ++k) in.varyings[k] = simd::Float::load_aligned(var[k]);
      in.pixel_x = in.pixel_y = simd::Float(0.0f);
      in.view_depth = simd::Float(10.0f);
      in.covered = simd::from_bits(covered);
      ShadeOutput out;
      program.shade(in, out);
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

private:
  Texture height_, height_max_, flat_;
  MaterialDesc material_;
  HeightField field_;
};

}  // namespace qdmr::test
