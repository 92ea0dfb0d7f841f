#include "cli/check.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "check/diff_folder.hpp"
#include "file/output_check.hpp"
#include "qdmr/check/check.hpp"
#include "qdmr/check/compare.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/core/version.hpp"

namespace qdmr::cli {
namespace {

Tolerance apply(const ToleranceArgs& args, Tolerance t) {
  const auto range = [](const char* flag, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi))
      throw Error(flag, "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " + std::to_string(v));
  };
  if (args.max_abs) range("--max-abs", *args.max_abs, 0, 1e30), t.max_abs = *args.max_abs;
  if (args.max_pixels) range("--max-pixels", double(*args.max_pixels), 0, 1e12), t.max_pixels = *args.max_pixels;
  if (args.max_fraction) range("--max-fraction", *args.max_fraction, 0, 1), t.max_fraction = *args.max_fraction;
  if (args.radius) range("--radius", *args.radius, 0, 16), t.radius = *args.radius;
  if (args.max_rmse) range("--max-rmse", *args.max_rmse, 0, 1e30), t.max_rmse = *args.max_rmse;
  if (args.min_psnr) range("--min-psnr", *args.min_psnr, -1e30, 1e30), t.min_psnr = *args.min_psnr;
  return t;
}

bool tolerance_given(const ToleranceArgs& a) {
  return a.max_abs || a.max_pixels || a.max_fraction || a.radius || a.max_rmse || a.min_psnr;
}

// The one-off form: a manifest of one check, in memory.
Manifest one_off_manifest(const CheckArgs& args) {
  if (!args.golden.empty() && !args.hash.empty()) throw Error("--golden", "give --golden FILE or --hash HASH, not both");
  Manifest manifest;
  manifest.file = args.target;
  manifest.bits_version = kBitsVersion;
  CheckSpec check;
  check.name = std::filesystem::path(args.target).stem().string();
  check.pointer = "(command line)";
  check.scene = std::filesystem::absolute(args.target);
  for (const std::string& s : args.sets) check.overrides.push_back(parse_override(s));
  check.width = args.width.value_or(0);
  check.height = args.height.value_or(0);
  check.outputs = {"color"};
  check.variants = {CheckVariant{}};
  if (!args.hash.empty()) {
    if (tolerance_given(args.tolerance)) throw Error("--hash", "an exact check has no tolerance flags");
    check.mode = CheckMode::Exact;
    if (args.hash != "none") check.hashes["color"] = args.hash;
    if (args.hash != "none" && (args.hash.size() != 45 || !args.hash.starts_with("sha1:")))
      throw Error("--hash " + args.hash, "expected \"sha1:\" and 40 hex digits (or none, with --update, to print it)");
  } else {
    check.mode = CheckMode::Tolerance;
    check.goldens["color"] = std::filesystem::absolute(args.golden);
    std::string ext = check.goldens["color"].extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".exr" && ext != ".png" && ext != ".tif" && ext != ".tiff")
      throw Error("--golden " + args.golden, "a golden image is .exr, .png or .tif");
  }
  check.tolerance = apply(args.tolerance, Tolerance{});
  manifest.checks.push_back(std::move(check));
  return manifest;
}

void print_result(const CheckResult& r, std::size_t done, std::size_t total) {
  std::printf("[%zu/%zu] %-7s %s", done, total, check_status_name(r.status), r.name.c_str());
  if (r.status == CheckStatus::Passed || r.status == CheckStatus::Failed || r.status == CheckStatus::Updated)
    std::printf("  (draw %.1f ms, total %.1f ms)", r.draw_ms, r.seconds * 1e3);
  std::printf("\n");
  for (const std::string& line : r.lines) std::printf("    %s\n", line.c_str());
  if (!r.diff_folder.empty()) std::printf("    diff folder: %s\n", r.diff_folder.c_str());
  std::fflush(stdout);
}

}  // namespace

void ToleranceArgs::add_to(CLI::App& command) {
  command.add_option("--max-abs", max_abs, "A channel differing by more than this makes a pixel fail (default 1/255)");
  command.add_option("--max-pixels", max_pixels, "Failing pixels allowed (default 0)");
  command.add_option("--max-fraction", max_fraction, "Fraction of all pixels allowed to fail, 0 to 1");
  command.add_option("--radius", radius,
                     "A pixel passes when a golden pixel within this many pixels matches it (one-pixel shifts; default 0)");
  command.add_option("--max-rmse", max_rmse, "Fail when the root mean square difference exceeds this");
  command.add_option("--min-psnr", min_psnr, "Fail when the PSNR (dB, peak 1) is below this");
}

int run_check(const CheckArgs& args) {
  if (args.jobs < 1 || args.jobs > 64) throw Error("--jobs", "must be from 1 to 64, got " + std::to_string(args.jobs));
  if (args.threads && (*args.threads < 1 || *args.threads > limits::kMaxThreads))
    throw Error("--threads", "must be from 1 to " + std::to_string(limits::kMaxThreads));
  const bool one_off = !args.golden.empty() || !args.hash.empty();
  if (!one_off && (!args.sets.empty() || args.width || args.height || tolerance_given(args.tolerance)))
    throw Error(args.target, "--set, --width, --height and tolerance flags belong to the one-off form (a scene with "
                             "--golden or --hash); a manifest sets them per check");
  Manifest manifest = one_off ? one_off_manifest(args) : read_manifest(args.target);

  // Report files may go into folders that do not exist yet (CI artefact folders): they are created.
  std::vector<OutputPath> outputs;
  if (!args.junit.empty()) outputs.push_back({"--junit", args.junit});
  if (!args.json.empty()) outputs.push_back({"--json", args.json});
  for (const OutputPath& o : outputs)
    if (o.path.has_parent_path()) std::filesystem::create_directories(o.path.parent_path());
  check_outputs(outputs);
  if (!args.report.empty()) {
    std::filesystem::create_directories(args.report);
    check_outputs({{"--report", std::filesystem::path(args.report) / "index.html"}});
  }

  CheckOptions options;
  options.update = args.update;
  options.diff_dir = args.report.empty() ? std::filesystem::path(args.diff_dir) : std::filesystem::path(args.report);
  options.jobs = args.jobs;
  options.threads = args.threads.value_or(0);
  options.on_result = print_result;
  const CheckRun run = run_checks(manifest, options);

  int counts[5] = {};
  for (const CheckResult& r : run.results) ++counts[int(r.status)];
  std::printf("%zu checks in %.2f s: %d passed, %d failed, %d could not run, %d skipped, %d updated (qdmr %s, bits "
              "version %d)\n",
              run.results.size(), run.seconds, counts[int(CheckStatus::Passed)], counts[int(CheckStatus::Failed)],
              counts[int(CheckStatus::Error)], counts[int(CheckStatus::Skipped)], counts[int(CheckStatus::Updated)],
              version(), kBitsVersion);
  if (run.manifest_rewritten) std::printf("rewrote %s\n", manifest.file.c_str());
  if (one_off && args.update && !args.hash.empty())
    std::printf("hash of %s: %s\n", args.target.c_str(), run.results.front().outputs.empty() ? "-" : run.results.front().outputs.front().hash.c_str());
  if (!args.junit.empty()) write_junit(manifest, run, args.junit);
  if (!args.json.empty()) write_results_json(manifest, run, args.json);
  if (!args.report.empty()) {
    write_html_report(manifest, run, args.report);
    std::printf("report: %s\n", (std::filesystem::path(args.report) / "index.html").c_str());
  }
  return run.exit_code();
}

int run_diff(const DiffArgs& args) {
  if (!args.heatmap.empty()) {
    if (std::filesystem::path(args.heatmap).extension() != ".png") throw Error("--heatmap " + args.heatmap, "the heatmap is written as .png");
    check_outputs({{"--heatmap", args.heatmap}});
  }
  const Image a = read_comparable_image(args.a);
  const Image b = read_comparable_image(args.b);
  if (!args.heatmap.empty()) check_outputs({{"--heatmap", args.heatmap}});  // both images are known inputs now
  const Comparison c = compare_images(a, b, apply(args.tolerance, Tolerance{}));
  std::printf("%s vs %s: %dx%d, %d channel(s): %s\n", args.a.c_str(), args.b.c_str(), a.width, a.height, a.channels,
              c.summary().c_str());
  for (const std::string& line : c.failures) std::printf("  FAIL %s\n", line.c_str());
  if (!args.heatmap.empty() && c.comparable) {
    double scale = 0;
    for (std::size_t i = 0; i < a.texels.size(); ++i) {
      const double d = std::abs(double(a.texels[i]) - double(b.texels[i]));
      if (std::isfinite(d)) scale = std::max(scale, d);
    }
    write_display_png(difference_heatmap(a, b, scale), args.heatmap);
    std::printf("heatmap: %s (black 0 to yellow %.4g, magma)\n", args.heatmap.c_str(), scale);
  }
  std::printf("%s\n", c.passed() ? "PASS" : "FAIL");
  return c.passed() ? 0 : 1;
}

}  // namespace qdmr::cli
