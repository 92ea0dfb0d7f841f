#pragma once
// The write stage: a frame's pixels, AOVs and statistics to files, each through a temporary file in the same
// folder and a rename, so a failed or killed write leaves the previous file (or none), never a torn one.
#include <filesystem>
#include <optional>
#include <span>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/core/aov.hpp"
#include "qdmr/core/stats.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

// How images are written. By default a file holds no wall-clock time, so the same frame gives the same bytes
// (OpenImageIO's DateTime is written empty in EXR and TIFF; PNG gets no tIME chunk).
struct WriteOptions {
  bool timestamp = false;  // true: DateTime = the current local time, "YYYY:MM:DD hh:mm:ss" (EXR capDate,
                           // TIFF tag 306, PNG tIME chunk)
  // PNG pixel data compressed as small as libdeflate can (its level 12: 10-25 % smaller, seconds for a 1080p
  // frame) instead of as fast as ISA-L's igzip can (its level 1: about 15 ms). The same pixels either way.
  bool smallest_png = false;
  // At most this many threads encode and compress the file (1: the calling thread alone), as RenderOptions::threads
  // bounds a draw; 0: the caller's task arena (every core, or the renderer's threads inside its arena). The same
  // bytes on any count.
  int threads = 0;
};

// Writes the colour image (PNG: 8-bit sRGB, TIFF: 16-bit sRGB, EXR: 32-bit float linear), with the metadata
// "qdmr:bits_version" and Software = "qdmr <version> (bits version N)" (qdmr/core/version.hpp; TIFF keeps
// only the latter). Throws qdmr::Error.
void write_frame(const Frame& frame, const std::filesystem::path& file, const WriteOptions& write = {});
// Writes any image of `channels` floats per pixel, rows from the top, as write_frame writes the colour: PNG
// 8-bit and TIFF 16-bit codes, sRGB-encoded when `srgb`, else linear and clamped to [0, 1]; EXR the floats as
// they are. write_frame is this with 3 channels and srgb. Throws qdmr::Error.
void write_image(const std::filesystem::path& file, int width, int height, int channels, std::span<const float> pixels,
                 bool srgb, const WriteOptions& write = {});
// Writes the stats as JSON.
void write_stats(const RenderStats& stats, const std::filesystem::path& file);
// Writes any JSON document (indented by 2), e.g. `qdmr bench --json`.
void write_json(const nlohmann::json& document, const std::filesystem::path& file);
// Writes one AOV (EXR/TIFF: float data; PNG: 8-bit for viewing: normals mapped to 0.5 + 0.5 n, UVs to their
// fractional part, depth, iterations, hit depth and errors divided by their maximum).
void write_aov(const Frame& frame, Aov aov, const std::filesystem::path& file, const WriteOptions& write = {});

// What a file of `file`'s type (by extension) would hold for the colour image (no `aov`) or an AOV of the frame,
// as read_image returns such a file (codes / 255 for PNG, / 65535 for a colour TIFF, floats for EXR) but with
// rows from the top. `qdmr check` compares renders with golden files in this form.
Image stored_pixels(const Frame& frame, std::optional<Aov> aov, const std::filesystem::path& file);

}  // namespace qdmr
