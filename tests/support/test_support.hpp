#pragma once
// Helpers shared by the tests: paths of the repo, the data folder and the built command, and running it.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace qdmr::test {

std::filesystem::path source_dir();
std::filesystem::path data_dir();  // QDMR_DATA_DIR; may not exist
bool have_data();
std::filesystem::path cli();       // the qdmr command of this build

// A fresh empty directory under the system temp folder, removed by the destructor.
class TempDir {
public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
  std::filesystem::path path_;
};

// Points the bake cache (QDMR_CACHE_DIR) at `dir` while it lives, then restores the variable: bakes run, and the
// user's cache is left alone.
class ScopedCacheDir {
public:
  explicit ScopedCacheDir(const std::filesystem::path& dir);
  ~ScopedCacheDir();
  ScopedCacheDir(const ScopedCacheDir&) = delete;
  ScopedCacheDir& operator=(const ScopedCacheDir&) = delete;

private:
  std::optional<std::string> saved_;
};

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs `program args...` without a shell; stdin is /dev/null.
CommandResult run(const std::filesystem::path& program, const std::vector<std::string>& args);

// Like run, but kills the command (SIGKILL) after `timeout_seconds`: then exit_code is -1 and timed_out true.
struct TimedResult : CommandResult {
  double seconds = 0.0;      // wall time until it exited or was killed
  double cpu_seconds = 0.0;  // user + system time of the command
  std::uint64_t peak_resident_bytes = 0;  // the most memory it ever held in RAM (getrusage's ru_maxrss)
  bool timed_out = false;
};
TimedResult run_timed(const std::filesystem::path& program, const std::vector<std::string>& args,
                      double timeout_seconds);

// Starts `program args...` with stdout and stderr to /dev/null and returns its process id (for tests that
// signal it); reap it with waitpid.
int spawn(const std::filesystem::path& program, const std::vector<std::string>& args);

// This process's resident set size now (not the peak), from /proc/self/statm.
std::uint64_t resident_bytes();

std::string read_file(const std::filesystem::path& file);

// A 32-bit integer hash (Chris Wellons' "lowbias32"): well-mixed sample values for the files tests write.
std::uint32_t sample_hash(std::uint32_t x);
void write_file(const std::filesystem::path& file, const std::string& text);

// The lines of `text`, without their '\n' (no empty last line for a text that ends with one).
std::vector<std::string> lines_of(const std::string& text);

// The one file in `dir` (a test failure if there are none or several; then an empty path or the first).
std::filesystem::path only_file(const std::filesystem::path& dir);

}  // namespace qdmr::test
