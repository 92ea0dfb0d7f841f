#include "qdmr/core/stats.hpp"

#include <nlohmann/json.hpp>

#include "qdmr/core/version.hpp"

namespace qdmr {

nlohmann::json RenderStats::to_json() const {
  nlohmann::json j;
  j["qdmr_version"] = version();
  j["bits_version"] = kBitsVersion;
  j["time_ms"] = {{"load", load_ms},         {"plan", plan_ms},         {"prepare", prepare_ms},
                  {"geometry", geometry_ms}, {"binning", binning_ms},   {"raster_shade", raster_shade_ms},
                  {"draw", draw_ms()},       {"write", write_ms},
                  {"total", load_ms + plan_ms + prepare_ms + draw_ms() + write_ms}};
  if (frame >= 0)
    j["frame"] = {{"number", frame}, {"time_s", time_s}, {"rebuild_ms", prepare_ms}, {"draw_ms", draw_ms()}};
  j["triangles"] = {{"in", triangles_in}, {"culled", triangles_culled}, {"clipped", triangles_clipped},
                    {"rasterized", triangles_rasterized}};
  j["tiles"] = {{"count", tiles}, {"size", tile_size}, {"bin_entries", tile_bin_entries}};
  j["blocks"] = {{"rejected", blocks_rejected}, {"full", blocks_full}, {"partial", blocks_partial}};
  j["shading"] = {{"batches", batches}, {"quads", quads}, {"pixels_shaded", pixels_shaded},
                  {"pixels_depth_failed", pixels_depth_failed}, {"simd_lanes", simd_lanes}, {"simd_arch", simd_arch}};
  j["iterations"] = {{"mean", iterations_mean}, {"p99", iterations_p99}, {"max", iterations_max},
                     {"lane_utilisation", lane_utilisation}};
  if (reference)
    j["reference"] = {{"pixels", reference_pixels}, {"error_texels_mean", error_texels_mean},
                      {"error_texels_max", error_texels_max}, {"missed_fraction", missed_fraction}};
  if (texture_cache.enabled) {
    const TextureCacheStats& c = texture_cache;
    j["texture_cache"] = {{"layout", c.layout},
                          {"quadtree", c.quadtree},
                          {"replacement", c.replacement},
                          {"size_bytes", c.size_bytes},
                          {"line_bytes", c.line_bytes},
                          {"ways", c.ways},
                          {"region", c.region},
                          {"warp", c.warp},
                          {"accesses", c.accesses},
                          {"hits", c.hits},
                          {"misses", c.misses},
                          {"miss_ratio", c.miss_ratio},
                          {"accesses_per_pixel", c.accesses_per_pixel},
                          {"misses_per_pixel", c.misses_per_pixel},
                          {"bytes_per_pixel", c.bytes_per_pixel},
                          {"footprint_bytes", c.footprint_bytes}};
  }
  j["threads"] = threads;
  j["isa"] = simd_arch;
  j["memory"] = {{"framebuffer_bytes", framebuffer_bytes}, {"texture_bytes", texture_bytes},
                 {"mesh_bytes", mesh_bytes}, {"peak_rss_bytes", peak_rss_bytes}};
  j["prepare"] = {{"items_built", items_built}, {"items_reused", items_reused}, {"steps", nlohmann::json::array()}};
  for (const PrepareStep& step : prepare_steps)
    j["prepare"]["steps"].push_back({{"item", step.item}, {"what", step.what}, {"where", step.where}, {"start_ms", step.start_ms}, {"ms", step.ms}});
  j["materials"] = nlohmann::json::array();
  for (const MaterialStat& m : materials) j["materials"].push_back({{"name", m.name}, {"variant", m.variant}});
  j["textures"] = nlohmann::json::array();
  for (const TextureStat& t : textures) {
    nlohmann::json entry = {{"where", t.where},   {"purpose", t.purpose}, {"format", t.format}, {"width", t.width},
                            {"height", t.height}, {"levels", t.levels},   {"bytes", t.bytes}};
    if (!t.height_format.empty()) entry["height_format"] = t.height_format;
    if (t.bc3) entry["bc3"] = {{"max_error", t.bc3_max_error}, {"rms_error", t.bc3_rms_error}};
    j["textures"].push_back(entry);
  }
  return j;
}

}  // namespace qdmr
