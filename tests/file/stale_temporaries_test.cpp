// Temporaries of atomic outputs (file/atomic_file.hpp): the writer holds a lock on its ".NAME.tmpPID-N.EXT"
// while it writes; a temporary left by a process that died is removed by the next write to the same target;
// one of a live process, one still locked, anything else in the folder is left alone.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>
#include <vector>

#include "file/atomic_file.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A process id that is not running: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return pid;
}

// Whether another open file description can take the lock of `file` now.
bool lock_is_free(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool free = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
  ::close(fd);
  return free;
}

TEST(StaleTemporaries, TheWriterLocksItsTemporaryUntilTheRename) {
  TempDir dir;
  const fs::path target = dir / "out.json";
  fs::path seen;
  bool locked = false;
  write_atomically(target, "file", [&](const fs::path& temporary) -> std::string {
    seen = temporary;
    locked = fs::exists(temporary) && !lock_is_free(temporary);
    write_file(temporary, "new\n");
    return "";
  });
  EXPECT_TRUE(locked);
  EXPECT_EQ(seen.filename().string().rfind(".out.json.tmp" + std::to_string(::getpid()) + "-", 0), 0u) << seen;
  EXPECT_EQ(seen.extension(), ".json");
  EXPECT_EQ(read_file(target), "new\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.json"});

  // In a batch the lock is held until commit() renames the file.
  {
    OutputBatch batch;
    write_atomically(target, "file", [&](const fs::path& temporary) -> std::string {
      seen = temporary;
      write_file(temporary, "batched\n");
      return "";
    });
    EXPECT_TRUE(fs::exists(seen));
    EXPECT_FALSE(lock_is_free(seen));
    batch.commit();
  }
  EXPECT_FALSE(fs::exists(seen));
  EXPECT_EQ(read_file(target), "batched\n");
}

TEST(StaleTemporaries, TheNextWriteRemovesThoseOfDeadProcessesOnly) {
  TempDir dir;
  const fs::path target = dir / "out.exr";
  const std::string dead = std::to_string(dead_pid()), parent = std::to_string(::getppid());
  const std::vector<std::string> stale{
      ".out.exr.tmp" + dead + "-0.exr",
      ".out.exr.tmp" + dead + "-17.exr",
      ".out.exr.tmp2147483646-3.exr",   // no such process can run (above the kernel's PID limit)
      ".out.exr.tmp99999999999-3.exr",  // beyond any pid_t
  };
  const std::vector<std::string> kept{
      ".out.exr.tmp" + parent + "-0.exr",  // a live process (this test's parent) may be writing it
      ".out.exr.tmp2147483645-1.exr",      // locked below: a writer this process cannot see (another PID namespace)
      ".out.exr.tmp2147483645-2.exr",      // a FIFO: not a file qdmr wrote; opening it must not hang
      ".out.exr.tmp" + dead + "-0.png",    // another extension
      ".out.exr.tmp" + dead + ".exr",      // no counter
      ".out.exr.tmp-1.exr",                // no process id
      ".out.exr.tmpx" + dead + "-1.exr",   // not digits
      ".out.exr.tmp" + dead + "-1x.exr",
      ".other.exr.tmp" + dead + "-0.exr",  // another target's
      "out.exr.tmp" + dead + "-0.exr",     // not hidden
      ".out.exr",
      "notes.txt",
  };
  for (const std::string& name : stale) write_file(dir / name, "partial");
  for (const std::string& name : kept)
    if (name != ".out.exr.tmp2147483645-2.exr") write_file(dir / name, "keep");
  ASSERT_EQ(::mkfifo((dir / ".out.exr.tmp2147483645-2.exr").c_str(), 0600), 0);
  const int lock = ::open((dir / ".out.exr.tmp2147483645-1.exr").c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX), 0);

  write_text_file(target, "new\n");
  std::vector<std::string> expected = kept;
  expected.push_back("out.exr");
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(names_in(dir.path()), expected);
  EXPECT_EQ(read_file(target), "new\n");

  // Once its lock is released (its writer died), the next write removes it.
  ::close(lock);
  write_text_file(target, "newer\n");
  expected.erase(std::find(expected.begin(), expected.end(), ".out.exr.tmp2147483645-1.exr"));
  EXPECT_EQ(names_in(dir.path()), expected);
  // A write to another target leaves this one's temporaries alone.
  const std::string stale_again = ".out.exr.tmp" + dead + "-5.exr";
  write_file(dir / stale_again, "partial");
  write_text_file(dir / "other.exr", "x");
  EXPECT_TRUE(fs::exists(dir / stale_again));
  EXPECT_FALSE(fs::exists(dir / (".other.exr.tmp" + dead + "-0.exr")));  // that target's own stale one
}

}  // namespace
}  // namespace qdmr::test
