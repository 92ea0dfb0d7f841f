// load_scene's threads (qdmr render/bench --threads, a study's threads): the load's parallel parts run in an arena
// of that many threads, whatever arena the caller is in, and the loaded meshes have the same bits for any count.
// The parallel part seen is MikkTSpace's: it splits its vertices into one part per thread of the arena it runs in
// (mesh_detail::take_mikktspace_parts_seen).
#include <gtest/gtest.h>

#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh/mikktspace.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

namespace fs = std::filesystem;

// A wavy 48 x 48 grid as a .gltf beside its .bin: POSITION, NORMAL, TEXCOORD_0 (mirrored in u on its right half,
// so MikkTSpace splits the seam's vertices), 32-bit indices, no TANGENT (MikkTSpace makes them).
fs::path threads_test_grid(const test::TempDir& dir,
                           const std::function<void(std::vector<float>&, std::vector<std::uint32_t>&)>& edit = {}) {
  constexpr int kSize = 48;
  std::vector<float> positions, normals, uvs;
  for (int j = 0; j <= kSize; ++j)
    for (int i = 0; i <= kSize; ++i) {
      const float x = float(i) / kSize, y = float(j) / kSize;
      positions.insert(positions.end(), {x, 0.1f * std::sin(9.0f * x) * std::cos(7.0f * y), -y});
      normals.insert(normals.end(), {-0.9f * std::cos(9.0f * x), 1.0f, 0.7f * std::sin(7.0f * y)});
      uvs.insert(uvs.end(), {i <= kSize / 2 ? x : 1.0f - x, 1.0f - y});
    }
  std::vector<std::uint32_t> indices;
  const auto vertex = [](int i, int j) { return std::uint32_t(j * (kSize + 1) + i); };
  for (int j = 0; j < kSize; ++j)
    for (int i = 0; i < kSize; ++i)
      indices.insert(indices.end(), {vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j),
                                     vertex(i + 1, j + 1), vertex(i, j + 1)});
  if (edit) edit(positions, indices);
  std::string bin;
  nlohmann::json views = nlohmann::json::array();
  const auto append = [&](const void* data, std::size_t bytes) {
    views.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}});
    bin.append(static_cast<const char*>(data), bytes);
  };
  append(positions.data(), positions.size() * 4);
  append(normals.data(), normals.size() * 4);
  append(uvs.data(), uvs.size() * 4);
  append(indices.data(), indices.size() * 4);
  const std::size_t n = positions.size() / 3;
  const nlohmann::json gltf = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}}, {"indices", 3}}}}}}},
      {"buffers", {{{"uri", "grid.bin"}, {"byteLength", bin.size()}}}},
      {"bufferViews", views},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", n}, {"type", "VEC3"},
         {"min", {0.0, -0.1, -1.0}}, {"max", {1.0, 0.1, 0.0}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", n}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", n}, {"type", "VEC2"}},
        {{"bufferView", 3}, {"componentType", 5125}, {"count", indices.size()}, {"type", "SCALAR"}}}}};
  test::write_file(dir / "grid.bin", bin);
  test::write_file(dir / "grid.gltf", gltf.dump());
  return dir / "grid.gltf";
}

const MeshData& threads_test_mesh(const SceneDesc& scene) {
  EXPECT_EQ(scene.objects.size(), 1u);
  return *scene.objects.at(0).obj_mesh;
}

template <class T>
bool threads_test_same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(LoadThreads, TheLoadRunsOnTheThreadsItIsGiven) {
  const int cores = tbb::info::default_concurrency();
  if (cores < 2) GTEST_SKIP() << "one core: every arena has one thread, a bound cannot show";
  test::TempDir dir;
  const fs::path grid = threads_test_grid(dir);
  mesh_detail::take_mikktspace_parts_seen();
  // --threads 1 outside any arena (the command's case): one part, where the default arena has every core.
  load_scene(grid, {}, 0, 1);
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), 1u);
  load_scene(grid, {}, 0, 2);
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), 2u);
  // 0: every core, or the caller's arena.
  load_scene(grid);
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), std::size_t(cores));
  tbb::task_arena one(1);
  one.execute([&] { load_scene(grid); });
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), 1u);
  // A count given wins over the caller's arena; more than the cores gets the cores.
  one.execute([&] { load_scene(grid, {}, 0, 2); });
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), 2u);
  load_scene(grid, {}, 0, cores + 5);
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), std::size_t(cores));
  // load_scene_json (a study's configurations) alike.
  const nlohmann::json scene = nlohmann::json::parse(R"({
    "camera": {"position": [0.5, -2, 2], "target": [0.5, 0.5, 0], "up": [0, 0, 1], "fov_deg": 60},
    "objects": [{"mesh": {"type": "gltf", "file": "grid.gltf"}}]})");
  load_scene_json(scene, dir / "scene.json", dir.path(), {}, 0, 1);
  EXPECT_EQ(mesh_detail::take_mikktspace_parts_seen(), 1u);
}

TEST(LoadThreads, TheLoadedMeshHasTheSameBitsForAnyThreadCount) {
  test::TempDir dir;
  const fs::path grid = threads_test_grid(dir);
  const SceneDesc one = load_scene(grid, {}, 0, 1);
  const MeshData& reference = threads_test_mesh(one);
  EXPECT_GT(reference.positions.size(), std::size_t(49 * 49));  // the mirrored seam's vertices were split
  std::vector<SceneDesc> others;
  for (const int threads : {2, 3, 8}) others.push_back(load_scene(grid, {}, 0, threads));
  for (const int arena : {3, 8}) others.push_back(tbb::task_arena(arena).execute([&] { return load_scene(grid); }));
  // $QDMR_ISA: sse4.2 keeps MikkTSpace's corners in four lanes (else eight where the CPU has AVX2); one the draw
  // would refuse is the draw's to name, not the load's.
  const char* saved = std::getenv("QDMR_ISA");
  const std::string kept = saved ? saved : "";
  for (const char* isa : {"sse4.2", "avx9"}) {
    ::setenv("QDMR_ISA", isa, 1);
    others.push_back(load_scene(grid, {}, 0, 2));
  }
  if (saved) {
    ::setenv("QDMR_ISA", kept.c_str(), 1);
  } else {
    ::unsetenv("QDMR_ISA");
  }
  for (const SceneDesc& other : others) {
    const MeshData& mesh = threads_test_mesh(other);
    EXPECT_TRUE(threads_test_same_bits(mesh.positions, reference.positions));
    EXPECT_TRUE(threads_test_same_bits(mesh.normals, reference.normals));
    EXPECT_TRUE(threads_test_same_bits(mesh.uvs, reference.uvs));
    EXPECT_TRUE(threads_test_same_bits(mesh.tangents, reference.tangents));
    EXPECT_TRUE(threads_test_same_bits(mesh.indices, reference.indices));
  }
}

// The checks of the accessors run on threads, a block at a time: the first bad element is named, on any count.
TEST(LoadThreads, TheFirstBadElementIsNamedOnAnyThreadCount) {
  const auto error = [](const fs::path& file, int threads) {
    try {
      load_scene(file, {}, 0, threads);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const auto has = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos ? testing::AssertionSuccess()
                                                : testing::AssertionFailure() << "'" << text << "' lacks '" << part << "'";
  };
  test::TempDir a, b;
  // Positions 700 (y) and 1900 (x) not finite: element 700 is named (2401 vertices: blocks of 512 floats).
  const fs::path floats = threads_test_grid(a, [](std::vector<float>& p, std::vector<std::uint32_t>&) {
    p[3 * 700 + 1] = std::numeric_limits<float>::quiet_NaN();
    p[3 * 1900] = -std::numeric_limits<float>::infinity();
  });
  // Indices 3000 and 9000 past the vertices: index 3000 is named.
  const fs::path indices = threads_test_grid(b, [](std::vector<float>&, std::vector<std::uint32_t>& i) {
    i[3000] = 2401;
    i[9000] = 5000;
  });
  for (const int threads : {1, 2}) {
    EXPECT_TRUE(has(error(floats, threads), "/accessors/0: element 700 is not finite")) << threads;
    EXPECT_TRUE(has(error(indices, threads), "/accessors/3: index 3000 is 2401, past the primitive's 2401 vertices")) << threads;
  }
}

}  // namespace
}  // namespace qdmr
