// Runs the checks of a manifest: see qdmr/check/check.hpp.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <tuple>

#include <nlohmann/json.hpp>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include "check/diff_folder.hpp"
#include "file/atomic_file.hpp"
#include "file/os_error.hpp"
#include "check/canonical_hash.hpp"
#include "qdmr/check/check.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "qdmr/core/version.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/write/write.hpp"

namespace qdmr {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The pixels of one output of a frame, rows from the top.
Image output_image(const Frame& frame, const std::string& output) {
  if (output == "color") {
    Image image(frame.width, frame.height, 3);
    std::copy(frame.color.begin(), frame.color.end(), image.texels.begin());
    return image;
  }
  const Aov aov = *parse_aov(output);
  for (const AovImage& a : frame.aovs)
    if (a.aov == aov) {
      Image image(frame.width, frame.height, a.channels);
      std::copy(a.pixels.begin(), a.pixels.end(), image.texels.begin());
      return image;
    }
  throw Error(output, "the AOV was not rendered");
}

std::optional<Aov> output_aov(const std::string& output) {
  return output == "color" ? std::nullopt : parse_aov(output);
}

// One job's renderers, one per (threads, tile, ISA): each keeps the assets of the last scene it drew.
class RendererPool {
public:
  explicit RendererPool(int threads) : threads_(threads) {}

  Renderer& get(const CheckVariant& variant) {
    RenderOptions options;
    options.threads = variant.threads.value_or(threads_);
    options.tile_size = variant.tile.value_or(options.tile_size);
    options.isa = resolve_isa(variant.isa.value_or(Isa::Auto));  // "auto" and its ISA share one renderer
    const auto key = std::make_tuple(options.threads, options.tile_size, int(options.isa));
    auto& slot = renderers_[key];
    if (!slot) slot = std::make_unique<Renderer>(options);
    return *slot;
  }

private:
  int threads_;
  std::map<std::tuple<int, int, int>, std::unique_ptr<Renderer>> renderers_;
};

// A tolerance output as compared: the render as a file of the golden's type holds it, and the golden.
struct Compared {
  Image rendered, golden;
};

// What one check found, before diff folders and updates.
struct Rendered {
  std::vector<Image> images;  // per output, of the first variant
  std::vector<std::string> hashes;
};

class CheckJob {
public:
  CheckJob(const Manifest& manifest, const CheckOptions& options, int threads)
      : manifest_(manifest), options_(options), pool_(threads) {}

  // Also returns, for update, the hashes to write into the manifest.
  CheckResult run(const CheckSpec& check, std::map<std::string, std::string>* new_hashes) {
    const auto start = Clock::now();
    CheckResult result;
    result.name = check.name;
    try {
      run_check(check, result, new_hashes);
    } catch (const Error& e) {
      result.status = CheckStatus::Error;
      result.lines.push_back(e.what());
    } catch (const std::bad_alloc&) {
      result.status = CheckStatus::Error;
      result.lines.push_back("out of memory");
    } catch (const Interrupted&) {  // Ctrl-C during a bake: run_checks stops and says so
      result.status = CheckStatus::Error;
      result.lines.push_back("interrupted");
    } catch (const std::filesystem::filesystem_error& e) {  // e.g. a full disk under the diff folder
      result.status = CheckStatus::Error;
      result.lines.push_back(os_error_line(e));
    } catch (const std::exception& e) {
      result.status = CheckStatus::Error;
      result.lines.push_back(e.what());
    }
    result.seconds = seconds_since(start);
    return result;
  }

private:
  void run_check(const CheckSpec& check, CheckResult& result, std::map<std::string, std::string>* new_hashes) {
    for (const std::filesystem::path& path : check.skip_if_missing)
      if (!std::filesystem::exists(path)) {
        result.status = CheckStatus::Skipped;
        result.lines.push_back("skipped: " + path.string() + " does not exist");
        return;
      }
    if (manifest_.bits_version != kBitsVersion && !options_.update) {
      result.status = CheckStatus::Failed;
      result.lines.push_back("bits version: the goldens were made by bits version " +
                             std::to_string(manifest_.bits_version) + ", this qdmr " + version() +
                             " renders bits version " + std::to_string(kBitsVersion) +
                             " (docs/bits-changelog.md says what changed); review the new images and re-bless with --update");
      return;
    }
    std::vector<SceneOverride> overrides = check.overrides;
    if (check.width > 0) overrides.push_back({"/output/width", std::to_string(check.width)});
    if (check.height > 0) overrides.push_back({"/output/height", std::to_string(check.height)});
    const SceneDesc scene = load_scene(check.scene, overrides);
    std::vector<Aov> aovs;
    for (const std::string& output : check.outputs)
      if (auto aov = output_aov(output)) aovs.push_back(*aov);

    // The first variant is compared with the golden; every other one must give its bits.
    Rendered first;
    Frame first_frame;
    std::vector<std::string> failures;
    for (std::size_t v = 0; v < check.variants.size(); ++v) {
      Renderer& renderer = pool_.get(check.variants[v]);
      renderer.set_scene(scene, aovs);
      const Frame& frame = renderer.draw();
      if (v == 0) {
        first_frame = frame;  // a later variant may draw with the same renderer
        result.prepare_ms = frame.stats.plan_ms + frame.stats.prepare_ms;
        result.draw_ms = frame.stats.draw_ms();
      }
      for (std::size_t o = 0; o < check.outputs.size(); ++o) {
        Image image = output_image(frame, check.outputs[o]);
        const std::string hash = canonical_hash(image.width, image.height, image.channels, image.texels);
        if (v == 0) {
          first.images.push_back(std::move(image));
          first.hashes.push_back(hash);
          result.outputs.push_back({check.outputs[o], hash, std::nullopt});
        } else if (hash != first.hashes[o]) {
          Tolerance exact;
          exact.max_abs = 0;
          const Comparison c = compare_images(image, first.images[o], exact);
          failures.push_back(check.outputs[o] + ": variant " + check.variants[v].label() +
                             " renders other bits than variant " +
                             (check.variants[0].label().empty() ? "(default)" : check.variants[0].label()) + ": " +
                             c.summary());
        }
      }
    }

    std::vector<std::string> updates;
    std::map<std::string, Compared> compared;  // tolerance outputs: what was compared, for the diff folder
    for (std::size_t o = 0; o < check.outputs.size(); ++o) {
      const std::string& output = check.outputs[o];
      OutputResult& out = result.outputs[o];
      if (check.mode == CheckMode::Exact) {
        const auto expected = check.hashes.find(output);
        if (expected != check.hashes.end() && expected->second == out.hash) continue;
        if (options_.update) {
          (*new_hashes)[output] = out.hash;
          updates.push_back(output + ": hash " + (expected == check.hashes.end() ? "(none)" : expected->second) +
                            " -> " + out.hash);
          continue;
        }
        if (expected == check.hashes.end())
          throw Error(manifest_.file.string() + ": " + check.pointer + "/hash",
                      "no hash for output '" + output + "' yet: run qdmr check with --update to record " + out.hash);
        failures.push_back(output + ": hash " + out.hash + ", expected " + expected->second);
        continue;
      }
      // Tolerance: against the golden file, as a file of its type holds the render.
      const std::filesystem::path& golden = check.goldens.at(output);
      const bool exists = std::filesystem::exists(golden);
      if (exists) {
        int golden_bits = 0;
        Compared& c = compared[output];
        c.golden = read_comparable_image(golden, &golden_bits);
        c.rendered = stored_pixels(first_frame, output_aov(output), golden);
        out.comparison = compare_images(c.rendered, c.golden, check.tolerance);
        if (out.comparison->passed()) continue;
        if (!options_.update) {
          for (const std::string& line : out.comparison->failures) failures.push_back(output + ": " + line);
          if (golden_bits != 0 && golden_bits != kBitsVersion)
            failures.push_back(output + ": the golden was written by bits version " + std::to_string(golden_bits) +
                               ", this qdmr renders bits version " + std::to_string(kBitsVersion));
          continue;
        }
      } else if (!options_.update) {
        throw Error(golden.string(), "no golden image yet: run qdmr check with --update to write it");
      }
      write_golden(first_frame, output, golden);
      updates.push_back(output + ": " + (exists ? "rewrote " : "wrote ") + golden.string());
    }

    if (!failures.empty()) {
      result.status = CheckStatus::Failed;
      result.lines = failures;
      result.diff_folder = options_.diff_dir / check.name;
      write_diff_folder(check, result, first_frame, compared, result.diff_folder);
    } else if (!updates.empty()) {
      result.status = CheckStatus::Updated;
      result.lines = updates;
    }
  }

  static void write_golden(const Frame& frame, const std::string& output, const std::filesystem::path& file) {
    std::filesystem::create_directories(file.parent_path());
    if (auto aov = output_aov(output))
      write_aov(frame, *aov, file);
    else
      write_frame(frame, file);
  }

  static void write_diff_folder(const CheckSpec& check, const CheckResult& result, const Frame& frame,
                                const std::map<std::string, Compared>& compared, const std::filesystem::path& folder) {
    DiffFolder diff(folder);
    for (const std::string& output : check.outputs) {
      const std::optional<Aov> aov = output_aov(output);
      const auto c = compared.find(output);
      if (c != compared.end()) {
        diff.add_comparison(output, frame, aov, c->second.rendered, c->second.golden, check.goldens.at(output));
      } else {
        diff.add_render(output, frame, aov);
      }
    }
    diff.finish(result.lines);
  }

  const Manifest& manifest_;
  const CheckOptions& options_;
  RendererPool pool_;
};

// Rewrites the manifest with new hashes and the current bits version, keeping its key order and layout style.
bool rewrite_manifest(const Manifest& manifest, const std::map<std::size_t, std::map<std::string, std::string>>& hashes) {
  if (manifest.text.empty()) return false;  // built in memory (the one-off form): no file to rewrite
  if (hashes.empty() && manifest.bits_version == kBitsVersion) return false;
  nlohmann::ordered_json document = nlohmann::ordered_json::parse(manifest.text);
  document["bits_version"] = kBitsVersion;
  for (const auto& [index, outputs] : hashes)
    for (const auto& [output, hash] : outputs) document["checks"][index]["hash"][output] = hash;
  write_text_file(manifest.file, document.dump(2) + "\n");
  return true;
}

}  // namespace

const char* check_status_name(CheckStatus status) {
  switch (status) {
    case CheckStatus::Passed: return "PASS";
    case CheckStatus::Failed: return "FAIL";
    case CheckStatus::Skipped: return "SKIP";
    case CheckStatus::Error: return "ERROR";
    case CheckStatus::Updated: return "UPDATED";
  }
  return "?";
}

int CheckRun::exit_code() const {
  int code = 0;
  for (const CheckResult& r : results) {
    if (r.status == CheckStatus::Error) return 2;
    if (r.status == CheckStatus::Failed) code = 1;
  }
  return code;
}

CheckRun run_checks(const Manifest& manifest, const CheckOptions& options) {
  const auto start = Clock::now();
  const std::size_t total = manifest.checks.size();
  // Checks of the same scene run one after the other, so a renderer re-uses that scene's assets.
  std::vector<std::size_t> order(total);
  for (std::size_t i = 0; i < total; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return manifest.checks[a].scene < manifest.checks[b].scene;
  });

  const int jobs = std::max(1, std::min<int>(options.jobs, int(total)));
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = options.threads > 0 ? std::max(1, options.threads / jobs) : std::max(1, cores / jobs);

  CheckRun run;
  run.results.resize(total);
  std::map<std::size_t, std::map<std::string, std::string>> new_hashes;
  std::atomic<std::size_t> next{0};
  std::mutex done_mutex;
  std::size_t done = 0;
  const int job_threads = jobs == 1 && options.threads == 0 ? 0 : threads;
  const auto checks = [&] {
    CheckJob job(manifest, options, job_threads);
    for (std::size_t k; !stop_requested() && (k = next.fetch_add(1)) < total;) {
      const std::size_t index = order[k];
      std::map<std::string, std::string> hashes;
      CheckResult result = job.run(manifest.checks[index], &hashes);
      const std::lock_guard lock(done_mutex);
      if (!hashes.empty()) new_hashes[index] = std::move(hashes);
      run.results[index] = std::move(result);
      if (options.on_result) options.on_result(run.results[index], ++done, total);
    }
  };
  // A job's writes (goldens, diff folders) on its threads too: qdmr's writers use the arena they run in.
  const auto work = [&] {
    if (job_threads == 0) return checks();
    tbb::task_arena(std::min(job_threads, tbb::info::default_concurrency())).execute(checks);
  };
  if (jobs == 1) {
    work();
  } else {
    std::vector<std::thread> workers;
    for (int j = 0; j < jobs; ++j) workers.emplace_back(work);
    for (std::thread& w : workers) w.join();
  }
  throw_if_stop_requested();  // Ctrl-C: the goldens written so far are whole; the manifest is left as it was
  if (options.update) run.manifest_rewritten = rewrite_manifest(manifest, new_hashes);
  run.seconds = seconds_since(start);
  return run;
}

}  // namespace qdmr
