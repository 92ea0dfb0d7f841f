#include "cli/report.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "qdmr/core/error.hpp"

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

}  // namespace

int run_report(const ReportArgs& args) {
  const std::string interpreter = python(), package = generator().string();
  std::vector<std::string> argv{interpreter, package, args.results, "--worst", std::to_string(args.worst),
                                "--crop", std::to_string(args.crop)};
  if (!args.output.empty()) argv.insert(argv.end(), {"-o", args.output});
  if (args.partial) argv.push_back("--partial");
  std::vector<char*> pointers;
  for (std::string& a : argv) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  pid_t child = 0;
  if (const int error = ::posix_spawnp(&child, interpreter.c_str(), nullptr, nullptr, pointers.data(), environ))
    throw Error("qdmr report", "cannot run " + interpreter + " (" + std::string(std::strerror(error)) +
                                   "); set QDMR_PYTHON to a Python 3 with matplotlib and OpenImageIO");
  int status = 0;
  while (::waitpid(child, &status, 0) < 0)
    if (errno != EINTR) throw Error("qdmr report", "lost the report generator's process");
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  std::fprintf(stderr, "qdmr report: the report generator died (signal %d)\n", WTERMSIG(status));
  return 1;
}

}  // namespace qdmr::cli
