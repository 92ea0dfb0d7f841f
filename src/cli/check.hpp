#pragma once
// qdmr check and qdmr diff: golden-image checks and image comparison (docs/checks.md).
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace qdmr::cli {

// The tolerance flags shared by check and diff; absent flags keep the manifest's or the default values.
struct ToleranceArgs {
  std::optional<double> max_abs, max_fraction, max_rmse, min_psnr;
  std::optional<std::int64_t> max_pixels;
  std::optional<int> radius;
  void add_to(CLI::App& command);
};

struct CheckArgs {
  std::string target;  // a manifest, or a scene with --golden / --hash
  std::string golden, hash;
  std::vector<std::string> sets;
  std::optional<int> width, height;
  bool update = false;
  std::string junit, report, json, diff_dir = "qdmr-check-failures";
  int jobs = 1;
  std::optional<int> threads;
  ToleranceArgs tolerance;
};

struct DiffArgs {
  std::string a, b, heatmap;
  ToleranceArgs tolerance;
};

int run_check(const CheckArgs& args);
int run_diff(const DiffArgs& args);

}  // namespace qdmr::cli
