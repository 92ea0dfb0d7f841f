// Outputs are written atomically (a temporary in the same folder, then rename): a render killed with SIGKILL
// while it writes leaves the previous file intact, byte for byte; the next render to the same files removes the
// temporaries it left.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScene = R"({
  "output": {"width": 64, "height": 48},
  "materials": {"rock": {"layers": [{"height": {"procedural": "cobbles", "size": 64}}], "technique": {"name": "pom"}}},
  "objects": [{"mesh": {"type": "plane"}, "material": "rock"}]
})";

// The temporaries of `target` in its folder (".<name>.tmp<pid>-<n><ext>", see file/atomic_file.cpp).
std::vector<fs::path> temporaries_of(const fs::path& target) {
  std::vector<fs::path> found;
  std::string prefix = ".";  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "." + string
  prefix.append(target.filename().string()).append(".tmp");
  for (const auto& entry : fs::directory_iterator(target.parent_path()))
    if (entry.path().filename().string().rfind(prefix, 0) == 0) found.push_back(entry.path());
  return found;
}

TEST(CliAtomicOutput, SigkillWhileWritingKeepsThePreviousFile) {
  TempDir dir;
  write_file(dir / "scene.json", kScene);
  const fs::path image = dir / "image.exr", depth = dir / "depth.exr";
  const std::string previous = "the previous image: any bytes, compared exactly\n";
  write_file(image, previous);
  write_file(depth, previous);
  // 4096 x 4096 float EXRs (a colour image and a depth AOV, ~250 MB uncompressed): writing takes long enough
  // (hundreds of ms) to be caught in the middle, polling every millisecond.
  const pid_t pid = spawn(cli(), {"render", (dir / "scene.json").string(), "-o", image.string(), "--width", "4096",
                                  "--height", "4096", "--aov", "depth=" + depth.string()});
  ASSERT_GT(pid, 0);
  bool caught = false;
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid, &status, WNOHANG) == pid) break;  // finished before it was caught: fails below
    const std::vector<fs::path> temporaries = temporaries_of(image);
    std::error_code ec;
    if (!temporaries.empty() && fs::file_size(temporaries.front(), ec) > 0 && !ec) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      caught = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!caught && ::waitpid(pid, &status, WNOHANG) == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  ASSERT_TRUE(caught) << "the render was never seen writing its output";
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  EXPECT_EQ(read_file(image), previous);
  EXPECT_EQ(read_file(depth), previous);
  // The killed process leaves its hidden temporary behind (nothing in it can remove it); the targets are untouched.
  EXPECT_FALSE(temporaries_of(image).empty());

  // Finished normally, the same command replaces both files with complete images, removes the temporaries the
  // killed one left (its process is gone, its lock released) and leaves none of its own.
  const CommandResult done = run(cli(), {"render", (dir / "scene.json").string(), "-o", image.string(), "--aov",
                                         "depth=" + depth.string()});
  ASSERT_EQ(done.exit_code, 0) << done.output;
  EXPECT_NE(read_file(image), previous);
  EXPECT_EQ(read_file(image).substr(0, 4), std::string("\x76\x2f\x31\x01", 4));  // the OpenEXR magic number
  EXPECT_EQ(read_file(depth).substr(0, 4), std::string("\x76\x2f\x31\x01", 4));
  EXPECT_TRUE(temporaries_of(image).empty());
  EXPECT_TRUE(temporaries_of(depth).empty());
}

}  // namespace
}  // namespace qdmr::test
