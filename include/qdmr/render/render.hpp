#pragma once
// Rendering a scene: the library's front door. The qdmr command is a thin layer over these calls.
//
//   qdmr::SceneDesc scene = qdmr::load_scene("scenes/plane.json");
//   qdmr::Frame frame = qdmr::render_frame(scene, {});
//   qdmr::write_frame(frame, "plane.png");
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/render/pixel_buffer.hpp"
#include "qdmr/scene/scene.hpp"

namespace qdmr {

// Per-pixel outputs besides colour. Displacement AOVs: `iterations` of the intersection loop, `hit_uv` and
// `hit_depth` (UV units) of the hit; against the exact reference: `error_texels` (distance from the reference
// hit, in level-0 texels) and `missed` (1 where the technique hit more than a texel away from the reference,
// i.e. another feature or layer). Normal mapping reports 0 iterations and the hit at the polygon.
// Lighting AOVs, both in [0, 1] and 1 from programs or materials without the feature: `shadow`, the
// self-shadow visibility of the scene's first directional light (1 lit, 0 shadowed; 0 when that light is below
// the polygon; 1 with shadow mode off or no directional light) and `ao`, the ambient occlusion term that
// multiplies the ambient light (after ao.strength; 1 = open, also with ao mode off). Pixels nothing covers are
// 0 in every AOV.
enum class Aov { Depth, Normal, UV, Iterations, HitUV, HitDepth, ErrorTexels, Missed, Shadow, Ao };
inline constexpr int kAovCount = 10;
std::optional<Aov> parse_aov(const std::string& name);
std::string aov_name(Aov aov);
int aov_channels(Aov aov);
std::vector<std::string> aov_names();

struct RenderOptions {
  int threads = 0;     // 0 = every core
  int tile_size = 64;  // pixels, a multiple of 8 in [8, 1024]
  std::vector<Aov> aovs;
  // Called with a stage name ("prepare", "raster") and the fraction done, from any worker thread,
  // never concurrently with itself. Optional.
  std::function<void(const char* stage, double fraction)> progress;
};

// Throws qdmr::Error("option", ...) when options are out of range.
void validate_options(const RenderOptions& options);

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

struct RenderStats {
  // Milliseconds per stage; load and write are filled in by whoever loads and writes.
  double load_ms = 0, prepare_ms = 0, geometry_ms = 0, binning_ms = 0, raster_shade_ms = 0, write_ms = 0;
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
  std::string simd_arch;
  std::uint64_t framebuffer_bytes = 0, texture_bytes = 0, mesh_bytes = 0, peak_rss_bytes = 0;
  std::vector<TextureStat> textures;

  nlohmann::json to_json() const;
};

struct AovImage {
  Aov aov;
  int channels = 0;
  PixelBuffer pixels;  // width * height * channels
};

struct Frame {
  int width = 0, height = 0;
  PixelBuffer color;  // linear RGB, row 0 at the top
  std::vector<AovImage> aovs;
  RenderStats stats;
};

Frame render_frame(const SceneDesc& scene, const RenderOptions& options);

// How images are written. By default a file holds no wall-clock time, so the same frame gives the same bytes
// (OpenImageIO's DateTime is written empty in EXR and TIFF; PNG gets no tIME chunk).
struct WriteOptions {
  bool timestamp = false;  // true: DateTime = the current local time, "YYYY:MM:DD hh:mm:ss" (EXR capDate,
                           // TIFF tag 306, PNG tIME chunk)
};

// Writes the colour image (PNG: 8-bit sRGB, TIFF: 16-bit sRGB, EXR: 32-bit float linear) through a temporary
// file in the same folder and a rename, so a failed write leaves nothing behind. Throws qdmr::Error.
void write_frame(const Frame& frame, const std::filesystem::path& file, const WriteOptions& write = {});
// Writes the stats as JSON, atomically like the images.
void write_stats(const RenderStats& stats, const std::filesystem::path& file);
// Writes one AOV (EXR/TIFF: float data; PNG: 8-bit for viewing: normals mapped to 0.5 + 0.5 n, UVs to their
// fractional part, depth, iterations, hit depth and errors divided by their maximum).
void write_aov(const Frame& frame, Aov aov, const std::filesystem::path& file, const WriteOptions& write = {});

}  // namespace qdmr
