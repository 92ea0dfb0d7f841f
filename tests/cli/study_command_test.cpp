// qdmr study through the command: deterministic columns identical across thread counts, jobs, ISAs and shardings, resume
// after a kill equal to an uninterrupted run, merge refusing missing or foreign shards, folders never mixed.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <thread>

#include <nlohmann/json.hpp>

#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

void write_spec(const TempDir& dir, const std::string& extra = "") {
  write_file(dir / "s.json", R"({"scene": ")" + (source_dir() / "scenes" / "plane.json").string() + R"(",
    "width": 48, "height": 27, "frames": 1, "warmup": 0, )" + extra + R"(
    "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["normal", "pom", "qdm"]},
             {"name": "elevation", "camera": "elevation", "values": [60, 20]}],
    "baseline": {"technique": "qdm"}})");
}

// rows.jsonl's rows by index: "index", "config" and "deterministic" only (timing differs run to run).
std::vector<nlohmann::json> deterministic_rows(const fs::path& folder) {
  std::vector<nlohmann::json> rows;
  std::ifstream in(folder / "rows.jsonl");
  for (std::string line; std::getline(in, line);) {
    auto row = nlohmann::json::parse(line);
    row.erase("timing");
    rows.push_back(row);
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a["index"] < b["index"]; });
  return rows;
}

CommandResult study(const TempDir& dir, std::vector<std::string> args) {
  args.insert(args.begin(), {"study", (dir / "s.json").string()});
  return run(cli(), args);
}

TEST(StudyCommand, RowsAreTheSameForAnyThreadCountAndSharding) {
  TempDir dir;
  write_spec(dir);
  const CommandResult one = study(dir, {"-o", (dir / "one").string(), "--threads", "1"});
  ASSERT_EQ(one.exit_code, 0) << one.output;
  ASSERT_EQ(study(dir, {"-o", (dir / "two").string(), "--threads", "2"}).exit_code, 0);
  ASSERT_EQ(study(dir, {"-o", (dir / "jobs").string(), "--jobs", "2"}).exit_code, 0);
  ::setenv("QDMR_ISA", "sse4.2", 1);  // the baseline kernel instead of the CPU's best
  const CommandResult sse = study(dir, {"-o", (dir / "sse").string()});
  ::unsetenv("QDMR_ISA");
  ASSERT_EQ(sse.exit_code, 0) << sse.output;
  ASSERT_EQ(study(dir, {"-o", (dir / "a").string(), "--shard", "1/2"}).exit_code, 0);
  ASSERT_EQ(study(dir, {"-o", (dir / "b").string(), "--shard", "2/2"}).exit_code, 0);
  const CommandResult merged = run(cli(), {"study", "merge", (dir / "a").string(), (dir / "b").string(), "-o", (dir / "m").string()});
  ASSERT_EQ(merged.exit_code, 0) << merged.output;

  const auto reference = deterministic_rows(dir / "one");
  ASSERT_EQ(reference.size(), 6u);
  EXPECT_EQ(deterministic_rows(dir / "two"), reference);
  EXPECT_EQ(deterministic_rows(dir / "jobs"), reference);
  // Across ISAs every column but lane_utilisation, which measures the kernel's SIMD width (4, 8 or 16 lanes).
  const auto without_lanes = [](std::vector<nlohmann::json> rows) {
    for (auto& row : rows) row["deterministic"].erase("lane_utilisation");
    return rows;
  };
  EXPECT_EQ(without_lanes(deterministic_rows(dir / "sse")), without_lanes(reference));
  EXPECT_EQ(nlohmann::json::parse(read_file(dir / "sse" / "study.json"))["machine"]["isa"], "sse4.2");
  EXPECT_EQ(deterministic_rows(dir / "m"), reference);
  EXPECT_LT(deterministic_rows(dir / "a").size(), 6u);  // each shard has a part
  // The displaced techniques did iterate, QDM is its own baseline, and nothing is NaN.
  for (const auto& row : reference) {
    EXPECT_EQ(row["deterministic"]["nonfinite"], 0);
    if (row["config"]["technique"] == "qdm") {
      EXPECT_EQ(row["deterministic"]["diff_pixels"], 0);
      EXPECT_GT(row["deterministic"]["iterations_mean"].get<double>(), 0);
    }
    EXPECT_TRUE(row["deterministic"].contains("error_p99"));
  }
  for (const char* file : {"results.csv", "results.json", "pareto.csv", "study.json"}) {
    EXPECT_TRUE(fs::exists(dir / "one" / file)) << file;
    EXPECT_TRUE(fs::exists(dir / "m" / file)) << file;
  }
  const auto results = nlohmann::json::parse(read_file(dir / "m" / "results.json"));
  EXPECT_EQ(results["rows"].size(), 6u);
  EXPECT_EQ(results["spec_hash"], nlohmann::json::parse(read_file(dir / "one" / "study.json"))["spec_hash"]);
  EXPECT_NE(read_file(dir / "one" / "pareto.csv").find("technique=qdm"), std::string::npos);
}

TEST(StudyCommand, ResumeAfterAKillGivesTheRowsOfAnUninterruptedRun) {
  TempDir dir;
  write_spec(dir, R"("frames": 40,)");  // slow enough to be killed halfway
  ASSERT_EQ(study(dir, {"-o", (dir / "full").string()}).exit_code, 0);
  const fs::path rows = dir / "cut" / "rows.jsonl";
  const int pid = spawn(cli(), {"study", (dir / "s.json").string(), "-o", (dir / "cut").string()});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline && (!fs::exists(rows) || deterministic_rows(dir / "cut").size() < 2))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::size_t kept = deterministic_rows(dir / "cut").size();
  ASSERT_GE(kept, 2u);
  if (kept == 6) GTEST_SKIP() << "the run finished before it could be killed";

  const CommandResult refused = study(dir, {"-o", (dir / "cut").string()});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.output.find("holds the results of a study already: add --resume"), std::string::npos) << refused.output;
  const CommandResult resumed = study(dir, {"-o", (dir / "cut").string(), "--resume"});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("kept from before"), std::string::npos);
  EXPECT_EQ(deterministic_rows(dir / "cut"), deterministic_rows(dir / "full"));

  // Another spec may not continue these rows.
  write_spec(dir, R"("frames": 2,)");
  const CommandResult other = study(dir, {"-o", (dir / "cut").string(), "--resume"});
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.output.find("holds results of another spec"), std::string::npos) << other.output;
}

// Every state a kill can leave a folder in, made by hand from a finished run's files: nothing yet, the header
// only (killed before the first row: the state of issue #57), an empty rows file, half a first row, whole rows
// and half a row, a header temporary of a dead process. --resume finishes each with the rows of the
// uninterrupted run; a half row is cut, never kept.
TEST(StudyCommand, ResumeFinishesEveryStateAKillCanLeave) {
  TempDir dir;
  write_spec(dir);
  ASSERT_EQ(study(dir, {"-o", (dir / "full").string()}).exit_code, 0);
  const std::string header = read_file(dir / "full" / "study.json");
  std::vector<std::string> lines;
  {
    std::ifstream in(dir / "full" / "rows.jsonl");
    for (std::string line; std::getline(in, line);) lines.push_back(line + "\n");
  }
  ASSERT_EQ(lines.size(), 6u);
  const std::string half = lines[2].substr(0, lines[2].size() / 2);
  struct State {
    const char* name;
    bool header;
    std::optional<std::string> rows;  // absent: no rows.jsonl
    std::size_t kept;                 // rows the resumed run keeps
  };
  const State states[] = {{"empty_folder", false, std::nullopt, 0},
                          {"header_only", true, std::nullopt, 0},
                          {"empty_rows", true, "", 0},
                          {"half_first_row", true, half, 0},
                          {"rows_and_half_row", true, lines[0] + lines[1] + half, 2}};
  for (const State& state : states) {
    SCOPED_TRACE(state.name);
    const fs::path folder = dir / state.name;
    fs::create_directories(folder);
    if (state.header) write_file(folder / "study.json", header);
    if (state.rows) write_file(folder / "rows.jsonl", *state.rows);
    const CommandResult resumed = study(dir, {"-o", folder.string(), "--resume"});
    ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
    EXPECT_NE(resumed.output.find(std::to_string(state.kept) + " kept from before"), std::string::npos) << resumed.output;
    EXPECT_EQ(deterministic_rows(folder), deterministic_rows(dir / "full"));
  }
  // A header temporary of a process that is gone (killed while writing study.json the first time): the run
  // starts afresh, without --resume too, and removes it.
  const fs::path folder = dir / "header_temporary";
  fs::create_directories(folder);
  write_file(folder / ".study.json.tmp2147483647-0.json", header.substr(0, 10));
  const CommandResult fresh = study(dir, {"-o", folder.string()});
  ASSERT_EQ(fresh.exit_code, 0) << fresh.output;
  EXPECT_EQ(deterministic_rows(folder), deterministic_rows(dir / "full"));
  EXPECT_FALSE(fs::exists(folder / ".study.json.tmp2147483647-0.json"));
}

// A second study on a folder that a running one writes (two shards given the same -o, a requeued job racing its
// zombie) is refused with one line naming the folder and the holder, and writes nothing. Here the test itself
// holds the folder's lock as a running study would (faults.injection races two real studies); once released, the
// folder is a study's like any other.
TEST(StudyCommand, ASecondRunOnTheSameFolderIsRefused) {
  TempDir dir;
  write_spec(dir);
  const fs::path out = dir / "out";
  fs::create_directories(out);
  const int fd = ::open((out / ".qdmr-lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const std::string pid = std::to_string(::getpid()) + "\n";
  ASSERT_EQ(::write(fd, pid.data(), pid.size()), ssize_t(pid.size()));
  const CommandResult second = study(dir, {"-o", out.string()});
  EXPECT_EQ(second.exit_code, 2) << second.output;
  EXPECT_NE(second.output.find(out.string() + ": is in use by another qdmr study (process " + std::to_string(::getpid()) +
                               "): wait until it ends, or choose another -o"),
            std::string::npos) << second.output;
  EXPECT_FALSE(fs::exists(out / "study.json"));
  EXPECT_FALSE(fs::exists(out / "rows.jsonl"));
  ::close(fd);  // the lock goes with its holder
  const CommandResult after = study(dir, {"-o", out.string()});
  ASSERT_EQ(after.exit_code, 0) << after.output;
  EXPECT_EQ(deterministic_rows(out).size(), 6u);
}

TEST(StudyCommand, MergeRefusesMissingDuplicateAndForeignShards) {
  TempDir dir;
  write_spec(dir);
  ASSERT_EQ(study(dir, {"-o", (dir / "a").string(), "--shard", "1/2"}).exit_code, 0);
  ASSERT_EQ(study(dir, {"-o", (dir / "b").string(), "--shard", "2/2"}).exit_code, 0);
  const auto merge = [&](std::vector<std::string> folders) {
    std::vector<std::string> args{"study", "merge"};
    for (const auto& f : folders) args.push_back((dir / f).string());
    args.insert(args.end(), {"-o", (dir / "m").string()});
    return run(cli(), args);
  };
  const CommandResult missing = merge({"a"});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("shard 2 of 2 is missing"), std::string::npos) << missing.output;
  const CommandResult twice = merge({"a", "a", "b"});
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_NE(twice.output.find("is shard 1 again"), std::string::npos) << twice.output;
  write_spec(dir, R"("frames": 2,)");
  ASSERT_EQ(study(dir, {"-o", (dir / "c").string(), "--shard", "2/2"}).exit_code, 0);
  const CommandResult foreign = merge({"a", "c"});
  EXPECT_EQ(foreign.exit_code, 2);
  EXPECT_NE(foreign.output.find("is a shard of another spec"), std::string::npos) << foreign.output;
  const CommandResult bad_shard = study(dir, {"-o", (dir / "d").string(), "--shard", "3/2"});
  EXPECT_EQ(bad_shard.exit_code, 2);
  EXPECT_NE(bad_shard.output.find("--shard 3/2: expected I/N"), std::string::npos) << bad_shard.output;
}

}  // namespace
}  // namespace qdmr::test

namespace qdmr::test {
namespace {

// An axis that changes what is built (BC3 heights) toggling fastest: configurations are drawn grouped by what
// they build, so the heights are prepared twice (once per storage), not at every configuration; the rows are
// still written by index.
TEST(StudyCommand, ConfigurationsAreOrderedToPrepareEachAssetSetOnce) {
  TempDir dir;
  write_file(dir / "s.json", R"({"scene": ")" + (source_dir() / "scenes" / "plane.json").string() + R"(",
    "width": 48, "height": 27, "frames": 1, "warmup": 0, "metrics": ["time"],
    "axes": [{"name": "elevation", "camera": "elevation", "values": [60, 40, 20]},
             {"name": "compression", "path": "/materials/bricks/layers/0/height/compression", "values": ["none", "bc3"]}]})");
  const CommandResult result = run(cli(), {"study", (dir / "s.json").string(), "-o", (dir / "out").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("assets prepared 2 times"), std::string::npos) << result.output;
  const auto results = nlohmann::json::parse(read_file(dir / "out" / "results.json"));
  ASSERT_EQ(results["rows"].size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(results["rows"][i]["index"], i);
}

}  // namespace
}  // namespace qdmr::test
