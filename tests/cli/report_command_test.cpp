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

// Whether process `pid` has ended: gone, or a zombie no one has reaped yet.
bool ended(int pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(stat, text)) return true;
  const std::size_t paren = text.rfind(')');
  return paren != std::string::npos && paren + 2 < text.size() && text[paren + 2] == 'Z';
}

// ended(), waiting up to 10 s for it.
bool ends(int pid) {
  for (const auto deadline = Clock::now() + std::chrono::seconds(10); Clock::now() < deadline;) {
    if (ended(pid)) return true;
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

// `qdmr report` on a folder of `dir` with the stand-in generator, running: its process id and the generator's (0
// when it never started). Whatever a test leaves running is killed and reaped when it ends.
class RunningReport {
public:
  explicit RunningReport(const TempDir& dir)
      : generator_(dir), command_(spawn(cli(), {"report", (dir / "results").string()})), pid_(generator_.pid()) {}
  ~RunningReport() {
    if (pid_ > 0 && !ended(pid_)) ::kill(pid_, SIGKILL);
    if (command_ > 0) {
      ::kill(command_, SIGKILL);
      ::waitpid(command_, nullptr, 0);
    }
  }
  RunningReport(const RunningReport&) = delete;
  RunningReport& operator=(const RunningReport&) = delete;

  int generator() const { return pid_; }
  // Signals the command and reaps it: its exit status as exit_status() gives it.
  int signal_and_wait(int signal) {
    ::kill(command_, signal);
    const int status = exit_status(command_);
    command_ = 0;
    return status;
  }

private:
  SleepingGenerator generator_;
  int command_;
  int pid_;
};

TEST(ReportCommand, AKilledCommandLeavesNoGeneratorRunning) {
  TempDir dir;
  RunningReport report(dir);
  ASSERT_GT(report.generator(), 0) << "the stand-in generator never started";
  report.signal_and_wait(SIGKILL);
  EXPECT_TRUE(ends(report.generator())) << "the generator outlived the killed command";
}

TEST(ReportCommand, AStopRequestIsPassedOnToTheGenerator) {
  for (const int signal : {SIGTERM, SIGINT}) {
    TempDir dir;
    RunningReport report(dir);
    ASSERT_GT(report.generator(), 0) << "the stand-in generator never started";
    EXPECT_EQ(report.signal_and_wait(signal), 130) << "signal " << signal;  // stopped (docs/studies.md)
    EXPECT_TRUE(ends(report.generator())) << "signal " << signal;
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
