#pragma once
// qdmr study and qdmr study merge (docs/studies.md).
#include <optional>
#include <string>
#include <vector>

namespace qdmr::cli {

struct StudyArgs {
  std::string spec, output, shard;
  bool resume = false, force = false;
  bool report = false;  // write OUTPUT-report when done
  std::optional<int> threads;
  int jobs = 1;
};

struct StudyMergeArgs {
  std::vector<std::string> folders;
  std::string output;
};

int run_study(const StudyArgs& args);
int run_study_merge(const StudyMergeArgs& args);

}  // namespace qdmr::cli
