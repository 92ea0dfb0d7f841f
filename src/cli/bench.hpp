#pragma once
// qdmr bench: warm frames of one scene through one persistent Renderer, timed stage by stage.
#include <optional>
#include <string>
#include <vector>

namespace qdmr::cli {

struct BenchArgs {
  std::string scene;
  int frames = 10, warmup = 2;
  std::optional<int> threads;  // absent: every core
  int tile = 64;
  std::string isa = "auto";
  std::optional<int> width, height;
  std::vector<std::string> sets, aovs;
  std::string json, image;
};

// Prints a summary and writes --json; returns the exit status. Throws qdmr::Error on bad input.
int run_bench(const BenchArgs& args);

}  // namespace qdmr::cli
