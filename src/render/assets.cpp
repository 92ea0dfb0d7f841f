#include "render/assets.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

#include "qdmr/bake/ao_map.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/texture/height_texture.hpp"
#include "texture/blend_weights.hpp"
#include "shade/displacement.hpp"
#include "shade/normal_mapping.hpp"

namespace qdmr {
namespace {

// Builds one requested texture. Heights (and the heights behind from_height normals) go through the storage
// the scene asks for — quantisation, BC3 — so what is rendered is what a GPU would sample.
Texture build_texture(const TextureRequest& request, TextureStat& stat) {
  const bool needs_height = request.purpose == TexturePurpose::Height || request.desc.source == TextureSource::FromHeight;
  Texture texture;
  Image height;
  if (needs_height) {
    // Behind a from_height normal map only level 0 is used: any reduction will do.
    const MipReduce reduce = request.purpose == TexturePurpose::Height ? request.reduce : MipReduce::Box;
    HeightTexture stored = make_height_texture(make_layer_height(request.layer, request.where), request.layer.height, reduce);
    stat.height_format = format_name(stored.texture.format);
    if (stored.bc3) {
      stat.bc3 = true;
      stat.bc3_max_error = stored.bc3->max_error;
      stat.bc3_rms_error = stored.bc3->rms_error;
    }
    if (request.purpose == TexturePurpose::Height)
      texture = std::move(stored.texture);
    else
      height = stored.texture.level_image(0);
  }
  if (request.purpose != TexturePurpose::Height) {
    Image level0 = make_texture(request.desc, request.purpose, request.layer, needs_height ? &height : nullptr, request.where);
    if (request.purpose == TexturePurpose::Normal)
      for (float& v : level0.texels) v = 0.5f + 0.5f * v;  // stored as UNORM, as normal maps are
    texture = make_mip_texture(level0, request.format, request.srgb, request.reduce);
  }
  stat.where = request.where;
  stat.purpose = purpose_name(request.purpose);
  stat.format = format_name(texture.format) + (texture.srgb ? " srgb" : "");
  stat.width = texture.width();
  stat.height = texture.height();
  stat.levels = texture.level_count();
  stat.bytes = texture.bytes();
  return texture;
}

// Level 0 of a stored height texture in fp64, for the exact reference and the bakes.
HeightField height_field(const Texture& h, AddressMode address) {
  HeightField field;
  field.width = h.width();
  field.height = h.height();
  field.address = address;
  field.h.resize(std::size_t(h.width()) * std::size_t(h.height()));
  for (int y = 0; y < h.height(); ++y)
    for (int x = 0; x < h.width(); ++x) field.h[std::size_t(y) * std::size_t(h.width()) + std::size_t(x)] = h.texel(0, x, y, 0);
  return field;
}

}  // namespace

std::vector<DrawItem> Assets::draw_items() const {
  std::vector<DrawItem> items(meshes.size());
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    items[i].mesh = &meshes[i];
    items[i].material = object_material[i];
    items[i].mesh_materials = object_mtl_materials[i];
  }
  return items;
}

std::uint64_t Assets::texture_bytes() const {
  std::uint64_t bytes = 0;
  for (const Texture& t : textures) bytes += t.bytes();
  return bytes;
}

std::uint64_t Assets::mesh_bytes() const {
  std::uint64_t bytes = 0;
  for (const MeshData& m : meshes)
    bytes += m.vertex_count() * (sizeof(glm::vec3) * 2 + sizeof(glm::vec4) + sizeof(glm::vec2)) +
             (m.indices.size() + m.triangle_materials.size()) * sizeof(std::uint32_t);
  return bytes;
}

Assets prepare_assets(const SceneDesc& scene, const LightRig& lights, const RenderOptions& options) {
  Assets assets;
  const std::string file = scene.file.string();
  const std::size_t objects = scene.objects.size();
  assets.meshes.resize(objects);
  tbb::parallel_for(std::size_t(0), objects, [&](std::size_t i) {
    assets.meshes[i] = build_mesh(scene.objects[i].mesh, file + ": /objects/" + std::to_string(i) + "/mesh");
  });

  // Frame materials: the scene's materials that some object uses, then each obj's MTL materials.
  std::vector<MaterialDesc> material_descs;  // parallel to assets.materials
  std::vector<int> scene_material_index(scene.materials.size(), -1);
  assets.object_material.assign(objects, 0);
  assets.object_mtl_materials.resize(objects);
  for (std::size_t i = 0; i < objects; ++i) {
    const ObjectDesc& object = scene.objects[i];
    if (!object.material.empty()) {
      std::size_t m = 0;
      while (m < scene.materials.size() && scene.materials[m].name != object.material) ++m;
      if (m == scene.materials.size())
        throw Error(file + ": /objects/" + std::to_string(i) + "/material", "unknown material '" + object.material + "'");
      if (scene_material_index[m] < 0) {
        scene_material_index[m] = int(assets.materials.size());
        material_descs.push_back(scene.materials[m]);
        assets.materials.push_back(plan_material(scene.materials[m], file + ": /materials/" + scene.materials[m].name,
                                                 assets.requests));
      }
      assets.object_material[i] = std::uint32_t(scene_material_index[m]);
      // An explicit material overrides the MTL: every triangle of the object uses it.
      assets.object_mtl_materials[i].assign(assets.meshes[i].materials.size(), assets.object_material[i]);
      continue;
    }
    for (std::size_t k = 0; k < assets.meshes[i].materials.size(); ++k) {
      MaterialDesc mtl = assets.meshes[i].materials[k];
      mtl.name = object.name + "/" + mtl.name;
      assets.object_mtl_materials[i].push_back(std::uint32_t(assets.materials.size()));
      assets.materials.push_back(plan_material(mtl, file + ": /objects/" + std::to_string(i) + "/mesh/file", assets.requests));
      material_descs.push_back(std::move(mtl));
    }
    if (assets.meshes[i].materials.empty())
      throw Error(file + ": /objects/" + std::to_string(i) + "/material", "required (the mesh has no MTL materials)");
  }

  assets.textures.resize(assets.requests.size());
  assets.texture_stats.resize(assets.requests.size());
  tbb::parallel_for(std::size_t(0), assets.requests.size(), [&](std::size_t i) {
    assets.textures[i] = build_texture(assets.requests[i], assets.texture_stats[i]);
  });

  const bool reference_aovs = std::any_of(options.aovs.begin(), options.aovs.end(),
                                          [](Aov a) { return a == Aov::ErrorTexels || a == Aov::Missed; });
  for (std::size_t i = 0; i < assets.materials.size(); ++i) {
    const MaterialPlan& m = assets.materials[i];
    const MaterialDesc& desc = material_descs[i];
    const auto texture = [&](int index) { return index >= 0 ? &assets.textures[std::size_t(index)] : nullptr; };
    if (m.technique == TechniqueKind::Normal && !m.blend) {
      assets.programs.push_back(std::make_unique<NormalMappingProgram>(
          *texture(m.layers[0].albedo), *texture(m.layers[0].normal), m.sampling, m.lighting, desc.layers[0].specular, lights));
      continue;
    }
    DisplacementInputs inputs;
    for (const LayerPlan& l : m.layers)
      inputs.layers.push_back({texture(l.albedo), texture(l.normal), texture(l.height), texture(l.height_max)});
    const bool reference = reference_aovs && m.technique != TechniqueKind::Normal;
    const Texture* weight_texture = nullptr;  // blends: the per-pixel weights (also made for references and AO)
    if (m.blend) {
      const Image map = make_weight_map(desc.blend.weights, int(desc.layers.size()), file + ": /materials/" + desc.name + "/blend/weights");
      const WeightsDesc& w = desc.blend.weights;
      Image level0 = resample_weight_map(map, w.resolution);
      for (std::size_t k = 0; k < objects; ++k) {
        if (assets.object_material[k] != i || scene.objects[k].material.empty()) continue;
        MeshData& mesh = assets.meshes[k];
        std::vector<glm::vec4> at_vertices = vertex_weights(map, mesh.uvs, w.scale);
        if (m.weight_mode == WeightMode::Vertex)
          mesh.blend_weights = std::move(at_vertices);
        else if (w.from_vertices)
          rasterize_vertex_weights(mesh.uvs, mesh.indices, at_vertices, w.scale, level0);
      }
      if (m.weight_mode == WeightMode::Pixel || m.combined_quadtree || reference || m.blend_ao) {
        assets.derived_textures.push_back(std::make_unique<Texture>(make_weight_texture(level0)));
        weight_texture = assets.derived_textures.back().get();
        if (m.weight_mode == WeightMode::Pixel) inputs.weights = weight_texture;
      }
      if (m.combined_quadtree || reference || m.blend_ao) {
        // The blended box surface with per-pixel weights over the repeats the weights span, made once for the
        // combined quadtree, the exact reference (per-vertex errors then show the floating) and the baked AO.
        const float scale = w.scale;
        const std::string where = file + ": /materials/" + desc.name + "/blend/weights/scale";
        if (scale != std::floor(scale)) throw Error(where, "error AOVs of a blend need a whole number of repeats");
        std::vector<const Texture*> heights;
        for (const LayerInputs& l : inputs.layers) heights.push_back(l.height);
        const std::uint64_t texels = std::uint64_t(heights[0]->width()) * heights[0]->height() * std::uint64_t(scale * scale);
        if (reference && texels > (1ull << 26))
          throw Error(where, "error AOVs of this blend need a reference of " + std::to_string(texels) +
                                 " texels (the layers' size times scale squared), more than 2^26");
        auto combined = std::make_unique<HeightField>(combined_surface(heights, *weight_texture, int(scale), desc.blend.op));
        if (m.combined_quadtree) {
          assets.derived_textures.push_back(std::make_unique<Texture>(combined_quadtree(*combined)));
          inputs.combined = assets.derived_textures.back().get();
          inputs.combined_period = combined->width;
        }
        if (m.blend_ao) {
          AoDesc ao = desc.ao;
          ao.radius /= scale;  // the field's UV spans `scale` repeats
          ao.resolution = m.ao_resolution;
          assets.derived_textures.push_back(std::make_unique<Texture>(make_mip_texture(
              load_or_bake_ao_map(*combined, desc.technique.depth_scale, ao, default_cache_dir()), TexelFormat::R16,
              false, MipReduce::Box)));
          inputs.blend_ao = assets.derived_textures.back().get();
          inputs.blend_ao_scale = int(scale);
        }
        if (reference) {
          inputs.reference = combined.get();
          inputs.reference_scale = int(scale);
          assets.reference_fields.push_back(std::move(combined));
        }
      }
    }
    if (m.ao_map && !m.blend_ao) {
      // Each layer's AO baked from its stored heights (cached by content); blended like the colours when shading.
      for (std::size_t l = 0; l < inputs.layers.size(); ++l) {
        const HeightField field = height_field(*inputs.layers[l].height, m.sampling.address);
        assets.derived_textures.push_back(std::make_unique<Texture>(make_mip_texture(
            load_or_bake_ao_map(field, desc.technique.depth_scale, desc.ao, default_cache_dir()), TexelFormat::R16, false,
            MipReduce::Box)));
        inputs.layers[l].ao = assets.derived_textures.back().get();
      }
    }
    const bool bilinear_patch =
        m.technique == TechniqueKind::Qdm && desc.technique.refinement == QdmRefinement::BilinearPatch && !m.blend;
    const bool single_reference = reference && !m.blend;
    if (single_reference || m.cone_map || bilinear_patch) {
      // The exact reference traces the stored heights, in fp64; cone maps are baked from the same values.
      auto field = std::make_unique<HeightField>(height_field(*inputs.layers[0].height, m.sampling.address));
      if (m.cone_map) {
        assets.cone_maps.push_back(
            std::make_unique<ConeMap>(load_or_bake_cone_map(*field, m.cone_kind, default_cache_dir())));
        inputs.cones = assets.cone_maps.back().get();
      }
      if (bilinear_patch) {
        // QDM walks a quadtree of the 3x3 maxima, conservative for the bilinear surface it then solves exactly.
        assets.derived_textures.push_back(std::make_unique<Texture>(
            make_mip_texture(bilinear_upper_bound(*field), TexelFormat::R32F, false, MipReduce::Max)));
        inputs.layers[0].height_max = assets.derived_textures.back().get();
        inputs.surface = field.get();
      }
      if (single_reference) inputs.reference = field.get();
      if (single_reference || bilinear_patch) assets.reference_fields.push_back(std::move(field));
    }
    assets.programs.push_back(std::make_unique<DisplacementProgram>(inputs, desc, lights));
  }
  return assets;
}

}  // namespace qdmr
