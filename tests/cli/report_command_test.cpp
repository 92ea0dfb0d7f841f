// qdmr report's generator process ends with the command: a stop request is passed on, a killed command (SIGKILL)
// leaves no generator running, and an interpreter that cannot run is named. The generator here is a stand-in
// (QDMR_PYTHON): a shell script that writes its process id and then becomes `sleep`, keeping that id.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <thread>

#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Sets an environment variable while it lives, then restores it.
class ScopedEnv {
public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) saved_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() { saved_ ? ::setenv(name_, saved_->c_str(), 1) : ::unsetenv(name_); }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
  const char* name_;
  std::optional<std::string> saved_;
};

// A stand-in generator in `dir`: QDMR_PYTHON and QDMR_REPORT_DIR point at it for the scope's life.
class SleepingGenerator {
public:
  explicit SleepingGenerator(const TempDir& dir) : pid_file_(dir / "generator.pid") {
    const fs::path script = dir / "python";
    write_file(script, "#!/bin/sh\necho $$ > '" + pid_file_.string() + ".tmp'\nmv '" + pid_file_.string() +
                           ".tmp' '" + pid_file_.string() + "'\nexec sleep 120\n");
    fs::permissions(script, fs::perms::owner_all);
    write_file(dir / "package" / "__main__.py", "");
    python_.emplace("QDMR_PYTHON", script.string());
    package_.emplace("QDMR_REPORT_DIR", (dir / "package").string());
  }

  // The generator's process id once it runs, or 0 after 30 s.
  int pid() const {
    for (const auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
      if (fs::exists(pid_file_)) return std::stoi(read_file(pid_file_));
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return 0;
  }

private:
  fs::path pid_file_;
  std::optional<ScopedEnv> python_, package_;
};

// Whether process `pid` has ended (gone, or a zombie no one has reaped yet), waiting up to 10 s for it.
bool ends(int pid) {
  for (const auto deadline = Clock::now() + std::chrono::seconds(10); Clock::now() < deadline;) {
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string text;
    if (!std::getline(stat, text)) return true;
    const std::size_t paren = text.rfind(')');
    if (paren != std::string::npos && paren + 2 < text.size() && text[paren + 2] == 'Z') return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// The command's exit status, waiting up to 30 s (then it is killed and -1 returned).
int exit_status(int pid) {
  int status = 0;
  for (const auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

TEST(ReportCommand, AKilledCommandLeavesNoGeneratorRunning) {
  TempDir dir;
  const SleepingGenerator generator(dir);
  const int command = spawn(cli(), {"report", (dir / "results").string()});
  const int pid = generator.pid();
  ASSERT_GT(pid, 0) << "the stand-in generator never started";
  ::kill(command, SIGKILL);
  int status = 0;
  ::waitpid(command, &status, 0);
  EXPECT_TRUE(ends(pid)) << "the generator outlived the killed command";
  if (!ends(pid)) ::kill(pid, SIGKILL);
}

TEST(ReportCommand, AStopRequestIsPassedOnToTheGenerator) {
  for (const int signal : {SIGTERM, SIGINT}) {
    TempDir dir;
    const SleepingGenerator generator(dir);
    const int command = spawn(cli(), {"report", (dir / "results").string()});
    const int pid = generator.pid();
    ASSERT_GT(pid, 0) << "the stand-in generator never started";
    ::kill(command, signal);
    EXPECT_EQ(exit_status(command), 130) << "signal " << signal;  // stopped (docs/studies.md)
    EXPECT_TRUE(ends(pid)) << "signal " << signal;
    if (!ends(pid)) ::kill(pid, SIGKILL);
  }
}

TEST(ReportCommand, AnInterpreterThatCannotRunIsNamed) {
  TempDir dir;
  write_file(dir / "package" / "__main__.py", "");
  const ScopedEnv package("QDMR_REPORT_DIR", (dir / "package").string());
  {
    const ScopedEnv python("QDMR_PYTHON", (dir / "no-such-python").string());
    const CommandResult result = run(cli(), {"report", (dir / "results").string()});
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.output.find("cannot run " + (dir / "no-such-python").string() + " (No such file or directory)"),
              std::string::npos) << result.output;
  }
  write_file(dir / "not-executable", "");
  const ScopedEnv python("QDMR_PYTHON", (dir / "not-executable").string());
  const CommandResult result = run(cli(), {"report", (dir / "results").string()});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("(Permission denied)"), std::string::npos) << result.output;
}

}  // namespace
}  // namespace qdmr::test
