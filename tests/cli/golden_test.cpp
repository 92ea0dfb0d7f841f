// Golden images: every scene in scenes/ rendered by the qdmr command at 480x270 to a float EXR, its pixels
// hashed (FNV-1a 64 over the float bytes) and compared with tests/golden/hashes.json.
//
// After an intended change of the images, update the goldens with
//   QDMR_UPDATE_GOLDEN=1 ./tests/qdmr_tests --gtest_filter='CliGolden*'     (from build/release)
// which rewrites tests/golden/hashes.json instead of comparing; review the new renders, then commit the file.
// See docs/testing.md.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

fs::path golden_file() { return source_dir() / "tests" / "golden" / "hashes.json"; }

bool updating() {
  const char* value = std::getenv("QDMR_UPDATE_GOLDEN");
  return value && std::string(value) == "1";
}

std::string hex(std::uint64_t value) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Sets one scene's hash in the golden file. CTest may run the scenes as parallel processes: the
// read-modify-write holds an exclusive lock on the file.
void store_hash(const std::string& scene, const std::string& hash) {
  const int fd = ::open(golden_file().c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0) << "cannot open " << golden_file();
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  const std::string text = read_file(golden_file());
  nlohmann::json hashes = text.empty() ? nlohmann::json::object() : nlohmann::json::parse(text);
  hashes[scene] = hash;
  write_file(golden_file(), hashes.dump(2) + "\n");
  ::close(fd);  // releases the lock
}

class CliGolden : public testing::TestWithParam<ShippedScene> {};

TEST_P(CliGolden, MatchesTheCommittedHash) {
  const ShippedScene& scene = GetParam();
  if (scene.needs_data && !have_data())
    GTEST_SKIP() << scene.name << ".json needs the real CC0 maps, not found in QDMR_DATA_DIR=" << data_dir();
  TempDir dir;
  const fs::path output = dir / (scene.name + ".exr");
  render_scene(cli(), scene, output);
  if (HasFatalFailure()) return;
  const FloatImage image = read_float_image(output);
  ASSERT_EQ(image.width, kCliWidth);
  ASSERT_EQ(image.height, kCliHeight);
  const std::string hash = hex(pixel_hash(image));

  if (updating()) {
    store_hash(scene.name, hash);
    std::printf("updated %s: %s = %s\n", golden_file().c_str(), scene.name.c_str(), hash.c_str());
    return;
  }
  const nlohmann::json hashes = nlohmann::json::parse(read_file(golden_file()));
  ASSERT_TRUE(hashes.contains(scene.name)) << golden_file() << " has no hash for " << scene.name
                                           << "; create it with QDMR_UPDATE_GOLDEN=1 (see docs/testing.md)";
  if (hashes[scene.name] == hash) return;

  // Keep the render for inspection: the temporary folder goes away with the test.
  const fs::path kept = fs::temp_directory_path() / ("qdmr_golden_" + scene.name + ".exr");
  fs::copy_file(output, kept, fs::copy_options::overwrite_existing);
  std::string command = "qdmr render";
  for (const std::string& arg : scene_args(scene)) command += " " + arg;
  ADD_FAILURE() << scene.name << ": the image changed (hash " << hash << ", golden " << hashes[scene.name].get<std::string>()
                << ").\nThe new render is kept at " << kept.string()
                << ".\nTo see what changed, render a reference with a build of the last good commit:\n  " << command
                << " -o ref.exr --width " << kCliWidth << " --height " << kCliHeight << "\nand compare: idiff -v ref.exr "
                << kept.string() << "   (or view both in an EXR viewer).\n"
                << "If the change is intended, update the goldens: QDMR_UPDATE_GOLDEN=1 ./tests/qdmr_tests "
                   "--gtest_filter='CliGolden*' and commit tests/golden/hashes.json.";
}

INSTANTIATE_TEST_SUITE_P(, CliGolden, testing::ValuesIn(shipped_scenes()), scene_name);

}  // namespace
}  // namespace qdmr::test
