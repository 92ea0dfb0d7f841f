#pragma once
// The folder `qdmr check` writes for a failed check, everything a person needs to see what changed: per output
// the render (in the golden's file type, so it can replace the golden), the golden, PNG views of both, a
// difference heatmap, a histogram of per-pixel differences (SVG and CSV), and failures.txt with one line per
// failed metric. The file names are fixed (see docs/checks.md); the HTML report links to them.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qdmr/core/aov.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

class DiffFolder {
public:
  explicit DiffFolder(std::filesystem::path folder);  // created, emptied of an earlier run's files

  // An output compared with a golden file: `rendered` is the render as a file of the golden's type holds it,
  // `golden` the golden's values (both rows from the top).
  void add_comparison(const std::string& output, const Frame& frame, std::optional<Aov> aov, const Image& rendered,
                      const Image& golden, const std::filesystem::path& golden_file);
  // An output with no golden image (exact checks): the render as EXR and a PNG view.
  void add_render(const std::string& output, const Frame& frame, std::optional<Aov> aov);
  void finish(const std::vector<std::string>& failures);

private:
  std::filesystem::path folder_;
  std::vector<std::string> notes_;
};

// Writes an RGB image of display values in [0, 1] as an 8-bit PNG, atomically (heatmaps, views).
void write_display_png(const Image& image, const std::filesystem::path& file);

// The SVG bar chart of a delta_histogram (counts on a log scale), for reports.
std::string delta_histogram_svg(const std::vector<std::int64_t>& bins, const std::string& title);

}  // namespace qdmr
