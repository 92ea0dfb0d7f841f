#pragma once
// Running golden-image checks: every check of a manifest rendered in one process (a persistent Renderer per
// job, so checks of the same scene prepare their assets once), compared with its golden hash or image, and, on
// failure, a diff folder to look at. `qdmr check` is this plus printing; docs/checks.md describes it.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "qdmr/check/compare.hpp"
#include "qdmr/check/manifest.hpp"

namespace qdmr {

enum class CheckStatus {
  Passed,
  Failed,   // an output differs from its golden, or variants differ from each other
  Skipped,  // a skip_if_missing path is missing
  Error,    // the check cannot run: unreadable scene, missing golden (hint: --update), unreadable golden
  Updated,  // with update: the golden or hash was (re)written
};
const char* check_status_name(CheckStatus status);  // "PASS", "FAIL", "SKIP", "ERROR", "UPDATED"

struct OutputResult {
  std::string output;  // "color" or an AOV name
  std::string hash;    // canonical hash of the rendered output
  std::optional<Comparison> comparison;  // tolerance checks, and exact checks whose variants differ
};

struct CheckResult {
  std::string name;
  CheckStatus status = CheckStatus::Passed;
  std::vector<std::string> lines;  // failed metrics, the reason for an error or skip, what was updated
  std::vector<OutputResult> outputs;
  std::filesystem::path diff_folder;  // written for a failure, else empty
  double prepare_ms = 0, draw_ms = 0;  // of the first variant
  double seconds = 0;                  // everything for this check: load, prepare, draws, compare, diff folder
};

struct CheckOptions {
  bool update = false;  // rewrite the goldens and hashes of failing checks (and missing ones), and nothing else
  std::filesystem::path diff_dir = "qdmr-check-failures";  // a folder per failed check goes here
  int jobs = 1;      // checks run at once, each with its own renderer
  int threads = 0;   // worker threads over all jobs (0: every core); a variant's threads override it
  // Called after each check, in the order checks finish, never concurrently.
  std::function<void(const CheckResult& result, std::size_t done, std::size_t total)> on_result;
};

struct CheckRun {
  std::vector<CheckResult> results;  // in manifest order
  double seconds = 0;
  bool manifest_rewritten = false;  // update wrote new hashes or the bits version into the manifest
  // 0: every check passed, was skipped or updated; 1: some failed; 2: some could not run.
  int exit_code() const;
};

// Runs every check of the manifest. With update, rewrites the manifest (atomically, keeping its key order)
// when hashes or the bits version changed, and golden images that failed or were missing.
CheckRun run_checks(const Manifest& manifest, const CheckOptions& options);

// JUnit XML, as GitLab, Jenkins and GitHub test reporters read it: a test case per check, the failure message
// the failed metrics.
void write_junit(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& file);

// Every result as JSON: per check its name, status, lines, output hashes, prepare_ms, draw_ms and seconds; the
// run's seconds, qdmr version and bits version. For scripts (bench/check_overhead.py reads it).
void write_results_json(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& file);

// index.html in `dir`: a summary of every check and, per failure, its metrics and images (the diff folders,
// which must be inside `dir`). Viewable from disk: no scripts from elsewhere, no server.
void write_html_report(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& dir);

}  // namespace qdmr
