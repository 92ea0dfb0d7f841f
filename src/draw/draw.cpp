#include "draw/draw.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <tbb/parallel_for.h>

#include "qdmr/core/progress.hpp"
#include "qdmr/reference/reference_memo.hpp"
#include "qdmr/scene/scene.hpp"
#include "raster/binner.hpp"
#include "raster/geometry.hpp"
#include "texture/blend_box_values.hpp"
#include "texture/cache_model.hpp"

namespace qdmr {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The camera's view and projection matrices (OpenGL conventions): the geometry stage's and the light rig's.
glm::mat4 view_matrix(const CameraDesc& camera) { return glm::lookAt(camera.position, camera.target, camera.up); }

glm::mat4 projection_matrix(const CameraDesc& camera, const OutputDesc& output) {
  return glm::perspective(glm::radians(camera.fov_y_deg), float(output.width) / float(output.height), camera.near,
                          camera.far);
}

// The scene's lights and camera as the programs read them.
LightRig light_rig(const SceneDesc& scene) {
  LightRig rig;
  for (const auto& d : scene.lights.directional)
    rig.directional.push_back({glm::normalize(d.direction), d.color * d.intensity});
  rig.ambient = scene.lights.ambient.color * scene.lights.ambient.intensity;
  rig.camera_position = scene.camera.position;
  rig.view_projection = projection_matrix(scene.camera, scene.output) * view_matrix(scene.camera);
  return rig;
}

glm::mat4 model_matrix(const TransformDesc& t) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), t.translate);
  m = glm::rotate(m, glm::radians(t.rotate_deg.z), glm::vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(t.rotate_deg.y), glm::vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(t.rotate_deg.x), glm::vec3(1, 0, 0));
  return glm::scale(m, t.scale);
}

// The error AOVs summarised over the pixels some triangle covers (depth below the clear value), in pixel order.
void summarise_reference(const Framebuffer& fb, RenderStats& stats) {
  const PixelBuffer& error = fb.aov[std::size_t(Aov::ErrorTexels)];
  const PixelBuffer& missed = fb.aov[std::size_t(Aov::Missed)];
  if (error.empty() && missed.empty()) return;
  stats.reference = true;
  double error_sum = 0.0, missed_sum = 0.0;
  for (std::size_t i = 0; i < fb.depth.size(); ++i) {
    if (!(fb.depth[i] < 1.0f)) continue;
    ++stats.reference_pixels;
    if (!error.empty()) {
      error_sum += error[i];
      stats.error_texels_max = std::max(stats.error_texels_max, double(error[i]));
    }
    if (!missed.empty()) missed_sum += missed[i];
  }
  if (stats.reference_pixels == 0) return;
  stats.error_texels_mean = error_sum / double(stats.reference_pixels);
  stats.missed_fraction = missed_sum / double(stats.reference_pixels);
}

void summarise_counters(const TileCounters& total, RenderStats& stats) {
  stats.tile_bin_entries = total.bin_entries;
  stats.blocks_rejected = total.blocks_rejected;
  stats.blocks_full = total.blocks_full;
  stats.blocks_partial = total.blocks_partial;
  stats.batches = total.batches_shaded;
  stats.quads = total.quads_shaded;
  stats.pixels_shaded = total.pixels_shaded;
  stats.pixels_depth_failed = total.pixels_depth_failed;
  stats.iterations_mean = stats.iterations_p99 = stats.iterations_max = 0;
  if (total.pixels_shaded > 0) {
    stats.iterations_mean = double(total.iterations_useful) / double(total.pixels_shaded);
    std::uint64_t seen = 0;
    const std::uint64_t p99_rank = (total.pixels_shaded * 99 + 99) / 100;  // ceil(0.99 n)
    bool p99_found = false;
    for (std::size_t i = 0; i < total.iteration_histogram.size(); ++i) {
      if (total.iteration_histogram[i] == 0) continue;
      seen += total.iteration_histogram[i];
      if (!p99_found && seen >= p99_rank) {
        stats.iterations_p99 = double(i);
        p99_found = true;
      }
      stats.iterations_max = double(i);
    }
  }
  stats.lane_utilisation =
      total.iterations_executed > 0 ? double(total.iterations_useful) / double(total.iterations_executed) : 1.0;
}

// Every texture the frame's programs read, at its address under the cache's layout, registered in plan order.
TextureAddressMap cache_address_map(const FramePlan& plan, const Assets& assets) {
  const TextureCacheDesc& cache = plan.scene.texture_cache;
  TextureAddressMap map(cache.layout, cache.quadtree);
  const auto texture = [&](int i, bool quadtree) {
    if (i < 0) return;
    const bool bc3 = plan.textures[std::size_t(i)].desc.compression == Compression::Bc3;
    map.add(*assets.textures[std::size_t(i)], quadtree, bc3);
  };
  const auto derived = [&](int i, bool quadtree) {
    if (i >= 0 && assets.derived[std::size_t(i)].texture) map.add(*assets.derived[std::size_t(i)].texture, quadtree, false);
  };
  for (const MaterialPlan& m : plan.materials) {
    for (const LayerPlan& l : m.layers) {
      texture(l.albedo, false);
      texture(l.normal, false);
      texture(l.orm, false);
      texture(l.height, false);
      texture(l.height_max, true);
      derived(l.ao, false);
    }
    derived(m.weights, false);
    derived(m.combined_quadtree, true);
    derived(m.blend_ao, false);
    derived(m.bilinear_bound, true);
  }
  return map;
}

void summarise_cache(const TextureCacheDesc& desc, const TextureAddressMap& map, const TileCounters& total,
                     RenderStats& stats) {
  TextureCacheStats& c = stats.texture_cache;
  c.enabled = true;
  c.layout = texel_layout_name(desc.layout);
  c.quadtree = quadtree_storage_name(desc.quadtree);
  c.replacement = cache_replacement_name(desc.replacement);
  c.size_bytes = desc.size_bytes;
  c.line_bytes = desc.line_bytes;
  c.ways = desc.ways;
  c.region = desc.region;
  c.warp = desc.warp;
  c.accesses = total.cache_accesses;
  c.hits = total.cache_hits;
  c.misses = total.cache_accesses - total.cache_hits;
  c.miss_ratio = c.accesses > 0 ? double(c.misses) / double(c.accesses) : 0.0;
  const double pixels = double(std::max<std::uint64_t>(total.pixels_shaded, 1));
  c.accesses_per_pixel = double(c.accesses) / pixels;
  c.misses_per_pixel = double(c.misses) / pixels;
  c.bytes_per_pixel = double(c.misses) * double(desc.line_bytes) / pixels;
  c.footprint_bytes = map.footprint_bytes();
}

}  // namespace

std::vector<std::unique_ptr<Program>> make_programs(const FramePlan& plan, const Assets& assets, const Kernel& kernel,
                                                    ReferenceMemo* memo) {
  const LightRig lights = light_rig(plan.scene);
  std::vector<std::unique_ptr<Program>> programs;
  for (const MaterialPlan& m : plan.materials) {
    const auto texture = [&](int i) { return i >= 0 ? assets.textures[std::size_t(i)].get() : nullptr; };
    const auto derived = [&](int i) -> const DerivedAsset* { return i >= 0 ? &assets.derived[std::size_t(i)] : nullptr; };
    DisplacementInputs inputs;
    for (const LayerPlan& l : m.layers) {
      const DerivedAsset* ao = derived(l.ao);
      const DerivedAsset* twin = derived(l.twin);
      inputs.layers.push_back({texture(l.albedo), texture(l.normal), texture(l.height), texture(l.height_max),
                               ao ? ao->texture.get() : nullptr,
                               twin && !twin->twin_texels->empty() ? twin->twin_texels->data() : nullptr,
                               texture(l.orm)});
    }
    if (const DerivedAsset* w = derived(m.weights); w && m.weight_mode == WeightMode::Pixel) inputs.weights = w->texture.get();
    if (const DerivedAsset* c = derived(m.combined_quadtree)) {
      inputs.combined = c->texture.get();
      inputs.layer_heights = c->layer_heights.get();
      inputs.box_values = c->box_values ? c->box_values->data() : nullptr;
      // The period of its box values where it has them, else of the fp64 surface it was made from.
      if (c->box_values) {
        const HeightView<float> values = box_value_view(*c->box_values, *c->layer_heights, m.weights_scale);
        inputs.combined_period_u = values.width;
        inputs.combined_period_v = values.height;
      } else {
        const HeightField& combined = *assets.derived[std::size_t(m.combined_surface)].field;
        inputs.combined_period_u = combined.width;
        inputs.combined_period_v = combined.height;
      }
    }
    if (const DerivedAsset* a = derived(m.blend_ao)) {
      inputs.blend_ao = a->texture.get();
      inputs.blend_ao_scale = m.weights_scale;
    }
    if (const DerivedAsset* c = derived(m.cones)) inputs.cones = c->cones.get();
    if (const DerivedAsset* b = derived(m.bilinear_bound)) {
      // QDM then walks the bound's quadtree and solves the fp64 bilinear patches exactly.
      inputs.layers[0].height_max = b->texture.get();
      inputs.surface = assets.derived[std::size_t(m.layers[0].field)].field.get();
    }
    if (m.reference) {
      const auto& field = assets.derived[std::size_t(m.blend ? m.combined_surface : m.layers[0].field)].field;
      inputs.reference = field.get();
      if (m.blend) inputs.reference_scale = m.weights_scale;
      if (memo) {
        inputs.reference_memo = memo;
        inputs.reference_id = memo->field_id(field);
      }
    }
    programs.push_back(kernel.make_program(m.key, m.params, inputs, lights));
  }
  return programs;
}

std::uint64_t DrawScratch::bytes() const {
  const auto capacity = [](const auto& v) { return std::uint64_t(v.capacity()) * sizeof(v[0]); };
  const ItemVertices& item = geometry_scratch.item;
  std::uint64_t total = capacity(item.frustum_code) + capacity(item.band_code) + capacity(item.screen) +
                        capacity(geometry.vertices) + capacity(geometry.triangles) +
                        capacity(tile_counters);
  for (const GeometryChunk& chunk : geometry_scratch.chunks)
    total += capacity(chunk.triangles) + capacity(chunk.clipped_vertices);
  for (const auto& chunk : bins.bins)
    for (const auto& tile : chunk) total += capacity(tile);
  return total;
}

void draw(const FramePlan& plan, const Assets& assets, const Kernel& kernel,
          const std::vector<std::unique_ptr<Program>>& programs, Framebuffer& fb, DrawScratch& scratch,
          const DrawOptions& options, RenderStats& stats) {
  const SceneDesc& scene = plan.scene;
  auto start = Clock::now();
  const Viewport viewport{plan.width, plan.height};
  std::vector<DrawItem> items(plan.meshes.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    items[i].mesh = assets.meshes[i].get();
    items[i].material = plan.meshes[i].material;
    items[i].mesh_materials = plan.meshes[i].mtl_materials;
    items[i].model = model_matrix(scene.objects[i].transform);
  }
  const glm::mat4 view = view_matrix(scene.camera);
  const glm::mat4 projection = projection_matrix(scene.camera, scene.output);
  run_geometry(items, view, projection, viewport, scratch.geometry_scratch, scratch.geometry);
  const GeometryResult& geometry = scratch.geometry;
  stats.geometry_ms = ms_since(start);
  stats.triangles_in = geometry.counters.triangles_in;
  stats.triangles_culled = geometry.counters.culled_backface + geometry.counters.culled_outside;
  stats.triangles_clipped = geometry.counters.clipped;
  stats.triangles_rasterized = geometry.counters.triangles_out;

  start = Clock::now();
  const TileGrid grid(viewport.width, viewport.height, options.tile_size);
  TileBins& bins = scratch.bins;
  bin_triangles(geometry, viewport, grid, bins);
  stats.binning_ms = ms_since(start);
  stats.tiles = std::uint64_t(grid.count());
  stats.tile_size = options.tile_size;

  start = Clock::now();
  fb.resize(plan.width, plan.height, plan.aovs);
  fb.background = scene.output.background;
  stats.framebuffer_bytes = fb.bytes();
  RasterContext context;
  context.geometry = &geometry;
  context.framebuffer = &fb;
  for (const auto& program : programs) context.programs.push_back(program.get());
  std::optional<TextureAddressMap> cache_addresses;
  if (scene.texture_cache.enabled) {
    cache_addresses.emplace(cache_address_map(plan, assets));
    context.cache = &scene.texture_cache;
    context.cache_addresses = &*cache_addresses;
  }
  std::vector<TileCounters>& tile_counters = scratch.tile_counters;  // kept: 8 KiB each, zeroed by their tiles
  tile_counters.resize(std::size_t(grid.count()));
  std::atomic<int> tiles_done{0};
  std::mutex progress_mutex;
  const int report_every = std::max(1, grid.count() / 100);
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.count(), 1), [&](const auto& range) {
    for (int tile = range.begin(); tile != range.end(); ++tile) {
      throw_if_stop_requested();  // Ctrl-C (qdmr/core/progress.hpp): the frame stops at the next tile
      TileCounters& counters = tile_counters[std::size_t(tile)];
      counters.reset();
      kernel.raster_tile(context, tile, grid.rect(tile), bins, counters);
      const int done = ++tiles_done;
      if (options.progress && done % report_every == 0) {
        std::lock_guard lock(progress_mutex);
        options.progress(double(done) / grid.count());
      }
    }
  });
  TileCounters total;
  for (const TileCounters& c : tile_counters) total += c;  // in tile order
  stats.raster_shade_ms = ms_since(start);
  summarise_counters(total, stats);
  stats.texture_cache = TextureCacheStats{};
  if (cache_addresses) summarise_cache(scene.texture_cache, *cache_addresses, total, stats);
  stats.reference = false;
  stats.reference_pixels = 0;
  stats.error_texels_mean = stats.error_texels_max = stats.missed_fraction = 0;
  summarise_reference(fb, stats);
  stats.simd_lanes = kernel.lanes();
  stats.simd_arch = isa_name(kernel.isa());
  stats.materials.clear();
  for (std::size_t i = 0; i < programs.size(); ++i) stats.materials.push_back({plan.materials[i].name, programs[i]->variant()});
}

}  // namespace qdmr
