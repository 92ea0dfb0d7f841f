#pragma once
// Shared by the OBJ + MTL tests: a row of four unit quads (x from -2 to 2, facing +z), one per MTL material,
// each with one kind of map: `displaced` (map_Kd + disp), `bumped` (bump), `normal_mapped` (norm) and `plain`
// (Kd only). The disp height is 1 but for a 16x16 square pit of 0 in the middle of its 64x64 texels; the bump
// height is 32x32 stripes.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "support/test_support.hpp"

namespace qdmr::test {

inline void write_image(const std::filesystem::path& file, int size, int channels,
                        const std::vector<std::uint8_t>& texels) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(file.string(), OIIO::ImageSpec(size, size, channels, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, texels.data()));
  ASSERT_TRUE(out->close());
}

// quads.obj, lib.mtl and the maps under tex/ in `dir`.
inline void write_mtl_assets(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir / "tex");
  std::vector<std::uint8_t> height(64 * 64, 255);
  for (int y = 24; y < 40; ++y)
    for (int x = 24; x < 40; ++x) height[std::size_t(y * 64 + x)] = 0;
  write_image(dir / "tex/height.png", 64, 1, height);
  std::vector<std::uint8_t> stripes(32 * 32);
  for (std::size_t i = 0; i < stripes.size(); ++i) stripes[i] = (i / 4) % 2 ? 255 : 0;
  write_image(dir / "tex/bump.png", 32, 1, stripes);
  write_image(dir / "tex/albedo.png", 2, 3, {200, 80, 40, 40, 200, 80, 80, 40, 200, 200, 200, 200});
  write_image(dir / "tex/normal.png", 2, 3, {160, 128, 240, 160, 128, 240, 160, 128, 240, 160, 128, 240});
  write_file(dir / "lib.mtl",
             "newmtl displaced\nKd 1 1 1\nmap_Kd tex/albedo.png\ndisp tex/height.png\n"
             "newmtl bumped\nKd 0.8 0.8 0.8\nbump -bm 0.3 tex/bump.png\n"
             "newmtl normal_mapped\nKd 0.8 0.8 0.8\nnorm tex/normal.png\n"
             "newmtl plain\nKd 0.5 0.6 0.7\n");
  std::ostringstream obj;
  obj << "mtllib lib.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n";
  const char* names[] = {"displaced", "bumped", "normal_mapped", "plain"};
  for (int q = 0; q < 4; ++q) {
    const int x = q - 2, v = 4 * q;
    obj << "v " << x << " -0.5 0\nv " << x + 1 << " -0.5 0\nv " << x + 1 << " 0.5 0\nv " << x << " 0.5 0\n";
    obj << "usemtl " << names[q] << "\nf " << v + 1 << "/1/1 " << v + 2 << "/2/1 " << v + 3 << "/3/1 " << v + 4
        << "/4/1\n";
  }
  write_file(dir / "quads.obj", obj.str());
}

// A scene of the quads seen from above at an angle, the object named "quads" (its materials "quads/<mtl>").
inline std::string mtl_scene(const std::string& object_extra = "") {
  return R"({
  "camera": {"position": [0, -2.2, 2.2], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 60},
  "objects": [{"name": "quads", "mesh": {"type": "obj", "file": "quads.obj"})" +
         object_extra + "}]\n}\n";
}

}  // namespace qdmr::test
