#pragma once
// What a frame cost and did: timings per stage, counters of every stage, what was built. Filled by prepare and
// draw, completed by whoever loads and writes; `qdmr render --stats` writes it as JSON.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace qdmr {

// What was built for one texture of the frame.
struct TextureStat {
  std::string where;    // the scene field it came from
  std::string purpose;  // albedo, normal, height
  std::string format;   // storage format of the chain, e.g. "rgba8 srgb"
  int width = 0, height = 0, levels = 0;
  std::uint64_t bytes = 0;
  std::string height_format;  // heights behind it (from_height normals, heights): storage format, else empty
  bool bc3 = false;           // the height was BC3-compressed; errors in 8-bit steps
  double bc3_max_error = 0, bc3_rms_error = 0;
};

// One item prepare built (not one it reused), as `qdmr plan` numbers it: its build's wall time. Items are built
// in parallel where they do not depend on each other, so the steps' times overlap and may add up to more than
// prepare_ms.
struct PrepareStep {
  std::string item;   // "mesh 0", "texture 3", "derived 7": the plan's numbering
  std::string what;   // the texture's purpose or the derived kind: "albedo", "combined_quadtree", "blend_ao_map"
  std::string where;  // the scene field it came from
  double start_ms = 0;  // when its build began, from the start of the preparation (steps overlap where built side by side)
  double ms = 0;
};

// The program that ran for one material: its variant, taken from the instantiated program type.
struct MaterialStat {
  std::string name;
  std::string variant;
};

// The emulated texture cache over the frame (scene key texture_cache): its settings, the texel reads replayed
// through it and their outcome. Per pixel: divided by the pixels shaded (written).
struct TextureCacheStats {
  bool enabled = false;
  std::string layout, quadtree, replacement;
  int size_bytes = 0, line_bytes = 0, ways = 0, region = 0, warp = 0;
  std::uint64_t accesses = 0, hits = 0, misses = 0;
  double miss_ratio = 0, accesses_per_pixel = 0, misses_per_pixel = 0, bytes_per_pixel = 0;  // bytes: misses x line
  std::uint64_t footprint_bytes = 0;  // the textures' memory in this layout (padding and 3D slices included)
};

struct RenderStats {
  // Milliseconds per stage; load and write are filled in by whoever loads and writes. prepare_ms is 0 for a
  // frame that re-used everything.
  double load_ms = 0, plan_ms = 0, prepare_ms = 0, geometry_ms = 0, binning_ms = 0, raster_shade_ms = 0, write_ms = 0;
  double draw_ms() const { return geometry_ms + binning_ms + raster_shade_ms; }
  std::uint64_t triangles_in = 0, triangles_culled = 0, triangles_clipped = 0, triangles_rasterized = 0;
  std::uint64_t tiles = 0, tile_bin_entries = 0, blocks_rejected = 0, blocks_full = 0, blocks_partial = 0;
  std::uint64_t batches = 0, quads = 0, pixels_shaded = 0, pixels_depth_failed = 0;
  // Intersection iterations per written pixel (0 for normal mapping); p99 and max from a histogram capped at
  // 1024 (a max of 1024 means "1024 or more"). Lane utilisation: useful lane-iterations / executed ones.
  double iterations_mean = 0, iterations_p99 = 0, iterations_max = 0, lane_utilisation = 1;
  // Against the exact reference, over the covered pixels, when the error_texels or missed AOV is rendered.
  bool reference = false;
  std::uint64_t reference_pixels = 0;
  double error_texels_mean = 0, error_texels_max = 0, missed_fraction = 0;
  int threads = 0, tile_size = 0, simd_lanes = 0;
  std::string simd_arch;  // the draw kernel's ISA: "sse4.2", "avx2"
  std::uint64_t framebuffer_bytes = 0, texture_bytes = 0, mesh_bytes = 0, peak_rss_bytes = 0;
  std::uint64_t items_built = 0, items_reused = 0;  // prepare: plan items built, and taken from the previous frame
  std::vector<PrepareStep> prepare_steps;           // the items built, in plan order
  std::vector<TextureStat> textures;
  std::vector<MaterialStat> materials;
  TextureCacheStats texture_cache;
  // The frame of the scene's animation this is (qdmr render --frames / --frame), and its time; -1: a still render.
  // Its prepare_ms is then the frame's rebuild of the dynamic items (after the sequence's first frame).
  int frame = -1;
  double time_s = 0;

  nlohmann::json to_json() const;
};

}  // namespace qdmr
