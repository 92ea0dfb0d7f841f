#include "cli/study.hpp"

#include "cli/interrupt.hpp"
#include "cli/report.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/core/progress.hpp"
#include "qdmr/study/spec.hpp"
#include "qdmr/study/study.hpp"

namespace qdmr::cli {
namespace {

StudyShard parse_shard(const std::string& text) {
  StudyShard shard;
  if (text.empty()) return shard;
  int i = 0, n = 0;
  char slash = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &i, &slash, &n, &rest) != 3 || slash != '/' || n < 1 || n > 100000 || i < 1 || i > n)
    throw Error("--shard " + text, "expected I/N with 1 <= I <= N, e.g. --shard 2/4");
  shard.index = i;
  shard.count = n;
  return shard;
}

std::string clock_text(double seconds) {
  const int s = int(seconds + 0.5);
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%d:%02d:%02d", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%d:%02d", s / 60, s % 60);
  return text;
}

}  // namespace

int run_study(const StudyArgs& args) {
  if (args.threads && (*args.threads < 1 || *args.threads > limits::kMaxThreads))
    throw Error("--threads", "must be from 1 to " + std::to_string(limits::kMaxThreads));
  StudyOptions options;
  options.shard = parse_shard(args.shard);
  if (args.jobs < 1 || args.jobs > 64) throw Error("--jobs", "must be from 1 to 64, got " + std::to_string(args.jobs));
  options.threads = args.threads.value_or(0);
  options.jobs = args.jobs;
  options.resume = args.resume;
  options.force = args.force;
  const StudySpec spec = read_study_spec(args.spec);
  const std::size_t total = expand_study(spec, args.force).size();
  std::fprintf(stderr, "study %s: %zu configurations%s\n", args.spec.c_str(), total,
               options.shard.count > 1 ? (", shard " + args.shard).c_str() : "");

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last_line = start;
  const bool terminal = ::isatty(STDERR_FILENO);
  std::size_t first_done = std::size_t(-1);
  options.progress = [&](std::size_t done, std::size_t all, const std::string& label) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (first_done == std::size_t(-1)) first_done = done - 1;  // rows kept by --resume are not this run's pace
    const double rate = elapsed / double(done - first_done);
    const double eta = rate * double(all - done);
    if (terminal) {
      const int width = 30, filled = int(double(width) * double(done) / double(all));
      std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu  %s elapsed, ETA %s  %-40.40s", filled,
                   "##############################", width - filled, "", done, all, clock_text(elapsed).c_str(),
                   clock_text(eta).c_str(), label.c_str());
      if (done == all) std::fputc('\n', stderr);
    } else if (done == all || Clock::now() - last_line > std::chrono::seconds(10)) {
      std::fprintf(stderr, "study: %zu/%zu done, %s elapsed, ETA %s (%s)\n", done, all, clock_text(elapsed).c_str(),
                   clock_text(eta).c_str(), label.c_str());
      last_line = Clock::now();
    }
    std::fflush(stderr);
  };
  options.stop_requested = [] { return qdmr::stop_requested(); };  // main's stop_on_signals
  const StudyRun run = qdmr::run_study(spec, args.output, options);
  std::printf("%s: %zu configurations (%zu rendered now, %zu kept from before; assets prepared %zu times) in %.1f s; "
              "results.csv, results.json, pareto.csv\n",
              args.output.c_str(), run.total, run.rendered, run.resumed, run.asset_builds, run.seconds);
  if (run.stopped) {
    std::fprintf(stderr, "study: interrupted; the results so far are valid, continue with --resume\n");
    return kExitInterrupted;
  }
  if (args.report) {
    ReportArgs report;
    report.results = args.output;
    report.partial = options.shard.count > 1;
    return run_report(report);
  }
  return 0;
}

int run_study_merge(const StudyMergeArgs& args) {
  std::vector<std::filesystem::path> folders(args.folders.begin(), args.folders.end());
  merge_studies(folders, args.output);
  std::printf("%s: merged %zu shards\n", args.output.c_str(), folders.size());
  return 0;
}

}  // namespace qdmr::cli
