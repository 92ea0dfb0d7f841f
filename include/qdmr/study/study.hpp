#pragma once
// Running a study: every configuration of a spec rendered by persistent renderers in one process, one row of
// metrics each, appended to the results folder as it finishes (docs/studies.md describes the folder, the
// columns, sharding, resuming and merging).
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "qdmr/study/spec.hpp"

namespace qdmr {

using StudyRow = nlohmann::ordered_json;  // "index", "config", "deterministic", "timing" (docs/studies.md)

struct StudyShard {
  int index = 1, count = 1;  // 1-based: shard `index` of `count`
};

struct StudyOptions {
  int threads = 0;                   // per configuration; 0: every core / jobs
  int jobs = 1;                      // configurations drawn at once (each by its own renderers)
  StudyShard shard;
  bool resume = false;               // keep the rows of an interrupted run of the same spec and shard
  bool force = false;                // allow more than the spec's max_configurations
  // After each configuration: done, total (of this shard), the configuration's label. Never concurrently.
  std::function<void(std::size_t done, std::size_t total, const std::string& label)> progress;
  // Polled between configurations: true stops the run with a valid partial result (Ctrl-C).
  std::function<bool()> stop_requested;
};

struct StudyRun {
  std::size_t total = 0;     // configurations of this shard
  std::size_t rendered = 0;  // in this run
  std::size_t resumed = 0;   // kept from an earlier run
  std::size_t asset_builds = 0;  // configurations whose assets had to be (re)built: configurations are ordered
                                 // by what they build, so this is near the number of distinct asset sets
  bool stopped = false;
  double seconds = 0;
};

// The configurations of shard I of N: balanced by an estimate of their cost (iteration caps, step counts,
// techniques, grazing angles), not by index; every configuration is in exactly one shard. Indices, ascending.
std::vector<std::size_t> shard_configurations(const StudySpec& spec, const std::vector<StudyConfig>& configs,
                                              StudyShard shard);

// One process's measuring of a spec's configurations, one at a time, by persistent renderers (the timed frames,
// the error AOVs and the reference, the baselines): consecutive configurations that share an asset set prepare it
// once, and each baseline is drawn once per measurer. A Dask worker keeps one across tasks (python/qdmr/_dask.py).
class StudyMeasurer {
public:
  StudyMeasurer(const StudySpec& spec, int threads, bool force = false);  // threads 0: every core
  ~StudyMeasurer();
  StudyMeasurer(const StudyMeasurer&) = delete;
  StudyMeasurer& operator=(const StudyMeasurer&) = delete;

  std::size_t configurations() const;
  const std::string& spec_hash() const;
  // Configuration `index`'s row, its kept files written into out/images. Throws qdmr::Error naming it.
  StudyRow measure(std::size_t index, const std::filesystem::path& out);
  // `pending` in the order that re-prepares least: grouped by the items their plans build (asset sets), groups in
  // the order of their first configuration, indices ascending within a group.
  std::vector<std::size_t> reuse_order(const std::vector<std::size_t>& pending) const;
  // `pending` in groups of configurations that share what one measurer computes once for all of them beyond an
  // asset set: the exact reference (the fields it traces, from one camera at one frame size) and the heights
  // those fields are made of. Each group in reuse_order, groups in the order of their first configuration.
  // Processes that split a spec between them duplicate least when each draws whole groups.
  std::vector<std::vector<std::size_t>> share_groups(const std::vector<std::size_t>& pending) const;
  // A relative estimate of what configuration `index` costs to draw (the one shards are balanced by).
  double estimated_cost(std::size_t index) const;
  std::size_t asset_builds() const;  // configurations measured so far whose timed scene built anything
  int threads() const;
  const char* isa() const;

private:
  struct State;
  std::unique_ptr<State> state_;
};

struct StudyFolderInfo {
  std::size_t configurations = 0;  // of the whole spec
  StudyShard shard;
  bool resume = false;
  int threads = 1, jobs = 1;  // of the machine section of study.json
  std::string isa;
};

// A results folder while a study writes it, locked for the object's life (FOLDER/.qdmr-lock): study.json written,
// the rows of an earlier run of the same spec and shard kept (resume; another spec's or shard's are refused),
// rows appended one line each as they come, results.json/csv and pareto.csv rewritten every 2 s and by finish().
class StudyFolder {
public:
  StudyFolder(const StudySpec& spec, const std::filesystem::path& out, const StudyFolderInfo& info);
  ~StudyFolder();
  StudyFolder(const StudyFolder&) = delete;
  StudyFolder& operator=(const StudyFolder&) = delete;

  const std::set<std::size_t>& done() const;  // indices with a row
  std::size_t resumed() const;                // rows kept from earlier runs
  void append(StudyRow row);                  // throws qdmr::Error for an index that has a row
  void finish();

private:
  struct State;
  std::unique_ptr<State> state_;
};

// Runs the spec into `out` (created): study.json (what the rows belong to), rows.jsonl (a row per line, appended
// as each finishes), results.json, results.csv and pareto.csv (rewritten from the rows), images/ (keep).
StudyRun run_study(const StudySpec& spec, const std::filesystem::path& out, const StudyOptions& options);

// Merges the folders of every shard of one spec into `out`, with the outputs of an unsharded run. Throws
// qdmr::Error when a folder is of another spec, a shard is missing or given twice, or rows are missing.
void merge_studies(const std::vector<std::filesystem::path>& shards, const std::filesystem::path& out);

// Indices (into rows) of the rows no other row dominates in (timing.draw_ms_median, deterministic.error_p99,
// deterministic.missed_fraction), all to be minimised; a missing metric counts as 0. Ascending.
std::vector<std::size_t> pareto_front(const std::vector<StudyRow>& rows);

}  // namespace qdmr
