#include "cli/report.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"

extern char** environ;

namespace qdmr::cli {
namespace {

std::filesystem::path executable_folder() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path() : self.parent_path();
}

// The generator's package: $QDMR_REPORT_DIR, else share/qdmr/qdmr_report of the installation (beside bin/) or
// of the build folder (beside the executable).
std::filesystem::path generator() {
  if (const char* dir = std::getenv("QDMR_REPORT_DIR"); dir && *dir) return dir;
  const std::filesystem::path here = executable_folder();
  for (const std::filesystem::path& candidate :
       {here.parent_path() / "share" / "qdmr" / "qdmr_report", here / "share" / "qdmr" / "qdmr_report"})
    if (std::filesystem::is_regular_file(candidate / "__main__.py")) return candidate;
  throw Error("qdmr report", "the report generator is not installed (share/qdmr/qdmr_report beside " +
                                 here.string() + "); set QDMR_REPORT_DIR to report/qdmr_report of the sources");
}

// Debian's interpreter first: its matplotlib and OpenImageIO are the packages scripts/setup installs.
std::string python() {
  if (const char* p = std::getenv("QDMR_PYTHON"); p && *p) return p;
  if (::access("/usr/bin/python3", X_OK) == 0) return "/usr/bin/python3";
  return "python3";
}

// Where exec looks for `program`: itself when it names a folder, else each folder of $PATH in turn (as execvp
// does; resolved before fork, so that the child calls nothing but async-signal-safe functions).
std::vector<std::string> exec_candidates(const std::string& program) {
  if (program.find('/') != std::string::npos) return {program};
  const char* path = std::getenv("PATH");
  std::string folders = path && *path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::vector<std::string> candidates;
  for (std::size_t begin = 0; begin <= folders.size();) {
    const std::size_t end = std::min(folders.find(':', begin), folders.size());
    const std::string folder = end > begin ? folders.substr(begin, end - begin) : ".";
    candidates.push_back(folder + "/" + program);
    begin = end + 1;
  }
  return candidates;
}

// Starts the generator as a child that ends with this process, however it ends (SIGKILL included): the kernel
// sends it SIGTERM when its parent dies (PR_SET_PDEATHSIG). A failed exec reaches the parent as its errno, through
// a pipe that a successful exec closes.
pid_t start_generator(const std::string& interpreter, std::vector<std::string>& argv) {
  const std::vector<std::string> candidates = exec_candidates(interpreter);
  std::vector<char*> pointers;
  for (std::string& a : argv) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  int exec_error[2];
  if (::pipe2(exec_error, O_CLOEXEC) != 0) throw Error("qdmr report", "cannot make a pipe: " + std::string(std::strerror(errno)));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t parent = ::getpid();
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(exec_error[0]);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);  // the parent died before the line above
    int error = ENOENT;
    for (const std::string& candidate : candidates) {
      ::execve(candidate.c_str(), pointers.data(), environ);
      if (errno != ENOENT && errno != ENOTDIR) error = errno;  // as execvp: a file found but not run says why
    }
    [[maybe_unused]] const ssize_t written = ::write(exec_error[1], &error, sizeof error);
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(exec_error[1]);
  if (child < 0) {
    ::close(exec_error[0]);
    throw Error("qdmr report", "cannot start " + interpreter + ": " + std::strerror(fork_error));
  }
  int error = 0;
  ssize_t got;
  while ((got = ::read(exec_error[0], &error, sizeof error)) < 0 && errno == EINTR) {
  }
  ::close(exec_error[0]);
  if (got == ssize_t(sizeof error)) {
    while (::waitpid(child, nullptr, 0) < 0 && errno == EINTR) {
    }
    throw Error("qdmr report", "cannot run " + interpreter + " (" + std::string(std::strerror(error)) +
                                   "); set QDMR_PYTHON to a Python 3 with matplotlib and OpenImageIO");
  }
  return child;
}

}  // namespace

int run_report(const ReportArgs& args) {
  const std::string interpreter = python(), package = generator().string();
  std::vector<std::string> argv{interpreter, package, args.results, "--worst", std::to_string(args.worst),
                                "--crop", std::to_string(args.crop)};
  if (!args.output.empty()) argv.insert(argv.end(), {"-o", args.output});
  if (args.partial) argv.push_back("--partial");
  const pid_t child = start_generator(interpreter, argv);
  // A stop request (SIGINT, SIGTERM: stop_on_signals) interrupts the wait and is passed on to the generator,
  // which then ends without its report (it writes into a temporary folder and renames it when done).
  bool stopped = false;
  int status = 0;
  for (;;) {
    if (!stopped && stop_requested()) {
      ::kill(child, SIGTERM);
      stopped = true;
    }
    if (::waitpid(child, &status, 0) >= 0) break;
    if (errno != EINTR) throw Error("qdmr report", "lost the report generator's process");
  }
  if (stopped) throw Interrupted();  // main says so and exits 130
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  std::fprintf(stderr, "qdmr report: the report generator died (signal %d)\n", WTERMSIG(status));
  return 1;
}

}  // namespace qdmr::cli
