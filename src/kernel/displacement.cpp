#include "kernel/displacement.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <type_traits>

#include "kernel/batch_scheduler.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/reference/reference.hpp"
#include "qdmr/reference/reference_memo.hpp"
#include "qdmr/core/limits.hpp"
#include "kernel/ambient_occlusion.hpp"
#include "kernel/self_shadow.hpp"
#include "kernel/shading_math.hpp"
#include "kernel/cone_step.hpp"
#include "kernel/pom.hpp"
#include "kernel/qdm.hpp"
#include "kernel/refine.hpp"
#include "kernel/relief.hpp"
#include "kernel/traversal.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using namespace shading;
using simd::Int;
using simd::IntMask;
using simd::kLanes;
using simd::Mask;

using simd::count;
using simd::float_mask;
using simd::int_mask;

// The key of the program that runs: the trace options of the instantiation selected, which name it as the plan
// does (a test checks that the two agree).
ProgramKey with_trace(ProgramKey key, const TraceOptions& ran) {
  key.trace = ran;
  return key;
}

}  // namespace

DisplacementProgram::DisplacementProgram(const DisplacementInputs& inputs, const ProgramKey& key,
                                         const ProgramParams& params, const LightRig& lights)
    : DisplacementProgram(inputs, key, params, lights, select(key.trace)) {}

DisplacementProgram::DisplacementProgram(const DisplacementInputs& inputs, const ProgramKey& key,
                                         const ProgramParams& params, const LightRig& lights, const Variant& variant)
    : ShadingProgram(variant_name(with_trace(key, variant.options)),
                     inputs.layers.size() > 1 && key.weights == WeightMode::Vertex ? kWeight0 + int(inputs.layers.size())
                                                                                   : kBaseVaryingCount),
      shade_(variant.shade), cones_(inputs.cones),
      reference_(inputs.reference), reference_scale_(inputs.reference_scale), reference_memo_(inputs.reference_memo),
      reference_id_(inputs.reference_id), surface_(inputs.surface), sampler_(SamplerState::from(key.sampler, params.sampler)),
      key_(key), trace_(params.trace), lighting_(params.lighting),
      orm_params_(params.orm), blend_(params.blend), shadow_(params.shadow), ao_(params.ao), lights_(lights) {
  if (inputs.layers.empty() || inputs.layers.size() > std::size_t(BlendedSurface::kMaxLayers))
    throw Error("displacement program", "needs 1 to 4 layers");
  if (key.orm != (inputs.layers.size() == 1 && inputs.layers[0].orm != nullptr))
    throw Error("displacement program", "an orm texture needs the key's orm and one layer");
  SamplerState ao_sampler = sampler_;
  ao_sampler.filter = Filter::Bilinear;
  for (std::size_t i = 0; i < inputs.layers.size(); ++i) {
    const LayerInputs& l = inputs.layers[i];
    Layer layer{TwinSampler(*l.albedo, *l.normal, sampler_, l.twin_texels), std::nullopt, std::nullopt,
                i < params.specular.size() ? params.specular[i] : SpecularFromAlbedo{}, std::nullopt};
    if (l.height) layer.height.emplace(*l.height, l.height_max, sampler_, key_.sampler.heights);
    if (l.ao) layer.ao.emplace(*l.ao, ao_sampler);
    if (l.orm) layer.orm.emplace(*l.orm, sampler_);
    layers_.push_back(std::move(layer));
  }
  if (inputs.blend_ao) {
    blend_ao_.emplace(*inputs.blend_ao, ao_sampler);
    blend_ao_scale_ = inputs.blend_ao_scale;
  }
  if (key_.ao == AoMode::Baked && !blend_ao_ &&
      std::any_of(layers_.begin(), layers_.end(), [](const Layer& l) { return !l.ao; }))
    throw Error("displacement program", "baked AO needs an AO map per layer or one of the blend");
  if (inputs.weights) weights_.emplace(*inputs.weights, weight_sampler_state(sampler_));
  if (inputs.combined) {
    combined_.emplace(*inputs.combined, sampler_);
    combined_period_u_ = inputs.combined_period_u;
    combined_period_v_ = inputs.combined_period_v;
    layer_heights_ = inputs.layer_heights;
    if (layer_heights_ != nullptr) box_values_ = inputs.box_values;
  }
  if (layers_.size() > 1 && key_.weights == WeightMode::Pixel && !weights_)
    throw Error("displacement program", "per-pixel blending needs a weight texture");
  const Texture* height0 = inputs.layers[0].height;
  if (cones_ && (!height0 || cones_->width != height0->width() || cones_->height != height0->height()))
    throw Error("cone map", "needs the height map it was baked from (same level-0 size)");
}

SingleLayerSurface DisplacementProgram::layer_surface(int i) const {
  const Layer& l = layers_[std::size_t(i)];
  return SingleLayerSurface(*l.height);
}

// The hit in world space: the UV offset through dP/du and dP/dv (from the quad derivatives of the world
// position and the UVs), the depth along -n scaled by sqrt(|dP/du| |dP/dv|) world units per UV unit; then its
// window depth through the camera's view-projection.
void DisplacementProgram::displaced_depth(const Fragments& in, const UvDerivatives& d, const TangentFrame& frame,
                                          const Ray& ray, const Float& s, ShadeOutput& out) const {
  const Vec3 p{in.varyings[kWorldX], in.varyings[kWorldY], in.varyings[kWorldZ]};
  const Vec3 dpdx{simd::quad_ddx(p.x), simd::quad_ddx(p.y), simd::quad_ddx(p.z)};
  const Vec3 dpdy{simd::quad_ddy(p.x), simd::quad_ddy(p.y), simd::quad_ddy(p.z)};
  const Float det = d.dudx * d.dvdy - d.dudy * d.dvdx;
  const Mask usable = xsimd::abs(det) > Float(1e-30f);
  const Float inv = xsimd::select(usable, Float(1.0f) / det, Float(0.0f));
  const Vec3 dpdu = scale(add(scale(dpdx, d.dvdy), scale(dpdy, Float(0.0f) - d.dvdx)), inv);
  const Vec3 dpdv = scale(add(scale(dpdy, d.dudx), scale(dpdx, Float(0.0f) - d.dudy)), inv);
  const Float k = xsimd::sqrt(xsimd::sqrt(dot(dpdu, dpdu)) * xsimd::sqrt(dot(dpdv, dpdv)));
  const Vec3 hit = add(add(p, add(scale(dpdu, ray.du * s), scale(dpdv, ray.dv * s))), scale(frame.n, Float(0.0f) - s * k));
  const glm::mat4& m = lights_.view_projection;
  const auto row = [&](int r) {
    return Float(m[0][r]) * hit.x + Float(m[1][r]) * hit.y + Float(m[2][r]) * hit.z + Float(m[3][r]);
  };
  const Float clip_z = row(2), clip_w = row(3);
  out.depth = (clip_z / clip_w) * Float(0.5f) + Float(0.5f);
  out.view_depth = clip_w;
  out.writes_depth = true;
}

template <class PerLane>
void DisplacementProgram::trace_reference(const Ray& ray, const Float& ds, const Mask& covered,
                                          PerLane per_lane) const {
  alignas(64) float u0[kLanes], v0[kLanes], du[kLanes], dv[kLanes], depth[kLanes];
  ray.u0.store_aligned(u0);
  ray.v0.store_aligned(v0);
  ray.du.store_aligned(du);
  ray.dv.store_aligned(dv);
  ds.store_aligned(depth);
  const std::uint32_t lanes = simd::to_bits(covered);
  // QDM and cone stepping without refinement see the box surface; everything else the filtered surface.
  const TechniqueKind technique = key_.trace.technique;
  const bool box = (technique == TechniqueKind::Qdm || technique == TechniqueKind::Csm ||
                    technique == TechniqueKind::Rcsm) &&
                   trace_.refinement == QdmRefinement::None;
  const ReferenceSurface surface = box ? ReferenceSurface::Box : ReferenceSurface::Bilinear;
  // The reference may span several texture repeats (a blend's weights): its UV is the layers' / scale. The
  // ray's direction has depth component 1, so its t is the depth s.
  const double k = 1.0 / reference_scale_;
  for (int l = 0; l < kLanes; ++l) {
    if (!((lanes >> l) & 1u)) continue;
    const SurfaceRay r{{u0[l] * k, v0[l] * k, 0.0}, {du[l] * k, dv[l] * k, 1.0}};
    per_lane(l, r,
             reference_memo_ ? reference_memo_->intersect(reference_id_, *reference_, depth[l], r, surface, 1 << 16)
                             : intersect_reference(*reference_, depth[l], r, surface, 1 << 16));
  }
}

void DisplacementProgram::reference_errors(const Ray& ray, const Float& ds, const Hit& hit, const Mask& covered,
                                           ShadeOutput& out) const {
  alignas(64) float u0[kLanes], v0[kLanes], du[kLanes], dv[kLanes], s[kLanes], error[kLanes] = {},
      missed[kLanes] = {};
  ray.u0.store_aligned(u0);
  ray.v0.store_aligned(v0);
  ray.du.store_aligned(du);
  ray.dv.store_aligned(dv);
  hit.s.store_aligned(s);
  const double k = 1.0 / reference_scale_;
  trace_reference(ray, ds, covered, [&](int l, const SurfaceRay&, const ReferenceHit& ref) {
    if (!ref.hit) return;
    const double eu = ((double(u0[l]) + double(du[l]) * s[l]) * k - ref.point.x) * reference_->width;
    const double ev = ((double(v0[l]) + double(dv[l]) * s[l]) * k - ref.point.y) * reference_->height;
    error[l] = float(std::sqrt(eu * eu + ev * ev));
    missed[l] = error[l] > 1.0f ? 1.0f : 0.0f;
  });
  out.error_texels = Float::load_aligned(error);
  out.missed = Float::load_aligned(missed);
}

DisplacementProgram::Hit DisplacementProgram::exact_hit(const Ray& ray, const Float& ds, const Hit& traced,
                                                        const Mask& covered) const {
  alignas(64) float s[kLanes], cells[kLanes] = {};
  traced.s.store_aligned(s);
  trace_reference(ray, ds, covered, [&](int l, const SurfaceRay&, const ReferenceHit& ref) {
    cells[l] = float(ref.cells_visited);
    if (ref.hit) s[l] = float(ref.t);  // else (the ray leaves the slab) the traced hit stays
  });
  const Float hit_s = Float::load_aligned(s);
  return Hit{hit_s, Float::load_aligned(cells), hit_s};
}

struct DisplacementProgram::Setup {
  UvDerivatives d;
  TangentFrame frame;
  Vec3 view, view_tangent;
  Float ds;  // the depth range the ray is traced through: the depth scale after the distance fade and POM's LOD fade
  Ray ray;
  Mask active;  // the covered lanes (helper lanes are not traced)
  // Mip LOD of the (first) height map: relief and POM steps, blend heights, soft shadows; 0 without one. Set by
  // setup_for (no default: a group's array of setups is made per batch, in the hot path).
  Float height_lod;

  // f(value) for each Float above, value(setup) being it in a Setup (or const): what a packed batch takes of its
  // lanes' setups (batch_scheduler.hpp; `active` is its used lanes).
  template <class F>
  static constexpr void values(F&& f) {
    f([](auto& s) -> auto& { return s.d.dudx; });
    f([](auto& s) -> auto& { return s.d.dvdx; });
    f([](auto& s) -> auto& { return s.d.dudy; });
    f([](auto& s) -> auto& { return s.d.dvdy; });
    const auto vec3 = [&](auto of) {
      f([of](auto& s) -> auto& { return of(s).x; });
      f([of](auto& s) -> auto& { return of(s).y; });
      f([of](auto& s) -> auto& { return of(s).z; });
    };
    vec3([](auto& s) -> auto& { return s.frame.t; });
    vec3([](auto& s) -> auto& { return s.frame.b; });
    vec3([](auto& s) -> auto& { return s.frame.n; });
    vec3([](auto& s) -> auto& { return s.view; });
    vec3([](auto& s) -> auto& { return s.view_tangent; });
    f([](auto& s) -> auto& { return s.ds; });
    f([](auto& s) -> auto& { return s.ray.u0; });
    f([](auto& s) -> auto& { return s.ray.v0; });
    f([](auto& s) -> auto& { return s.ray.du; });
    f([](auto& s) -> auto& { return s.ray.dv; });
    f([](auto& s) -> auto& { return s.height_lod; });
  }
};

template <class V, class Surface>
DisplacementProgram::Hit DisplacementProgram::trace(const Surface& surface, const Setup& setup) const {
  const Ray& ray = setup.ray;
  const Float& ds = setup.ds;
  const Mask active = setup.active;
  Hit hit{Float(0.0f), Float(0.0f), Float(0.0f)};
  // Relief, POM and cone-step loops without the texture-cache recorder's tests when none listens: their calls
  // made the compiler keep the loop's vector values in memory.
  const bool recorded = fetch_recorder_listens();
  if constexpr (V::technique == TechniqueKind::Relief) {
    hit = recorded ? trace::relief<true>(surface, ray, ds, setup.height_lod, active, trace_)
                   : trace::relief<false>(surface, ray, ds, setup.height_lod, active, trace_);
    hit.box_s = hit.s;
  } else if constexpr (V::technique == TechniqueKind::Pom) {
    const Float& lod = setup.height_lod;
    hit = recorded ? trace::pom<true>(surface, ray, ds, lod, setup.view_tangent.z, active, trace_)
                   : trace::pom<false>(surface, ray, ds, lod, setup.view_tangent.z, active, trace_);
    hit.box_s = hit.s;
  } else if constexpr (V::technique == TechniqueKind::Csm || V::technique == TechniqueKind::Rcsm) {
    const trace::ConeTexels texels{cones_, &layers_[0].height->height, sampler_.address, sampler_.fetch};
    constexpr bool relaxed = V::technique == TechniqueKind::Rcsm;
    hit = recorded ? trace::cone_step<relaxed, true>(texels, ray, ds, active, trace_)
                   : trace::cone_step<relaxed, false>(texels, ray, ds, active, trace_);
    hit.box_s = hit.s;
    hit.s = trace::refine(surface, ray, ds, hit.s, hit.iterations, active, trace_, surface_);
  } else if constexpr (V::technique == TechniqueKind::Qdm) {
    const QdmBudget budget = qdm_budget(setup);
    hit = refine_qdm_hit(surface, setup, trace::qdm<V>(surface, ray, ds, budget.stop_level, budget.cap, active));
  }
  return hit;
}

template <class Surface>
DisplacementProgram::Hit DisplacementProgram::refine_qdm_hit(const Surface& surface, const Setup& setup, Hit hit) const {
  hit.box_s = hit.s;
  hit.s = trace::refine(surface, setup.ray, setup.ds, hit.s, hit.iterations, setup.active, trace_, surface_);
  return hit;
}

// refine_qdm_hit() of two paired batches' hits (no recorder listens); the linear refinement of both at once.
void DisplacementProgram::refine_qdm_hits(const SingleLayerSurface& surface, const Setup& setup_a, Hit& hit_a,
                                          const Setup& setup_b, Hit& hit_b) const {
  if (trace_.refinement != QdmRefinement::Linear) {
    hit_a = refine_qdm_hit(surface, setup_a, hit_a);
    hit_b = refine_qdm_hit(surface, setup_b, hit_b);
    return;
  }
  hit_a.box_s = hit_a.s;
  hit_b.box_s = hit_b.s;
  trace::refine_linear_pair(surface, setup_a.ray, setup_a.ds, hit_a.s, hit_a.iterations, setup_a.active, setup_b.ray,
                            setup_b.ds, hit_b.s, hit_b.iterations, setup_b.active);
}

DisplacementProgram::QdmBudget DisplacementProgram::qdm_budget(const Setup& setup) const {
  const UvDerivatives& d = setup.d;
  QdmBudget budget{Float(0.0f), Int(trace_.max_iterations)};
  if (trace_.lod_stop)
    budget.stop_level =
        xsimd::max(xsimd::floor(layers_[0].height->tree.lod(d.dudx, d.dvdx, d.dudy, d.dvdy)), Float(0.0f));
  if (trace_.min_iterations > 0) {
    const Float grazing = Float(1.0f) - xsimd::min(xsimd::max(setup.view_tangent.z, Float(0.0f)), Float(1.0f));
    budget.cap = xsimd::to_int(Float(float(trace_.min_iterations)) +
                               Float(float(trace_.max_iterations - trace_.min_iterations)) * grazing);
  }
  return budget;
}

namespace {

// Albedo and tangent-space normal (unnormalised) of one layer at the hit; textures: albedo first, normal second.
// like, like_lod: a texture whose LOD from d is known (the height map's, from the setup), or null. An albedo map
// alike (same_lod_as) has that LOD: the hit's sample does not wait on a second evaluation of the same chain.
void layer_colour(const TwinSampler& textures, const UvDerivatives& d, const TextureSampler* like, const Float& like_lod,
                  const Float& u, const Float& v, Float* albedo, Float* normal) {
  const TextureSampler &albedo_texture = textures.first(), &normal_texture = textures.second();
  const Float albedo_lod = like != nullptr && albedo_texture.same_lod_as(*like)
                               ? like_lod
                               : albedo_texture.lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
  Float n[4];
  const UvAhead ahead = d.quad_below();
  textures.sample(u, v, albedo_lod,
                  normal_texture.same_lod_as(albedo_texture) ? albedo_lod
                                                             : normal_texture.lod(d.dudx, d.dvdx, d.dudy, d.dvdy),
                  albedo, n, &ahead);
  for (int c = 0; c < 3; ++c) normal[c] = n[c] * Float(2.0f) - Float(1.0f);
}

// The colour blend factors of the layers at one point (they sum to 1 where any layer has weight):
//   alpha:        w_i / sum(w)
//   height:       the talk's operator, w_i h_i / sum(w h), with heights floored at 1/256 so that all-zero
//                 heights still blend by weight instead of dividing by the talk's epsilon
//   height_width: the widely used transition-width form: b_i = max(h_i + w_i - (max_j(h_j + w_j) - width), 0)
//                 over layers with weight, normalised
void blend_factors(BlendOperator op, float width, int count, const Float* h, const Float* w, Float* f) {
  const Float zero(0.0f);
  Float sum(0.0f);
  if (op == BlendOperator::Alpha) {
    for (int i = 0; i < count; ++i) f[i] = w[i];
  } else if (op == BlendOperator::Height) {
    for (int i = 0; i < count; ++i) f[i] = w[i] * xsimd::max(h[i], Float(1.0f / 256.0f));
  } else {
    Float top(-1.0f);
    for (int i = 0; i < count; ++i) top = xsimd::max(top, xsimd::select(w[i] > zero, h[i] + w[i], Float(-1.0f)));
    const Float floor_level = top - Float(width);
    for (int i = 0; i < count; ++i) f[i] = xsimd::select(w[i] > zero, xsimd::max(h[i] + w[i] - floor_level, zero), zero);
  }
  for (int i = 0; i < count; ++i) sum += f[i];
  const Float inv = xsimd::select(sum > zero, Float(1.0f) / sum, zero);
  for (int i = 0; i < count; ++i) f[i] = f[i] * inv;
}

}  // namespace

// The surface at the hit: where it is, its colour, normal, specular and baked AO; with an ORM texture, its
// roughness and occlusion (apply_orm), else those are not read.
struct DisplacementProgram::SurfaceAtHit {
  Hit hit;
  Float hu, hv;
  Float albedo[4], tangent_normal[3], specular = Float(0.0f), ao = Float(1.0f);
  Float roughness, occlusion;
};

template <class Surface>
void DisplacementProgram::surface_at_hit(const Setup& setup, const Surface& surface, const Hit& traced,
                                         SurfaceAtHit& at) const {
  const UvDerivatives& d = setup.d;
  const Ray& ray = setup.ray;
  at.hit = trace_.exact_hits ? exact_hit(ray, setup.ds, traced, setup.active) : traced;
  const Hit& hit = at.hit;
  const Float hu = ray.u0 + ray.du * hit.s, hv = ray.v0 + ray.dv * hit.s;
  at.hu = hu;
  at.hv = hv;
  // Baked AO is read per layer and blended like the colours.
  const auto baked_ao = [&](const Layer& l) {
    Float a[4];
    l.ao->sample(hu, hv, Float(0.0f), a);
    return a[0];
  };
  Float* const albedo = at.albedo;
  Float* const tangent_normal = at.tangent_normal;
  Float& specular = at.specular;
  Float& ao = at.ao;
  FetchLanes surface_lanes(FetchPhase::Surface);
  const TextureSampler* const height_map = layers_[0].height ? &layers_[0].height->height : nullptr;
  if constexpr (std::is_same_v<Surface, SingleLayerSurface>) {
    const Layer& l = layers_[0];
    layer_colour(l.textures, d, height_map, setup.height_lod, hu, hv, albedo, tangent_normal);
    specular = specular_from_albedo(albedo, l.specular, lighting_.specular);
    if (l.orm) {
      // Beside the albedo: the same UV, derivatives and filter (its own LOD when it is not alike).
      const Float lod = height_map != nullptr && l.orm->same_lod_as(*height_map) ? setup.height_lod
                                                                                 : l.orm->lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
      Float orm[4];
      l.orm->sample(hu, hv, lod, orm);
      const OrmSurface s = apply_orm(orm, orm_params_, lighting_.roughness, albedo, specular);
      for (int c = 0; c < 3; ++c) albedo[c] = s.albedo[c];
      specular = s.specular;
      at.roughness = s.roughness;
      at.occlusion = s.occlusion;
    }
    if (l.ao) ao = baked_ao(l);
  } else {
    const int count = surface.layer_count();
    Float h[BlendedSurface::kMaxLayers], w[BlendedSurface::kMaxLayers], f[BlendedSurface::kMaxLayers];
    surface.weights_at(hu, hv, w);
    if (key_.blend != BlendOperator::Alpha) {
      // A lane whose weight of a layer is 0 gets factor 0 from it whatever its height (blend_factors): only the
      // lanes with weight fetch a layer's height (as the texture cache counts them), none where no lane has any.
      for (int i = 0; i < count; ++i) {
        const Mask weighted = w[i] != Float(0.0f);
        h[i] = Float(0.0f);
        if (!xsimd::any(weighted)) continue;
        FetchLanes layer_lanes;
        layer_lanes.narrow(weighted);
        h[i] = surface.layer(i).height(hu, hv, setup.height_lod);
      }
    }
    blend_factors(key_.blend, blend_.width, count, h, w, f);
    for (int c = 0; c < 4; ++c) albedo[c] = Float(0.0f);
    for (int c = 0; c < 3; ++c) tangent_normal[c] = Float(0.0f);
    if (blend_ao_) {
      const Float inv(1.0f / float(blend_ao_scale_));
      Float a[4];
      blend_ao_->sample(hu * inv, hv * inv, Float(0.0f), a);
      ao = a[0];
    } else if (key_.ao == AoMode::Baked) {
      ao = Float(0.0f);
    }
    for (int i = 0; i < count; ++i) {
      if (!xsimd::any(f[i] > Float(0.0f))) continue;  // a layer absent from the whole batch costs no fetch
      FetchLanes layer_lanes(FetchPhase::Surface);     // and within a batch, only its lanes fetch it
      layer_lanes.narrow(f[i] > Float(0.0f));
      const Layer& l = layers_[std::size_t(i)];
      Float a[4], n[3];
      layer_colour(l.textures, d, height_map, setup.height_lod, hu, hv, a, n);
      for (int c = 0; c < 4; ++c) albedo[c] += f[i] * a[c];
      for (int c = 0; c < 3; ++c) tangent_normal[c] += f[i] * n[c];
      specular += f[i] * specular_from_albedo(a, l.specular, lighting_.specular);
      if (l.ao) ao += f[i] * baked_ao(l);
    }
  }
}

// Everything after the surface: the shading normal, lighting, AOVs, errors against the reference, depth.
template <class V, class Surface>
void DisplacementProgram::light_hit(const Fragments& in, const Setup& setup, const Surface& surface,
                                    const SurfaceAtHit& at, ShadeOutput& out) const {
  const Hit& hit = at.hit;
  const TangentFrame& frame = setup.frame;
  const Vec3 shading_normal =
      normalize(frame.to_world({at.tangent_normal[0], at.tangent_normal[1], at.tangent_normal[2]}));
  const bool orm = layers_[0].orm.has_value();
  light(in, setup, surface, hit, at.albedo, at.specular, at.ao, orm ? &at.roughness : nullptr,
        orm ? &at.occlusion : nullptr, shading_normal, out);
  out.normal[0] = shading_normal.x;
  out.normal[1] = shading_normal.y;
  out.normal[2] = shading_normal.z;
  out.iterations = hit.iterations;
  out.hit_u = at.hu;
  out.hit_v = at.hv;
  out.hit_depth = hit.s;
  out.error_texels = out.missed = Float(0.0f);
  if constexpr (V::technique != TechniqueKind::Normal)
    if (reference_) reference_errors(setup.ray, setup.ds, hit, in.covered, out);
}

// Self-shadowing per light and ambient occlusion at the hit, then the lighting model.
template <class Surface>
void DisplacementProgram::light(const Fragments& in, const Setup& setup, const Surface& surface, const Hit& hit,
                                const Float* albedo, const Float& specular, const Float& baked_ao,
                                const Float* roughness, const Float* occlusion, const Vec3& shading_normal,
                                ShadeOutput& out) const {
  const Ray& ray = setup.ray;
  const Float& ds = setup.ds;
  // Hard shadows trace the box surface, so they start from the hit on it: a refined hit between texel centres
  // can lie below a neighbouring column's top and would be shadowed by it (staircase acne).
  // The bias lifts the start along the light ray (towards depth 0) by a fraction of the depth scale.
  const Float s_hit = key_.shadow == ShadowMode::Hard ? hit.box_s : hit.s;
  const Float lift = xsimd::min(Float(shadow_.bias) * ds, s_hit);
  const Float su_hit = ray.u0 + ray.du * s_hit, sv_hit = ray.v0 + ray.dv * s_hit;
  const Float hu = ray.u0 + ray.du * hit.s, hv = ray.v0 + ray.dv * hit.s;
  const Float zero(0.0f);
  Float visibility[limits::kMaxDirectionalLights];
  const bool shadows = key_.shadow != ShadowMode::Off;
  if (shadows) {
    for (std::size_t j = 0; j < lights_.directional.size(); ++j) {
      const glm::vec3& l = lights_.directional[j].direction;
      const Vec3 lt = setup.frame.to_tangent({Float(l.x), Float(l.y), Float(l.z)});
      const Mask above = lt.z > zero;  // a light below the polygon leaves the whole relief in shadow
      const Float lz = xsimd::max(lt.z, Float(1e-6f));
      const Float du = lt.x / lz, dv = lt.y / lz;
      const Float su = su_hit + du * lift, sv = sv_hit + dv * lift, s0 = s_hit - lift;
      const Float u1 = su + du * s0, v1 = sv + dv * s0;
      const Surface towards_light =
          surface.around(xsimd::min(su, u1), xsimd::max(su, u1), xsimd::min(sv, v1), xsimd::max(sv, v1));
      const ShadowResult r =
          self_shadow(towards_light, key_.shadow, shadow_, ShadowRay{su, sv, s0, du, dv, ds}, setup.height_lod, setup.active & above);
      visibility[j] = xsimd::select(above, r.visibility, zero);
    }
  }
  Float ao = baked_ao;
  if (key_.ao == AoMode::Frame) {
    const Float radius(ao_.radius);
    ao = ambient_occlusion(surface.around(hu - radius, hu + radius, hv - radius, hv + radius), ao_, hu, hv, hit.s, ds,
                           in.pixel_x, in.pixel_y, setup.active);
  }
  if (key_.ao != AoMode::Off) ao = apply_ao_strength(ao, ao_.strength);
  if (occlusion) ao = ao * *occlusion;  // the ORM texture's, on top of the material's
  // The lighting AOVs: what the lighting model multiplies by, for the first directional light.
  out.shadow = shadows && !lights_.directional.empty() ? visibility[0] : Float(1.0f);
  out.ao = ao;
  shade_lights(shading_normal, setup.frame.n, setup.view, SurfaceSample{albedo, specular, ao, roughness},
               shadows ? visibility : nullptr, key_.lighting, lighting_, lights_, out.color);
}

void DisplacementProgram::shade(const Fragments* const* in, ShadeOutput* const* out, int n) const {
  (this->*shade_)(in, out, n);
}

// A blend's sparse batches are packed into fewer (shade_in_stages): up to eight at once, with at most four
// batches' worth of covered lanes (replayed on the terrain's batches, larger groups of eight left hardly fewer
// packed batches: docs/performance-history.md).
static_assert(simd::LaneCompaction::kMaxBatches <= kMaxGroupBatches);

BatchGrouping DisplacementProgram::grouping() const {
  if (!pairs_technique(key_.trace.technique)) return {};
  if (layers_.size() > 1) return {simd::LaneCompaction::kMaxBatches, 4 * simd::kLanes};
  return {2, 2 * simd::kLanes};
}

// Two batches' QDM walks to their ends, a step of each per round: their hits on the box surface.
template <class V, class Surface>
void DisplacementProgram::walk_pair(const Surface& surface_a, const Setup& setup_a, Hit& hit_a,
                                    const Surface& surface_b, const Setup& setup_b, Hit& hit_b) const {
  const QdmBudget budget_a = qdm_budget(setup_a), budget_b = qdm_budget(setup_b);
  using Walk = trace::QdmWalk<V, Surface, false>;  // no recorder listens to paired batches
  Walk walk_a(surface_a, setup_a.ray, setup_a.ds, budget_a.stop_level, budget_a.cap, setup_a.active);
  Walk walk_b(surface_b, setup_b.ray, setup_b.ds, budget_b.stop_level, budget_b.cap, setup_b.active);
  trace::qdm_pair(walk_a, walk_b);
  hit_a = walk_a.hit();
  hit_b = walk_b.hit();
}

// A batch's stages over one surface type (SingleLayerSurface, or BlendedSurface for a blend), as shade_in_stages
// calls them (batch_scheduler.hpp says in which order, paired or packed).
template <class V, class Surface>
class DisplacementProgram::Stages {
public:
  static constexpr bool kBlend = std::is_same_v<Surface, BlendedSurface>;
  // A blend's sparse groups are packed (its setup has made everything that reads whole quads).
  static constexpr PackLanes kPackLanes = kBlend ? PackLanes::Groups : PackLanes::Never;
  using Setup = DisplacementProgram::Setup;
  using Hit = DisplacementProgram::Hit;
  using AtHit = SurfaceAtHit;

  explicit Stages(const DisplacementProgram& program) : p_(program), layers_(layers(program)) {}

  Setup setup(const Fragments& in) const { return p_.setup_for(in); }

  // One layer's surface is every batch's; a blend's is bounded per batch (its weights over the ray's UV box).
  std::conditional_t<kBlend, BlendedSurface, const SingleLayerSurface&> surface(const Fragments& in,
                                                                                const Setup& setup) const {
    if constexpr (kBlend)
      return p_.blended_surface(layers_, in, setup);
    else
      return layers_;
  }

  Hit trace(const Surface& surface, const Setup& setup) const { return p_.trace<V>(surface, setup); }

  // Two batches' traces: QDM's walks step in one loop, a single layer's relief runs its binary searches side by
  // side. Other techniques have none: the scheduler traces a pair's batches one after the other (POM's loop runs
  // at the core's throughput already; CSM and RCSM batches are never paired).
  static constexpr bool kTracePair =
      V::technique == TechniqueKind::Qdm || (V::technique == TechniqueKind::Relief && !kBlend);
  void trace_pair(const Surface& surface_a, const Setup& setup_a, Hit& hit_a, const Surface& surface_b,
                  const Setup& setup_b, Hit& hit_b) const
    requires kTracePair
  {
    if constexpr (V::technique == TechniqueKind::Qdm) {
      p_.walk_pair<V>(surface_a, setup_a, hit_a, surface_b, setup_b, hit_b);
      if constexpr (kBlend) {
        hit_a = p_.refine_qdm_hit(surface_a, setup_a, hit_a);
        hit_b = p_.refine_qdm_hit(surface_b, setup_b, hit_b);
      } else {
        p_.refine_qdm_hits(surface_a, setup_a, hit_a, setup_b, hit_b);
      }
    } else if (fetch_recorder_listens()) {  // relief
      hit_a = trace(surface_a, setup_a);
      hit_b = trace(surface_b, setup_b);
    } else {
      trace::relief_pair(surface_a, p_.trace_, setup_a.ray, setup_a.ds, setup_a.height_lod, setup_a.active, hit_a,
                         setup_b.ray, setup_b.ds, setup_b.height_lod, setup_b.active, hit_b);
      hit_a.box_s = hit_a.s;
      hit_b.box_s = hit_b.s;
    }
  }

  AtHit surface_at_hit(const Setup& setup, const Surface& surface, const Hit& hit) const {
    AtHit at;
    p_.surface_at_hit(setup, surface, hit, at);
    return at;
  }

  void light(const Fragments& in, const Setup& setup, const Surface& surface, const AtHit& at,
             ShadeOutput& out) const {
    p_.light_hit<V>(in, setup, surface, at, out);
  }

  // The displaced depth, from the batch's own quads (the world position's derivatives) and its hits.
  void finish(const Fragments& in, const Setup& setup, ShadeOutput& out) const {
    if (p_.trace_.write_depth) p_.displaced_depth(in, setup.d, setup.frame, setup.ray, out.hit_depth, out);
  }

  // Of the inputs, what the stages after the setup read: the pixel (frame AO's noise) and the vertex weights (the
  // blended surface).
  template <class F>
  void lane_inputs(F&& f) const {
    f([](auto& in) -> auto& { return in.pixel_x; });
    f([](auto& in) -> auto& { return in.pixel_y; });
    for (int j = kWeight0; j < p_.varying_count(); ++j) f([j](auto& in) -> auto& { return in.varyings[j]; });
  }
  // What light_hit writes: every lane-wise output.
  template <class F>
  static void output_values(F&& f) {
    ShadeOutput::lane_values(f);
  }

private:
  static auto layers(const DisplacementProgram& program) {
    if constexpr (kBlend)
      return program.layer_surfaces();
    else
      return program.layer_surface(0);
  }

  const DisplacementProgram& p_;
  std::conditional_t<kBlend, LayerSurfaces, SingleLayerSurface> layers_;
};

// Every group, one batch included, in stages (batch_scheduler.hpp): one layer's batches two at a time, a blend's
// sparse batches packed.
template <class V>
void DisplacementProgram::shade_variant(const Fragments* const* in, ShadeOutput* const* out, int n) const {
  // values() lists every member but `active` (a Mask, in a Float's room): a member added without it fails here.
  static_assert(sizeof(Setup) == std::size_t([] {
                  int count = 0;
                  Setup::values([&](auto) { ++count; });
                  return count + 1;
                }()) * sizeof(Float));
  if (layers_.size() > 1)
    shade_in_stages(Stages<V, BlendedSurface>(*this), in, out, n);
  else
    shade_in_stages(Stages<V, SingleLayerSurface>(*this), in, out, n);
}

DisplacementProgram::Setup DisplacementProgram::setup_for(const Fragments& in) const {
  const Float& u = in.varyings[kU];
  const Float& v = in.varyings[kV];
  Setup setup;
  setup.d = UvDerivatives::from(u, v, key_.sampler.lod);
  setup.frame = TangentFrame::from(in);
  setup.view = view_vector(in, lights_);
  setup.view_tangent = setup.frame.to_tangent(setup.view);

  // Depth scale, faded with camera distance when asked; the ray leaves the polygon along -view.
  setup.ds = Float(trace_.depth_scale);
  if (trace_.fade_end > 0.0f) {
    const Float range(std::max(trace_.fade_end - trace_.fade_start, 1e-6f));
    const Float fade = xsimd::min(xsimd::max((in.view_depth - Float(trace_.fade_start)) / range, Float(0.0f)), Float(1.0f));
    setup.ds = setup.ds * (Float(1.0f) - fade);
  }
  const Float vz = xsimd::max(setup.view_tangent.z, Float(1e-4f));  // grazing and back-facing views: nearly parallel rays
  setup.ray = Ray{u, v, (Float(0.0f) - setup.view_tangent.x) / vz, (Float(0.0f) - setup.view_tangent.y) / vz};
  setup.active = in.covered;
  setup.height_lod = layers_[0].height
                         ? layers_[0].height->height.lod(setup.d.dudx, setup.d.dvdx, setup.d.dudy, setup.d.dvdy)
                         : Float(0.0f);
  if (key_.trace.technique == TechniqueKind::Pom) {
    // Far away (high LOD) POM fades to normal mapping.
    const Float fade = xsimd::min(xsimd::max((setup.height_lod - Float(trace_.lod_threshold)) /
                                                 Float(std::max(trace_.lod_fade, 1e-6f)),
                                             Float(0.0f)),
                                  Float(1.0f));
    setup.ds = setup.ds * (Float(1.0f) - fade);
  }
  return setup;
}

DisplacementProgram::LayerSurfaces DisplacementProgram::layer_surfaces() const {
  const int count = int(layers_.size());
  return {layer_surface(0), layer_surface(std::min(1, count - 1)), layer_surface(std::min(2, count - 1)),
          layer_surface(std::min(3, count - 1))};
}

BlendedSurface DisplacementProgram::blended_surface(const LayerSurfaces& layers, const Fragments& in,
                                                    const Setup& setup) const {
  const int count = int(layers_.size());
  if (key_.weights == WeightMode::Vertex) {
    const Float w[BlendedSurface::kMaxLayers] = {in.varyings[kWeight0], in.varyings[kWeight1],
                                                 count > 2 ? in.varyings[kWeight2] : Float(0.0f),
                                                 count > 3 ? in.varyings[kWeight3] : Float(0.0f)};
    return BlendedSurface(layers.data(), count, key_.blend, w);
  }
  // Per-pixel weights: bounded over the UV box the view ray crosses down to depth_scale.
  const Ray& ray = setup.ray;
  const Float u1 = ray.u0 + ray.du * setup.ds, v1 = ray.v0 + ray.dv * setup.ds;
  const WeightTexture weights{&*weights_, blend_.weights_scale, combined_ ? &*combined_ : nullptr, combined_period_u_,
                              combined_period_v_, layer_heights_, box_values_};
  return BlendedSurface(layers.data(), count, key_.blend, weights, xsimd::min(ray.u0, u1), xsimd::max(ray.u0, u1),
                        xsimd::min(ray.v0, v1), xsimd::max(ray.v0, v1));
}

template <class V>
DisplacementProgram::Variant DisplacementProgram::variant() {
  return {&DisplacementProgram::shade_variant<V>, V::options()};
}

// Every combination of the trace options is instantiated (TraceOptions, qdmr/program/program_key.hpp): 5 techniques, and for qdm
// 3 math modes x 2 max fetches x 3 level-up rules.
DisplacementProgram::Variant DisplacementProgram::select(const TraceOptions& o) {
  using K = TechniqueKind;
  switch (o.technique) {
    case K::Normal: return variant<Trace<K::Normal>>();
    case K::Relief: return variant<Trace<K::Relief>>();
    case K::Pom: return variant<Trace<K::Pom>>();
    case K::Csm: return variant<Trace<K::Csm>>();
    case K::Rcsm: return variant<Trace<K::Rcsm>>();
    case K::Qdm: break;
  }
  const auto qdm = [&]<MathMode M, bool Filtered>() -> Variant {
    switch (o.level_up) {
      case QdmLevelUp::Stay: return variant<Trace<K::Qdm, M, Filtered, QdmLevelUp::Stay>>();
      case QdmLevelUp::One: return variant<Trace<K::Qdm, M, Filtered, QdmLevelUp::One>>();
      case QdmLevelUp::Aligned: return variant<Trace<K::Qdm, M, Filtered, QdmLevelUp::Aligned>>();
    }
    throw Error("displacement program", "unknown level_up");
  };
  const auto fetch = [&]<MathMode M>() -> Variant {
    return o.filtered_max ? qdm.template operator()<M, true>() : qdm.template operator()<M, false>();
  };
  switch (o.math) {
    case MathMode::Sm4: return fetch.operator()<MathMode::Sm4>();
    case MathMode::Sm3: return fetch.operator()<MathMode::Sm3>();
    case MathMode::Exact: return fetch.operator()<MathMode::Exact>();
  }
  throw Error("displacement program", "unknown math mode");
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
