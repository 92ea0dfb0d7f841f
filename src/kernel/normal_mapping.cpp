#include "kernel/normal_mapping.hpp"

#include "kernel/lighting_models.hpp"
#include "kernel/shading_math.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

using namespace shading;

// One batch's texture samples: albedo and the tangent-space normal at the batch's UVs (and the ORM texture's).
struct NormalMappingProgram::Samples {
  Float albedo[4], tangent_normal[4], orm[4];
};

UvDerivatives NormalMappingProgram::derivatives(const Fragments& in) const {
  return UvDerivatives::from(in.varyings[kU], in.varyings[kV], lod_mode_);
}

// Whether the albedo map is magnified in every lane of the batch and no bias can lift it: each lane's footprint
// is at most one texel (rho² ≤ 1, where lod_from_derivatives gives at most 0) and the material's LOD bias is at
// most 0. The sampler then reads level 0 of both maps whatever the exact LOD (sample_levels clamps any LOD plus
// bias of at most 0 to level 0, and the LOD is read by nothing else here), so 0 serves, without the logarithm's
// chain of dependent operations.
bool NormalMappingProgram::magnified(const UvDerivatives& d) const {
  const TextureSampler& albedo = textures_.first();
  if (albedo.state().lod_bias > 0.0f) return false;
  Float px, py;
  footprint_lengths2(albedo.view(), d.dudx, d.dvdx, d.dudy, d.dvdy, px, py);
  // NaN or infinite footprints fail the test (and go to lod_from_derivatives).
  return xsimd::all((px <= Float(1.0f)) & (py <= Float(1.0f)));
}

Float NormalMappingProgram::albedo_lod(const UvDerivatives& d) const {
  if (magnified(d)) return Float(0.0f);
  return textures_.first().lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
}

// Two batches' LODs. Per quad, a quad's derivatives are the same in its four lanes, so one evaluation serves
// both batches: each quad's top lanes carry a's derivatives and its bottom lanes b's, and each batch takes its LOD
// back from its own lanes (the computation is lane by lane: the bits are those of two evaluations).
void NormalMappingProgram::albedo_lods(const UvDerivatives& da, const UvDerivatives& db, Float& lod_a,
                                       Float& lod_b) const {
  if (magnified(da) && magnified(db)) {
    lod_a = lod_b = Float(0.0f);
    return;
  }
  if (lod_mode_ != LodMode::PerQuad) {
    lod_a = albedo_lod(da);
    lod_b = albedo_lod(db);
    return;
  }
  const simd::Mask b_lanes = simd::from_bits(0xccccccccu);  // lanes 2 and 3 of every quad
  const auto pick = [&](const Float& of_a, const Float& of_b) { return xsimd::select(b_lanes, of_b, of_a); };
  const Float both = textures_.first().lod(pick(da.dudx, db.dudx), pick(da.dvdx, db.dvdx), pick(da.dudy, db.dudy),
                                           pick(da.dvdy, db.dvdy));
  lod_a = simd::from_quad_corners<0, 0, 0, 0>(both);
  lod_b = simd::from_quad_corners<2, 2, 2, 2>(both);
}

Float NormalMappingProgram::normal_lod(const UvDerivatives& d, const Float& albedo_lod) const {
  if (textures_.second().same_lod_as(textures_.first())) return albedo_lod;
  return textures_.second().lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
}

Float NormalMappingProgram::orm_lod(const UvDerivatives& d, const Float& albedo_lod) const {
  if (orm_->same_lod_as(textures_.first())) return albedo_lod;
  return orm_->lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
}

template <bool Orm>
void NormalMappingProgram::sample(const Fragments& in, const UvDerivatives& d, const Float& albedo_lod,
                                  Samples& out) const {
  const UvAhead ahead = d.quad_below();
  textures_.sample(in.varyings[kU], in.varyings[kV], albedo_lod, normal_lod(d, albedo_lod), out.albedo,
                   out.tangent_normal, &ahead);
  if constexpr (Orm) orm_->sample(in.varyings[kU], in.varyings[kV], orm_lod(d, albedo_lod), out.orm);
}

namespace {

// The tangent-space normal (an RGB sample in [0, 1]) to world space, unit length.
Vec3 shading_normal_of(const TangentFrame& frame, const Float* tangent_normal) {
  return normalize(frame.to_world({tangent_normal[0] * Float(2.0f) - Float(1.0f), tangent_normal[1] * Float(2.0f) - Float(1.0f),
                                   tangent_normal[2] * Float(2.0f) - Float(1.0f)}));
}

}  // namespace

template <bool Orm>
void NormalMappingProgram::light(const Fragments& in, const Samples& s, const TangentFrame& frame,
                                 const Vec3& shading_normal, const Vec3& view, ShadeOutput& out) const {
  const Float specular = specular_from_albedo(s.albedo, specular_, lighting_.specular);
  if constexpr (Orm) {
    const OrmSurface orm = apply_orm(s.orm, orm_params_, lighting_.roughness, s.albedo, specular);
    shade_lights(shading_normal, frame.n, view, SurfaceSample{orm.albedo, orm.specular, orm.occlusion, &orm.roughness},
                 nullptr, lighting_model_, lighting_, lights_, out.color);
    out.ao = orm.occlusion;
  } else {
    shade_lights(shading_normal, frame.n, view, SurfaceSample{s.albedo, specular, Float(1.0f)}, nullptr,
                 lighting_model_, lighting_, lights_, out.color);
    out.ao = Float(1.0f);  // no AO
  }
  out.normal[0] = shading_normal.x;
  out.normal[1] = shading_normal.y;
  out.normal[2] = shading_normal.z;
  out.iterations = out.hit_depth = out.error_texels = out.missed = Float(0.0f);
  out.shadow = Float(1.0f);  // no self-shadowing
  out.hit_u = in.varyings[kU];
  out.hit_v = in.varyings[kV];
}

void NormalMappingProgram::shade(const Fragments* const* in, ShadeOutput* const* out, int n) const {
  if (orm_)
    shade_batches<true>(in, out, n);
  else
    shade_batches<false>(in, out, n);
}

template <bool Orm>
void NormalMappingProgram::shade_batches(const Fragments* const* in, ShadeOutput* const* out, int n) const {
  int k = 0;
  for (; k + 1 < n; k += 2) shade_pair<Orm>(*in[k], *out[k], *in[k + 1], *out[k + 1]);
  if (k < n) shade_batch<Orm>(*in[k], *out[k]);
}

template <bool Orm>
void NormalMappingProgram::shade_batch(const Fragments& in, ShadeOutput& out) const {
  Samples s;
  const UvDerivatives d = derivatives(in);
  sample<Orm>(in, d, albedo_lod(d), s);
  const TangentFrame frame = TangentFrame::from(in);
  light<Orm>(in, s, frame, shading_normal_of(frame, s.tangent_normal), view_vector(in, lights_), out);
}

// Stage by stage, a's and b's work side by side: each stage of one batch is a chain of dependent operations
// (derivatives, LOD, the sample's addresses, its loads, the filter), and the other batch's same stage next to it
// gives the core independent work to overlap with it. Sparse batches whose covered lanes fit in one run packed
// (shade_packed).
template <bool Orm>
void NormalMappingProgram::shade_pair(const Fragments& a, ShadeOutput& out_a, const Fragments& b,
                                      ShadeOutput& out_b) const {
  const UvDerivatives da = derivatives(a), db = derivatives(b);
  Float lod_a, lod_b;
  albedo_lods(da, db, lod_a, lod_b);
  const std::uint32_t covered_a = simd::to_bits(a.covered), covered_b = simd::to_bits(b.covered);
  if (simd::LanePacking::fits(covered_a, covered_b)) {
    shade_packed<Orm>(a, da, lod_a, out_a, b, db, lod_b, out_b, simd::LanePacking(covered_a, covered_b));
    return;
  }
  Samples sa, sb;
  // Each frame is a chain of three normalisations (a square root, then a division, each), and the shading normal
  // one more: a's and b's side by side, so one chain's arithmetic fills the other's waits. The frames and view
  // vectors need no sample: made while the LOD's chain (a logarithm after a division) is under way.
  const TangentFrame frame_a = TangentFrame::from(a), frame_b = TangentFrame::from(b);
  const Vec3 view_a = view_vector(a, lights_), view_b = view_vector(b, lights_);
  sample<Orm>(a, da, lod_a, sa);
  sample<Orm>(b, db, lod_b, sb);
  const Vec3 normal_a = shading_normal_of(frame_a, sa.tangent_normal), normal_b = shading_normal_of(frame_b, sb.tangent_normal);
  light<Orm>(a, sa, frame_a, normal_a, view_a, out_a);
  light<Orm>(b, sb, frame_b, normal_b, view_b, out_b);
}

// Past the LODs (which read whole quads) everything is lane by lane: the covered lanes of both batches run as one
// batch, and each batch's outputs are its own lanes back (the others are never written).
template <bool Orm>
void NormalMappingProgram::shade_packed(const Fragments& a, const UvDerivatives& da, const Float& lod_a,
                                        ShadeOutput& out_a, const Fragments& b, const UvDerivatives& db,
                                        const Float& lod_b, ShadeOutput& out_b, const simd::LanePacking& packing) const {
  Fragments packed;
  for (int k = 0; k < kBaseVaryingCount; ++k) packed.varyings[k] = packing.pack(a.varyings[k], b.varyings[k]);
  const UvAhead ahead_a = da.quad_below(), ahead_b = db.quad_below();
  const UvAhead ahead{packing.pack(ahead_a.du, ahead_b.du), packing.pack(ahead_a.dv, ahead_b.dv)};
  Samples s;
  textures_.sample(packed.varyings[kU], packed.varyings[kV], packing.pack(lod_a, lod_b),
                   packing.pack(normal_lod(da, lod_a), normal_lod(db, lod_b)), s.albedo, s.tangent_normal, &ahead);
  if constexpr (Orm)
    orm_->sample(packed.varyings[kU], packed.varyings[kV], packing.pack(orm_lod(da, lod_a), orm_lod(db, lod_b)), s.orm);
  const TangentFrame frame = TangentFrame::from(packed);
  ShadeOutput lit;
  light<Orm>(packed, s, frame, shading_normal_of(frame, s.tangent_normal), view_vector(packed, lights_), lit);
  const auto unpack = [&](const Fragments& in, ShadeOutput& out, auto lanes) {
    out = lit;
    for (int c = 0; c < 3; ++c) {
      out.color[c] = lanes(lit.color[c]);
      out.normal[c] = lanes(lit.normal[c]);
    }
    if constexpr (Orm) out.ao = lanes(lit.ao);
    out.hit_u = in.varyings[kU];
    out.hit_v = in.varyings[kV];
  };
  unpack(a, out_a, [&](const Float& v) { return packing.first(v); });
  unpack(b, out_b, [&](const Float& v) { return packing.second(v); });
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
