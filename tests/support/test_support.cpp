#include "support/test_support.hpp"
#include "support/converted_tiff.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>

#include <array>
#include <cstdlib>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace qdmr::test {

std::filesystem::path source_dir() { return QDMR_SOURCE_DIR; }
std::filesystem::path data_dir() { return QDMR_DATA_DIR; }
bool have_data() { return std::filesystem::is_directory(data_dir() / "materials"); }
std::filesystem::path cli() { return QDMR_CLI; }

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("qdmr_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

ScopedCacheDir::ScopedCacheDir(const std::filesystem::path& dir) {
  if (const char* old = std::getenv("QDMR_CACHE_DIR")) saved_ = old;
  ::setenv("QDMR_CACHE_DIR", dir.c_str(), 1);
}

ScopedCacheDir::~ScopedCacheDir() { saved_ ? ::setenv("QDMR_CACHE_DIR", saved_->c_str(), 1) : ::unsetenv("QDMR_CACHE_DIR"); }

CommandResult run(const std::filesystem::path& program, const std::vector<std::string>& args) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    std::FILE* in = std::fopen("/dev/null", "r");
    if (in) ::dup2(::fileno(in), 0);
    ::dup2(fds[1], 1);
    ::dup2(fds[1], 2);
    ::close(fds[0]);
    ::close(fds[1]);
    std::vector<char*> argv;
    std::string prog = program.string();
    argv.push_back(prog.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(prog.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  CommandResult result;
  std::array<char, 4096> buffer;
  ssize_t n;
  while ((n = ::read(fds[0], buffer.data(), buffer.size())) > 0) result.output.append(buffer.data(), std::size_t(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

namespace {

pid_t start(const std::filesystem::path& program, const std::vector<std::string>& args, int out_fd) {
  std::vector<std::string> copy = args;
  std::string prog = program.string();
  std::vector<char*> argv{prog.data()};
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int in = ::open("/dev/null", O_RDONLY);
    if (in >= 0) ::dup2(in, 0);
    ::dup2(out_fd, 1);
    ::dup2(out_fd, 2);
    ::execv(prog.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace

TimedResult run_timed(const std::filesystem::path& program, const std::vector<std::string>& args,
                      double timeout_seconds) {
  using Clock = std::chrono::steady_clock;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  const auto begin = Clock::now();
  const pid_t pid = start(program, args, fds[1]);
  ::close(fds[1]);
  TimedResult result;
  std::array<char, 4096> buffer;
  for (;;) {
    const double left = timeout_seconds - std::chrono::duration<double>(Clock::now() - begin).count();
    if (left <= 0) {
      result.timed_out = true;
      ::kill(pid, SIGKILL);
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    if (::poll(&p, 1, int(left * 1000) + 1) <= 0) continue;
    const ssize_t n = ::read(fds[0], buffer.data(), buffer.size());
    if (n <= 0) break;
    result.output.append(buffer.data(), std::size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  rusage usage{};
  ::wait4(pid, &status, 0, &usage);
  result.cpu_seconds = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                       double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
  result.peak_resident_bytes = std::uint64_t(usage.ru_maxrss) * 1024;  // reported in KiB
  result.seconds = std::chrono::duration<double>(Clock::now() - begin).count();
  result.exit_code = result.timed_out ? -1 : WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

int spawn(const std::filesystem::path& program, const std::vector<std::string>& args) {
  const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  const pid_t pid = start(program, args, null);
  ::close(null);
  return pid;
}

std::uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * std::uint64_t(::sysconf(_SC_PAGESIZE));
}

std::uint32_t sample_hash(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  return x ^ (x >> 16);
}

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_file(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

std::filesystem::path only_file(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files.push_back(e.path());
  EXPECT_EQ(files.size(), 1u);
  return files.empty() ? std::filesystem::path() : files[0];
}

std::string min_is_white_tiff() {
  std::string out("II*\0\x08\0\0\0", 8);  // little-endian; the first directory at byte 8
  const auto add = [&](std::uint32_t value, int bytes) {
    for (int b = 0; b < bytes; ++b) out += char(value >> (8 * b));
  };
  constexpr std::uint32_t kEntries = 8, kPixels = 8 + 2 + 12 * kEntries + 4;
  add(kEntries, 2);
  const std::uint32_t entries[kEntries][3] = {  // tag, type (3 short, 4 long), value
      {256, 3, 4}, {257, 3, 4}, {258, 3, 8}, {259, 3, 1},  // 4x4, 8 bits, no compression
      {262, 3, 0},                                          // PhotometricInterpretation: min is white
      {273, 4, kPixels}, {278, 3, 4}, {279, 4, 16}};        // one strip of 16 bytes
  for (const auto& [tag, type, value] : entries) {
    add(tag, 2);
    add(type, 2);
    add(1, 4);
    add(value, 4);
  }
  add(0, 4);  // no next directory
  for (int i = 0; i < 16; ++i) add(std::uint32_t(16 * i), 1);
  return out;
}

}  // namespace qdmr::test
