#include "prepare/assets.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <optional>

#include "kernel/kernel.hpp"
#include "bake/ao_map.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "texture/blend_box_values.hpp"
#include "texture/height_texture.hpp"
#include "texture/twin_texels.hpp"
#include "texture/blend_weights.hpp"
#include "texture/height_family.hpp"
#include "texture/pattern_reuse.hpp"

namespace qdmr {
namespace {

// The level 0 and stored box chain of a layer's heights, made once for the textures of its build group (its box
// chain, its max-quadtree, normals from it): each would otherwise make the pattern again. Empty for a lone texture.
struct SharedHeight {
  std::optional<Image> level0;
  std::optional<HeightTexture> stored_box;
};

// A layer's heights as made from the scene (or the shared level 0).
Image layer_height(const TextureRequest& request, const SharedHeight* shared) {
  return shared && shared->level0 ? *shared->level0 : make_layer_height(request.layer, request.where);
}

// A layer's heights through the storage the scene asks for (quantisation, BC3), so what is rendered is what a
// GPU would sample; the BC3 error goes to `stat`.
HeightTexture stored_height(const TextureRequest& request, MipReduce reduce, const Kernel& kernel, TextureStat& stat,
                            const SharedHeight* shared) {
  HeightTexture stored = shared && shared->stored_box && reduce == MipReduce::Box
                             ? *shared->stored_box
                             : make_height_texture(layer_height(request, shared), request.layer.height, reduce,
                                                   kernel.mip_extremum(), kernel.bc3_encode());
  stat.height_format = format_name(stored.texture.format);
  if (stored.bc3) {
    stat.bc3 = true;
    stat.bc3_max_error = stored.bc3->max_error;
    stat.bc3_rms_error = stored.bc3->rms_error;
  }
  return stored;
}

void describe(TextureStat& stat, const TextureRequest& request, const Texture& texture);

// Builds one requested texture. Each step's temporaries are freed before the next step allocates: the plan's
// texture_working_bytes counts the most this holds at once, step by step.
Texture build_texture(const TextureRequest& request, const Kernel& kernel, TextureStat& stat, const SharedHeight* shared) {
  Texture texture;
  if (request.purpose == TexturePurpose::Height) {
    texture = stored_height(request, request.reduce, kernel, stat, shared).texture;
    add_linear_copy(texture);
    if (request.wrap_footprints) add_wrap_footprints(texture);
  } else {
    Image level0;
    if (request.desc.source == TextureSource::FromHeight) {
      // Behind a from_height normal map only level 0 is used: any reduction will do.
      const Image height = stored_height(request, MipReduce::Box, kernel, stat, shared).texture.level_image(0);
      level0 = make_texture(request.desc, request.purpose, request.layer, &height, request.where);
    } else {
      level0 = make_texture(request.desc, request.purpose, request.layer, nullptr, request.where);
    }
    if (request.purpose == TexturePurpose::Normal)
      for (float& v : level0.texels) v = 0.5f + 0.5f * v;  // stored as UNORM, as normal maps are
    texture = make_mip_texture(level0, request.format, request.srgb, request.reduce, kernel.mip_extremum());
    add_linear_copy(texture);
  }
  describe(stat, request, texture);
  return texture;
}

void describe(TextureStat& stat, const TextureRequest& request, const Texture& texture) {
  stat.where = request.where;
  stat.purpose = purpose_name(request.purpose);
  stat.format = format_name(texture.format) + (texture.srgb ? " srgb" : "");
  stat.width = texture.width();
  stat.height = texture.height();
  stat.levels = texture.level_count();
  stat.bytes = texture.bytes();
}

// Level 0 of a stored height texture in fp64, for the exact reference and the bakes.
HeightField height_field(const Texture& h, AddressMode address) {
  HeightField field;
  field.width = h.width();
  field.height = h.height();
  field.address = address;
  field.h = ZeroedBuffer<double>(std::size_t(h.width()) * std::size_t(h.height()));
  for (int y = 0; y < h.height(); ++y)
    for (int x = 0; x < h.width(); ++x) field.h[std::size_t(y) * std::size_t(h.width()) + std::size_t(x)] = h.texel(0, x, y, 0);
  return field;
}

// An AO map from the bake cache, or baked every frame (and not kept) for a dynamic surface: amortized over K
// frames, the rows j % K == frame % K of the previous frame's map (`last`, when it is that frame's), else all.
template <class T>
Image ao_map(const HeightView<T>& field, double depth_scale, const AoDesc& ao, bool dynamic, AoMapRow row, int frame,
             const AoHistory* last, std::shared_ptr<const AoHistory>& history) {
  if (!dynamic) return load_or_bake_ao_map(field, depth_scale, ao, default_cache_dir(), row);
  if (ao.amortize_frames <= 1) return bake_ao_map(field, depth_scale, ao, row);
  const AoMapSize size = ao_map_size(field.width, field.height, ao);
  auto next = std::make_shared<AoHistory>();
  next->frame = frame;
  if (last && last->frame == frame - 1 && last->map.width == size.width && last->map.height == size.height) {
    next->map = last->map;
    bake_ao_rows(field, depth_scale, ao, next->map, frame % ao.amortize_frames, ao.amortize_frames, row);
  } else {
    next->map = bake_ao_map(field, depth_scale, ao, row);
  }
  history = next;
  return next->map;
}

// Items of the previous assets by key, to share instead of rebuild.
struct Previous {
  std::map<std::string, std::shared_ptr<const MeshData>> meshes;
  std::map<std::string, std::pair<std::shared_ptr<const Texture>, TextureStat>> textures;
  std::map<std::string, DerivedAsset> derived;
  const Assets* assets = nullptr;
  const FramePlan* plan = nullptr;

  // The AO history of derived item `index` when the previous plan's item there is of the same kind and place.
  const AoHistory* ao_history(std::size_t index, const DerivedPlan& d) const {
    if (!assets || !plan || index >= plan->derived.size() || index >= assets->derived.size()) return nullptr;
    const DerivedPlan& p = plan->derived[index];
    return p.kind == d.kind && p.where == d.where ? assets->derived[index].ao_history.get() : nullptr;
  }

  Previous(const Assets* a, const FramePlan* p) : assets(a), plan(p) {
    if (!assets || !plan) return;
    for (std::size_t i = 0; i < plan->meshes.size() && i < assets->meshes.size(); ++i)
      meshes.emplace(plan->meshes[i].key, assets->meshes[i]);
    for (std::size_t i = 0; i < plan->textures.size() && i < assets->textures.size(); ++i)
      textures.emplace(plan->textures[i].key, std::make_pair(assets->textures[i], assets->texture_stats[i]));
    for (std::size_t i = 0; i < plan->derived.size() && i < assets->derived.size(); ++i)
      derived.emplace(plan->derived[i].key, assets->derived[i]);
  }
};

class Preparer {
public:
  Preparer(const FramePlan& plan, const Kernel& kernel, const Previous& previous, Assets& assets,
           const std::function<void(double)>& progress, SpareTextures* spares)
      : plan_(plan), kernel_(kernel), previous_(previous), assets_(assets), progress_(progress), spares_(spares),
        file_(plan.scene.file.string()) {}

  void run() {
    begin_ = Clock::now();
    const std::vector<std::string> items = plan_.items();
    items_ = items.size();
    {
      const PatternReuse reuse(plan_.reused_patterns);  // until the textures are built (the plan counts it there)
      weight_maps();
      // A mesh is built on one thread (the grid, its heights, its tangents): beside the textures, whose builds
      // take the other threads, instead of before them with the others idle.
      tbb::parallel_invoke([&] { meshes(); }, [&] { textures(); });
    }
    assets_.derived.resize(plan_.derived.size());
    for (std::size_t i = 0, end = 0; i < plan_.derived.size(); i = end) {
      // Consecutive twin-texel items read built textures only and hold no working memory: each is a one-thread
      // copy, so they are built side by side.
      end = i + 1;
      if (plan_.derived[i].kind == DerivedKind::TwinTexels)
        while (end < plan_.derived.size() && plan_.derived[end].kind == DerivedKind::TwinTexels) ++end;
      tbb::parallel_for(i, end, [&](std::size_t k) { derived(k); });
    }
    // Built and reused lines in plan order, whatever order the parallel builds finished in.
    for (const std::string& item : items)
      (std::find(built_.begin(), built_.end(), item) != built_.end() ? assets_.built : assets_.reused).push_back(item);
    if (assets_.built.size() != built_.size()) throw Error("prepare", "built an item the plan does not list");
    std::sort(steps_.begin(), steps_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [order, step] : steps_) assets_.steps.push_back(std::move(step));
  }

private:
  using Clock = std::chrono::steady_clock;

  // An item built: `order` is its place in plan_.items(), `step` what it was and when its build began.
  void record(const std::string& item, std::size_t order, PrepareStep step, Clock::time_point start) {
    step.start_ms = std::chrono::duration<double, std::milli>(start - begin_).count();
    step.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    std::lock_guard lock(mutex_);
    built_.push_back(item);
    steps_.emplace_back(order, std::move(step));
    if (progress_) progress_(double(built_.size()) / double(std::max<std::size_t>(items_, 1)));
  }

  // The weight maps of blended materials whose meshes or weight textures are built (not reused), made once.
  void weight_maps() {
    std::vector<bool> needed(plan_.materials.size(), false);
    for (const MeshPlan& mp : plan_.meshes)
      if (mp.vertex_weights >= 0 && !previous_.meshes.count(mp.key)) needed[std::size_t(mp.vertex_weights)] = true;
    for (const DerivedPlan& d : plan_.derived)
      if (d.kind == DerivedKind::WeightTexture && !previous_.derived.count(d.key)) needed[std::size_t(d.material)] = true;
    for (std::size_t i = 0; i < needed.size(); ++i) {
      if (!needed[i]) continue;
      const MaterialPlan& m = plan_.materials[i];
      weight_maps_.emplace(i, make_weight_map(m.desc.blend.weights, int(m.layers.size()),
                                              file_ + ": /materials/" + m.name + "/blend/weights"));
    }
  }
  const Image& weight_map(std::size_t material) const { return weight_maps_.at(material); }

  void meshes() {
    const std::size_t n = plan_.meshes.size();
    assets_.meshes.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      const MeshPlan& mp = plan_.meshes[i];
      if (auto it = previous_.meshes.find(mp.key); it != previous_.meshes.end()) {
        assets_.meshes[i] = it->second;
        return;
      }
      const auto start = Clock::now();
      const ObjectDesc& object = plan_.scene.objects[i];
      std::shared_ptr<const MeshData> mesh =
          object.obj_mesh ? object.obj_mesh
                          : std::make_shared<const MeshData>(
                                build_mesh(object.mesh, file_ + ": /objects/" + std::to_string(i) + "/mesh"));
      if (mp.vertex_weights >= 0) {
        const MaterialPlan& m = plan_.materials[std::size_t(mp.vertex_weights)];
        auto weighted = std::make_shared<MeshData>(*mesh);
        weighted->blend_weights = vertex_weights(weight_map(std::size_t(mp.vertex_weights)), weighted->uvs,
                                                 m.desc.blend.weights.scale);
        mesh = std::move(weighted);
      }
      assets_.meshes[i] = std::move(mesh);
      record("mesh " + mp.key, i, {"mesh " + std::to_string(i), mp.kind, file_ + ": /objects/" + std::to_string(i)}, start);
    });
  }

  // The level 0 of the layer heights the pending textures `requests` are made from, and their box chain when a
  // box-filtered height or from_height normals use it: made once (each with every thread) where two or more of
  // them would each make the pattern again.
  SharedHeight shared_height(const std::vector<std::size_t>& requests) const {
    SharedHeight s;
    if (requests.size() < 2) return s;
    const TextureRequest& first = plan_.textures[requests.front()];
    s.level0 = make_layer_height(first.layer, first.where);
    const bool box = std::any_of(requests.begin(), requests.end(), [&](std::size_t i) {
      const TextureRequest& r = plan_.textures[i];
      return r.purpose != TexturePurpose::Height || r.reduce == MipReduce::Box;
    });
    if (box) s.stored_box = make_height_texture(*s.level0, first.layer.height, MipReduce::Box, kernel_.mip_extremum(),
                                                 kernel_.bc3_encode());
    return s;
  }

  // The dynamic heights whose every texture to build the family rebuild makes (heights stored as R8 or R16 with
  // Box or Max chains, from_height normals): built first, one height at a time, each with every thread, into the
  // spares' buffers where they fit. Returns which requests they built.
  std::vector<bool> height_families() {
    std::vector<bool> done(plan_.textures.size(), false);
    std::map<std::string, std::vector<std::size_t>> users;
    for (std::size_t i = 0; i < plan_.textures.size(); ++i) {
      const TextureRequest& r = plan_.textures[i];
      if (r.dynamic && !r.height_key.empty() && !previous_.textures.count(r.key)) users[r.height_key].push_back(i);
    }
    for (const auto& [key, requests] : users) {
      const TextureRequest* heights = nullptr;
      bool fits = true;
      for (std::size_t i : requests) {
        const TextureRequest& r = plan_.textures[i];
        if (r.purpose == TexturePurpose::Height) {
          fits = fits && (r.reduce == MipReduce::Box || r.reduce == MipReduce::Max) &&
                 height_family_stores(r.desc, r.format, r.width, r.height) && (!heights || r.format == heights->format);
          heights = heights ? heights : &r;
        } else {
          fits = fits && r.purpose == TexturePurpose::Normal && r.desc.source == TextureSource::FromHeight;
        }
      }
      if (!fits || !heights) continue;
      const ProgressStep step("dynamic height " + std::to_string(heights->width) + "x" + std::to_string(heights->height) +
                              " (" + heights->where + ")");
      const auto start = Clock::now();
      std::vector<HeightFamilyMember> members(requests.size());
      for (std::size_t k = 0; k < requests.size(); ++k) {
        const TextureRequest& r = plan_.textures[requests[k]];
        HeightFamilyMember& m = members[k];
        m.normals = r.purpose == TexturePurpose::Normal;
        m.reduce = r.reduce;
        m.wrap_footprints = r.wrap_footprints;
        m.normal_strength = r.layer.normal_strength;
        if (spares_)
          m.texture = spares_->take(r.width, r.height, m.normals ? TexelFormat::RGBA8 : r.format, r.wrap_footprints);
      }
      build_height_family(heights->layer, heights->format, heights->where, members, kernel_.height_rows(),
                          kernel_.mip_extremum());
      // Built together: each texture's step is the whole rebuild.
      for (std::size_t k = 0; k < requests.size(); ++k) {
        const std::size_t i = requests[k];
        const TextureRequest& r = plan_.textures[i];
        TextureStat& stat = assets_.texture_stats[i];
        stat.height_format = format_name(heights->format);
        describe(stat, r, members[k].texture);
        assets_.textures[i] = std::make_shared<Texture>(std::move(members[k].texture));
        record("texture " + r.key, plan_.meshes.size() + i, {"texture " + std::to_string(i), purpose_name(r.purpose), r.where},
               start);
        done[i] = true;
      }
    }
    return done;
  }

  void textures() {
    const std::size_t n = plan_.textures.size();
    assets_.textures.resize(n);
    assets_.texture_stats.resize(n);
    const std::vector<bool> done = height_families();
    for (std::size_t i = 0; i < n; ++i)
      if (auto it = previous_.textures.find(plan_.textures[i].key); !done[i] && it != previous_.textures.end()) {
        assets_.textures[i] = it->second.first;
        assets_.texture_stats[i] = it->second.second;
      }
    std::vector<std::vector<std::size_t>> groups;  // the textures left to build, by texture_build_groups
    for (const std::vector<std::size_t>& group : texture_build_groups(plan_.textures)) {
      std::vector<std::size_t> pending;
      for (std::size_t i : group)
        if (!done[i] && !assets_.textures[i]) pending.push_back(i);
      if (!pending.empty()) groups.push_back(std::move(pending));
    }
    // At most kTexturesBuiltAtOnce groups in flight (the plan counts that many groups' working memory); each
    // build's own loops use every thread.
    std::size_t next = 0;
    tbb::parallel_pipeline(
        kTexturesBuiltAtOnce,
        tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                            [&](tbb::flow_control& fc) -> std::size_t {
                                              if (next < groups.size()) return next++;
                                              fc.stop();
                                              return 0;
                                            }) &
            tbb::make_filter<std::size_t, void>(tbb::filter_mode::parallel, [&](std::size_t g) {
              auto start = Clock::now();  // the shared heights count in the group's first texture
              const SharedHeight shared = shared_height(groups[g]);
              for (std::size_t i : groups[g]) {
                const TextureRequest& request = plan_.textures[i];
                const ProgressStep step("texture " + std::to_string(request.width) + "x" +
                                        std::to_string(request.height) + " (" + request.where +
                                        ")");  // a line on a terminal when it takes seconds
                assets_.textures[i] = std::make_shared<Texture>(
                    build_texture(request, kernel_, assets_.texture_stats[i], &shared));
                record("texture " + request.key, plan_.meshes.size() + i,
                       {"texture " + std::to_string(i), purpose_name(request.purpose), request.where}, start);
                start = Clock::now();
              }
            }));
  }

  void derived(std::size_t index) {
    const DerivedPlan& d = plan_.derived[index];
    DerivedAsset& out = assets_.derived[index];
    if (auto it = previous_.derived.find(d.key); it != previous_.derived.end()) {
      out = it->second;
      return;
    }
    const auto start = Clock::now();
    const MaterialPlan& m = plan_.materials[std::size_t(d.material)];
    const MaterialDesc& desc = m.desc;
    const ProgressStep step(std::string(derived_kind_name(d.kind)) + " of " + m.name);
  // (and Ctrl-C stops here)
    const auto input = [&](std::size_t k) -> const DerivedAsset& { return assets_.derived[std::size_t(d.inputs.at(k))]; };
    const auto mip = [&](Image image, TexelFormat format, MipReduce reduce) {
      return std::make_shared<const Texture>(make_mip_texture(image, format, false, reduce, kernel_.mip_extremum()));
    };
    switch (d.kind) {
      case DerivedKind::WeightTexture: {
        const WeightsDesc& w = desc.blend.weights;
        const Image& map = weight_map(std::size_t(d.material));
        Image level0 = resample_weight_map(map, w.resolution);
        if (w.from_vertices)
          for (std::size_t o : m.objects) {
            const MeshData& mesh = *assets_.meshes[o];
            rasterize_vertex_weights(mesh.uvs, mesh.indices, vertex_weights(map, mesh.uvs, w.scale), w.scale, level0);
          }
        out.texture = std::make_shared<const Texture>(make_weight_texture(level0, kernel_.mip_extremum()));
        break;
      }
      case DerivedKind::CombinedSurface: {
        // The blended box surface with per-pixel weights over the repeats the weights span, made once for the
        // combined quadtree, the exact reference (per-vertex errors then show the floating) and the baked AO.
        std::vector<const Texture*> heights;
        for (const LayerPlan& l : m.layers) heights.push_back(assets_.textures[std::size_t(l.height)].get());
        out.field = std::make_shared<const HeightField>(
            combined_surface(heights, *input(0).texture, m.weights_scale, desc.blend.op));
        break;
      }
      case DerivedKind::CombinedQuadtree: {
        // Inputs: the weight texture last, the fp64 surface first where the tree is made from it (no box values).
        const Texture& weights = *input(d.inputs.size() - 1).texture;
        std::vector<const Texture*> chains;
        for (const LayerPlan& l : m.layers) chains.push_back(assets_.textures[std::size_t(l.height_max)].get());
        if (LayerHeights heights = interleave_layer_heights(chains); heights.width > 0) {
          out.layer_heights = std::make_shared<const LayerHeights>(std::move(heights));
          const BlendBoxSource source{&weights, m.weights_scale, out.layer_heights.get(), desc.blend.op,
                                      int(m.layers.size())};
          if (const std::size_t count = blend_box_value_count(source); count > 0) {
            ZeroedBuffer<float> values(count);  // zero pages, committed by the rows' threads
            kernel_.blend_box_values(source, values.data());
            out.box_values = std::make_shared<const ZeroedBuffer<float>>(std::move(values));
          }
        }
        if (d.inputs.size() == 1) {
          // The tree (and the blend's AO map) of the values the walk reads: the plan made no fp64 surface for them.
          if (!out.box_values) throw Error(d.where, "internal: the plan expected the blend's box values");
          out.texture = std::make_shared<const Texture>(combined_quadtree(
              box_value_view(*out.box_values, *out.layer_heights, m.weights_scale), kernel_.mip_extremum()));
        } else {
          out.texture = std::make_shared<const Texture>(combined_quadtree(*input(0).field, kernel_.mip_extremum()));
        }
        break;
      }
      case DerivedKind::BlendAoMap: {
        AoDesc ao = desc.ao;
        ao.radius /= float(m.weights_scale);  // the field's UV spans `scale` repeats
        ao.resolution = d.side;
        const DerivedAsset& surface = input(0);  // the combined quadtree with its box values, or the fp64 surface
        const auto bake = [&](const auto& field) {
          return mip(ao_map(field, desc.technique.depth_scale, ao, d.dynamic, kernel_.ao_map_row(), plan_.scene.frame,
                            previous_.ao_history(index, d), out.ao_history),
                     TexelFormat::R16, MipReduce::Box);
        };
        out.texture = surface.field ? bake(height_view(*surface.field))
                                    : bake(box_value_view(*surface.box_values, *surface.layer_heights, m.weights_scale));
        break;
      }
      case DerivedKind::TwinTexels:
        out.twin_texels = std::make_shared<const std::vector<float>>(interleave_twin_texels(
            *assets_.textures[std::size_t(d.texture)], *assets_.textures[std::size_t(d.second_texture)]));
        break;
      case DerivedKind::HeightField:
        out.field = std::make_shared<const HeightField>(
            height_field(*assets_.textures[std::size_t(d.texture)], desc.sampling.address));
        break;
      case DerivedKind::LayerAoMap:
        // Each layer's AO baked from its stored heights (cached by content); blended like the colours when shading.
        out.texture = mip(ao_map(height_view(*input(0).field), desc.technique.depth_scale, desc.ao, d.dynamic, kernel_.ao_map_row(),
                                 plan_.scene.frame, previous_.ao_history(index, d), out.ao_history),
                          TexelFormat::R16, MipReduce::Box);
        break;
      case DerivedKind::ConeMap:
        // A dynamic surface's maps are baked every frame and never kept: the cache would fill with frames.
        out.cones = std::make_shared<const ConeMap>(d.dynamic ? bake_cone_map(*input(0).field, m.cone_kind)
                                                              : load_or_bake_cone_map(*input(0).field, m.cone_kind,
                                                                                      default_cache_dir()));
        break;
      case DerivedKind::BilinearBound:
        // QDM walks a quadtree of the 3x3 maxima, conservative for the bilinear surface it then solves exactly.
        out.texture = mip(bilinear_upper_bound(*input(0).field), TexelFormat::R32F, MipReduce::Max);
        break;
    }
    record(d.key, plan_.meshes.size() + plan_.textures.size() + index,
           {"derived " + std::to_string(index), derived_kind_name(d.kind), d.where}, start);
  }

  const FramePlan& plan_;
  const Kernel& kernel_;
  const Previous& previous_;
  Assets& assets_;
  const std::function<void(double)>& progress_;
  SpareTextures* spares_;
  std::string file_;
  Clock::time_point begin_;
  std::size_t items_ = 0;
  std::mutex mutex_;
  std::vector<std::pair<std::size_t, PrepareStep>> steps_;
  std::map<std::size_t, Image> weight_maps_;
  std::vector<std::string> built_;
};

}  // namespace

std::uint64_t Assets::texture_bytes() const {
  std::uint64_t bytes = 0;
  for (const auto& t : textures) bytes += t->bytes();
  return bytes;
}

std::uint64_t Assets::mesh_bytes() const {
  std::uint64_t bytes = 0;
  for (const auto& m : meshes)
    bytes += m->vertex_count() * (sizeof(glm::vec3) * 2 + sizeof(glm::vec4) + sizeof(glm::vec2)) +
             (m->indices.size() + m->triangle_materials.size()) * sizeof(std::uint32_t);
  return bytes;
}

Texture SpareTextures::take(int width, int height, TexelFormat format, bool wrap_footprints) {
  for (auto it = textures.begin(); it != textures.end(); ++it) {
    const Texture& t = **it;
    if (it->use_count() != 1 || t.format != format || t.width() != width || t.height() != height ||
        t.wrap_footprints.empty() == wrap_footprints)
      continue;
    // prepare makes every texture of Assets::textures as a non-const object; held only here, it may be emptied.
    Texture out = std::move(*std::const_pointer_cast<Texture>(*it));
    textures.erase(it);
    return out;
  }
  return Texture{};
}

Assets prepare(const FramePlan& plan, const Kernel& kernel, const Assets* previous, const FramePlan* previous_plan,
               const std::function<void(double)>& progress, SpareTextures* spares) {
  Assets assets;
  const Previous reuse(previous, previous_plan);
  Preparer(plan, kernel, reuse, assets, progress, spares).run();
  return assets;
}

}  // namespace qdmr
