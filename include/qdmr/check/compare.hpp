#pragma once
// Comparing a rendered image with a golden one, idiff-style: the per-channel difference against a bound, how
// many pixels exceed it (optionally forgiving a pixel whose golden neighbour within a radius matches, for
// one-pixel shifts), RMSE and PSNR, and non-finite values. `qdmr check` and `qdmr diff` use it; docs/checks.md
// gives the exact definitions. Images hold floats, rows from the top.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qdmr/texture/image.hpp"

namespace qdmr {

// What may differ. The defaults: one 8-bit step per channel, no pixel above it.
struct Tolerance {
  double max_abs = 1.0 / 255.0;            // a channel differing by more than this makes the pixel "over"
  std::optional<std::int64_t> max_pixels;  // pixels allowed over (absent: 0 unless max_fraction is given)
  std::optional<double> max_fraction;      // fraction of all pixels allowed over, 0..1
  int radius = 0;                          // a pixel is not over when a golden pixel within this distance matches
  std::optional<double> max_rmse;          // over every channel of every pixel
  std::optional<double> min_psnr;          // dB, peak 1.0
};

struct Comparison {
  int width = 0, height = 0, channels = 0;
  bool comparable = true;          // false: sizes or channel counts differ (then only `failures` is meaningful)
  double max_abs = 0;              // largest channel difference
  int worst_x = 0, worst_y = 0, worst_channel = 0;  // where it is (from the top left)
  std::int64_t pixels_differing = 0;  // pixels with any channel not bit-identical
  std::int64_t pixels_over = 0;       // pixels over max_abs, after the radius
  double rmse = 0, psnr = 0;          // psnr is +inf for identical images
  std::int64_t nonfinite_rendered = 0, nonfinite_golden = 0;  // values that are NaN or infinite
  std::vector<std::string> failures;  // one line per failed metric: value vs bound, and where
  bool passed() const { return failures.empty(); }
  std::string summary() const;  // one line of the metrics
};

// NaN or infinity in either image is always a failure: a renderer that produces one has a bug to report.
Comparison compare_images(const Image& rendered, const Image& golden, const Tolerance& tolerance);

// An image file as compare_images takes it: any file read_image accepts, as floats (8-bit codes / 255 ...),
// rows from the top. `bits_version` (optional) gets the bits version of the qdmr that wrote it (metadata
// "qdmr:bits_version", or in TIFF the Software tag), 0 when it has none.
// Throws qdmr::Error naming the file.
Image read_comparable_image(const std::filesystem::path& file, int* bits_version = nullptr);

// The largest channel difference per pixel, scaled so `scale` (or more) is 1, through the magma colour map:
// RGB, black where the images agree. Non-finite differences are white.
Image difference_heatmap(const Image& rendered, const Image& golden, double scale);

// Pixels by their largest channel difference, in decades: [0] exactly equal (bits), [1] (0, 1e-7], [2]
// (1e-7, 1e-6] ... [8] (0.1, 1], [9] above 1 or not finite.
inline constexpr int kDeltaBins = 10;
std::vector<std::int64_t> delta_histogram(const Image& rendered, const Image& golden);
std::string delta_bin_label(int bin);  // "0", "<=1e-7", ..., ">1"

}  // namespace qdmr
