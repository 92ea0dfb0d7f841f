// Cone-map bake time (bake_cone_map, both kinds) on procedural and real height maps, 1 and 2 threads.
// A plain timing program: each case runs once per repetition and the fastest run is printed as a markdown row.
//   qdmr_cone_bench [--sizes 256,512,1024,2048] [--threads 1,2] [--reps N] [--real] [--map FILE]...
// --real adds ambientcg_rocks007 (1024² and 2048²) from the data folder when present; --map adds a height image
// (a path relative to the data folder, QDMR_DATA_DIR, e.g. terrain/puget_sound_4k.jpg, or any path).
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/texture/texture_level0.hpp"

namespace {

std::vector<int> parse_list(const std::string& text) {
  std::vector<int> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) values.push_back(std::atoi(item.c_str()));
  return values;
}

qdmr::HeightField field_of(const qdmr::Image& image) {
  qdmr::HeightField f;
  f.width = image.width;
  f.height = image.height;
  f.h = qdmr::ZeroedBuffer<double>(std::size_t(image.width) * std::size_t(image.height));
  for (std::size_t k = 0; k < f.h.size(); ++k) f.h[k] = image.texels[k * std::size_t(image.channels)];
  return f;
}

void run_case(const std::string& name, const qdmr::HeightField& field, const std::vector<int>& threads, int reps) {
  for (qdmr::ConeKind kind : {qdmr::ConeKind::Conservative, qdmr::ConeKind::Relaxed})
    for (int t : threads) {
      double best = 1e30;
      qdmr::ConeMap map;
      for (int r = 0; r < reps; ++r) {
        const auto start = std::chrono::steady_clock::now();
        tbb::task_arena(t).execute([&] { map = qdmr::bake_cone_map(field, kind); });
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
      double sum = 0;
      std::size_t zeros = 0;
      for (float v : map.ratio) {
        sum += v;
        zeros += v == 0.0f;
      }
      std::printf("| %s | %d² | %s | %d | %.3f | %.3f | %.1f %% |\n", name.c_str(), field.width,
                  qdmr::cone_kind_name(kind), t, best, sum / double(map.ratio.size()),
                  100.0 * double(zeros) / double(map.ratio.size()));
      std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes{256, 512, 1024, 2048}, threads{1, 2};
  int reps = 1;
  bool real = false;
  std::vector<std::string> maps;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--sizes" && k + 1 < argc)
      sizes = parse_list(argv[++k]);
    else if (arg == "--threads" && k + 1 < argc)
      threads = parse_list(argv[++k]);
    else if (arg == "--reps" && k + 1 < argc)
      reps = std::max(1, std::atoi(argv[++k]));
    else if (arg == "--real")
      real = true;
    else if (arg == "--map" && k + 1 < argc)
      maps.push_back(argv[++k]);
    else {
      std::fprintf(stderr, "usage: %s [--sizes 256,512,...] [--threads 1,2] [--reps N] [--real] [--map FILE]...\n",
                   argv[0]);
      return 2;
    }
  }
  std::printf("| map | size | kind | threads | bake s | mean ratio | ratio 0 |\n|---|---|---|---|---|---|---|\n");
  for (qdmr::ProceduralPattern pattern : {qdmr::ProceduralPattern::Noise, qdmr::ProceduralPattern::Cobbles})
    for (int size : sizes) {
      qdmr::ProceduralDesc desc;
      desc.pattern = pattern;
      desc.size = size;
      run_case(pattern == qdmr::ProceduralPattern::Noise ? "noise" : "cobbles",
               field_of(qdmr::generate_procedural(desc)), threads, reps);
    }
  const std::filesystem::path rocks = std::filesystem::path(QDMR_DATA_DIR) / "materials" / "ambientcg_rocks007";
  if (real && std::filesystem::is_directory(rocks))
    for (const char* file : {"height.jpg", "height_2k.jpg"})
      if (std::filesystem::exists(rocks / file))
        run_case(std::string("rocks007 ") + file, field_of(qdmr::read_image(rocks / file, file)), threads, reps);
  for (const std::string& map : maps) {
    const std::filesystem::path in_data = std::filesystem::path(QDMR_DATA_DIR) / map;
    const std::filesystem::path file = std::filesystem::exists(in_data) ? in_data : std::filesystem::path(map);
    run_case(map, field_of(qdmr::read_image(file, map)), threads, reps);
  }
  return 0;
}
