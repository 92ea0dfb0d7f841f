#include "kernel/normal_mapping.hpp"

#include <type_traits>

#include "kernel/batch_scheduler.hpp"
#include "kernel/lighting_models.hpp"
#include "kernel/shading_math.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

using namespace shading;

// One batch's texture samples: albedo and the tangent-space normal at the batch's UVs (and the ORM texture's).
struct NormalMappingProgram::Samples {
  Float albedo[4], tangent_normal[4], orm[4];
};

[[gnu::always_inline]] inline UvDerivatives NormalMappingProgram::derivatives(const Fragments& in) const {
  return UvDerivatives::from(in.varyings[kU], in.varyings[kV], lod_mode_);
}

// Whether the albedo map is magnified in every lane of the batch and no bias can lift it: each lane's footprint
// is at most one texel (rho² ≤ 1, where lod_from_derivatives gives at most 0) and the material's LOD bias is at
// most 0. The sampler then reads level 0 of both maps whatever the exact LOD (sample_levels clamps any LOD plus
// bias of at most 0 to level 0, and the LOD is read by nothing else here), so 0 serves, without the logarithm's
// chain of dependent operations.
[[gnu::always_inline]] inline bool NormalMappingProgram::magnified(const UvDerivatives& d) const {
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

[[gnu::always_inline]] inline Float NormalMappingProgram::normal_lod(const UvDerivatives& d, const Float& albedo_lod) const {
  if (textures_.second().same_lod_as(textures_.first())) return albedo_lod;
  return textures_.second().lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
}

[[gnu::always_inline]] inline Float NormalMappingProgram::orm_lod(const UvDerivatives& d, const Float& albedo_lod) const {
  if (orm_->same_lod_as(textures_.first())) return albedo_lod;
  return orm_->lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
}

namespace {

// The tangent-space normal (an RGB sample in [0, 1]) to world space, unit length.
[[gnu::always_inline]] inline Vec3 shading_normal_of(const TangentFrame& frame, const Float* tangent_normal) {
  return normalize(frame.to_world({tangent_normal[0] * Float(2.0f) - Float(1.0f), tangent_normal[1] * Float(2.0f) - Float(1.0f),
                                   tangent_normal[2] * Float(2.0f) - Float(1.0f)}));
}

}  // namespace

template <bool Orm>
void NormalMappingProgram::light(const Samples& s, const TangentFrame& frame, const Vec3& shading_normal,
                                 const Vec3& view, ShadeOutput& out) const {
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
}

// Normal mapping's stages, as shade_in_stages calls them (batch_scheduler.hpp): the surface is the polygon's, so
// there is nothing to trace. A pair's LODs are evaluated together (setup_pair), and a pair whose covered lanes fit
// in one batch samples and lights once (small triangles: a 1 M-triangle grid averages 5.6 covered lanes of 16).
template <bool Orm>
class NormalMappingProgram::Stages {
public:
  static constexpr PackLanes kPackLanes = PackLanes::Pairs;
  // What reads whole quads: the LODs (the ORM texture's with Orm) and the samples' prefetch hint.
  struct NoOrm {};
  struct Setup {
    Float lod, normal_lod;
    [[no_unique_address]] std::conditional_t<Orm, Float, NoOrm> orm_lod;  // the ORM texture's, with one
    UvAhead ahead;

    template <class F>
    static constexpr void values(F&& f) {
      f([](auto& s) -> auto& { return s.lod; });
      f([](auto& s) -> auto& { return s.normal_lod; });
      if constexpr (Orm) f([](auto& s) -> auto& { return s.orm_lod; });
      f([](auto& s) -> auto& { return s.ahead.du; });
      f([](auto& s) -> auto& { return s.ahead.dv; });
    }
  };
  // The polygon at the batch's lanes: its frame, the view vector and the UVs.
  struct Surface {
    TangentFrame frame;
    Vec3 view;
    Float u, v;
  };
  struct Hit {};
  using AtHit = Samples;

  explicit Stages(const NormalMappingProgram& program) : p_(program) {}

  Setup setup(const Fragments& in) const {
    const UvDerivatives d = p_.derivatives(in);
    Setup setup;
    fill(d, p_.albedo_lod(d), setup);
    return setup;
  }
  // Per quad, a quad's derivatives are the same in its four lanes: one LOD evaluation serves both batches
  // (albedo_lods).
  void setup_pair(const Fragments& a, const Fragments& b, Setup& setup_a, Setup& setup_b) const {
    const UvDerivatives da = p_.derivatives(a), db = p_.derivatives(b);
    Float lod_a, lod_b;
    p_.albedo_lods(da, db, lod_a, lod_b);
    fill(da, lod_a, setup_a);
    fill(db, lod_b, setup_b);
  }

  // The frame is a chain of three normalisations (a square root, then a division, each) that needs no sample: a
  // pair's two side by side, while the LODs' chains (a logarithm after a division) are under way.
  Surface surface(const Fragments& in, const Setup&) const {
    return {TangentFrame::from(in), view_vector(in, p_.lights_), in.varyings[kU], in.varyings[kV]};
  }
  Hit trace(const Surface&, const Setup&) const { return {}; }

  Samples surface_at_hit(const Setup& setup, const Surface& surface, const Hit&) const {
    Samples s;
    p_.textures_.sample(surface.u, surface.v, setup.lod, setup.normal_lod, s.albedo, s.tangent_normal, &setup.ahead);
    if constexpr (Orm) p_.orm_->sample(surface.u, surface.v, setup.orm_lod, s.orm);
    return s;
  }

  void light(const Fragments&, const Setup&, const Surface& surface, const Samples& s, ShadeOutput& out) const {
    p_.light<Orm>(s, surface.frame, shading_normal_of(surface.frame, s.tangent_normal), surface.view, out);
  }

  // The hit is the polygon's own UV.
  void finish(const Fragments& in, const Setup&, ShadeOutput& out) const {
    out.hit_u = in.varyings[kU];
    out.hit_v = in.varyings[kV];
  }

  // Of the inputs, what the surface reads: every varying but the blend weights (none here).
  template <class F>
  void lane_inputs(F&& f) const {
    for (int j = 0; j < kBaseVaryingCount; ++j) f([j](auto& in) -> auto& { return in.varyings[j]; });
  }
  // What light writes that differs between lanes (the rest is the same in every lane).
  template <class F>
  static void output_values(F&& f) {
    for (int c = 0; c < 3; ++c) f([c](auto& o) -> auto& { return o.color[c]; });
    for (int c = 0; c < 3; ++c) f([c](auto& o) -> auto& { return o.normal[c]; });
    if constexpr (Orm) f([](auto& o) -> auto& { return o.ao; });
  }

private:
  // Member by member: a whole Setup returned and assigned was copied through general registers.
  void fill(const UvDerivatives& d, const Float& lod, Setup& setup) const {
    setup.lod = lod;
    setup.normal_lod = p_.normal_lod(d, lod);
    if constexpr (Orm) setup.orm_lod = p_.orm_lod(d, lod);
    const UvAhead ahead = d.quad_below();
    setup.ahead.du = ahead.du;
    setup.ahead.dv = ahead.dv;
  }

  const NormalMappingProgram& p_;
};

void NormalMappingProgram::shade(const Fragments* const* in, ShadeOutput* const* out, int n) const {
  if (orm_)
    shade_in_stages(Stages<true>(*this), in, out, n);
  else
    shade_in_stages(Stages<false>(*this), in, out, n);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
