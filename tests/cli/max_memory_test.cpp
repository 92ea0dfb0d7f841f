// --max-memory: the plan's memory estimate is checked by Renderer::set_scene before anything is built, once (no
// second plan in the command), with the flag named in the message. `qdmr bake cone` checks its own estimate from
// the height image's header, before any pixel is decoded.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

TEST(MaxMemory, SetSceneRefusesAPlanOverTheLimitBeforeBuildingAnything) {
  const SceneDesc scene = load_scene(source_dir() / "scenes" / "plane.json");
  const std::uint64_t needed = plan_frame(scene).total_bytes();
  RenderOptions tight;
  tight.max_memory_bytes = needed - 1;  // one byte short
  Renderer refusing(tight);
  try {
    refusing.set_scene(scene);
    ADD_FAILURE() << "a plan of " << needed << " bytes accepted under a limit of " << needed - 1;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("plane.json: the job needs an estimated"), std::string::npos) << e.what();
  }
  EXPECT_THROW(refusing.plan(), std::exception);  // nothing was set
  RenderOptions enough;
  enough.max_memory_bytes = needed;
  Renderer accepting(enough);
  EXPECT_NO_THROW(accepting.set_scene(scene));
}

TEST(MaxMemory, TheCommandNamesTheFlagAndWritesNothing) {
  TempDir dir;
  const CommandResult r = run(cli(), {"render", (source_dir() / "scenes" / "plane.json").string(), "-o",
                                      (dir / "x.png").string(), "--max-memory", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("MiB (see qdmr plan), more than the limit of 1 MiB (--max-memory)"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

// A PNG whose header says width x height, 8-bit grey, followed by an IDAT chunk that is not zlib data: its header
// reads fine, decoding any pixel fails. A few dozen bytes stand for a 16384^2 map.
std::string png_header_only(std::uint32_t width, std::uint32_t height) {
  const auto crc32 = [](const std::string& bytes) {
    std::uint32_t crc = 0xFFFFFFFFu;
    for (const char c : bytes) {
      crc ^= static_cast<unsigned char>(c);
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xFFFFFFFFu;
  };
  const auto be32 = [](std::uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16 & 0xFF), char(v >> 8 & 0xFF), char(v & 0xFF)};
  };
  const auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(std::uint32_t(data.size())) + type + data + be32(crc32(type + data));
  };
  return std::string("\x89PNG\r\n\x1A\n", 8) + chunk("IHDR", be32(width) + be32(height) + std::string("\x08\x00\x00\x00\x00", 5)) +
         chunk("IDAT", "not zlib data") + chunk("IEND", "");
}

TEST(MaxMemory, BakeConeRefusesA16384SquaredMapFromItsHeader) {
  TempDir dir;
  write_file(dir / "big.png", png_header_only(16384, 16384));
  const TimedResult r = run_timed(cli(), {"bake", "cone", (dir / "big.png").string(), "-o", (dir / "cone.exr").string(),
                                          "--max-memory", "1024"}, 60);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // The estimate, not a decoder error: nothing was decoded (the pixel data is not even valid).
  EXPECT_NE(r.output.find("big.png: baking its 16384x16384 conservative cone map (address wrap) needs an estimated "),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" MiB, more than the limit of 1024 MiB (--max-memory)"), std::string::npos) << r.output;
  EXPECT_LT(r.cpu_seconds, 2.0);
  EXPECT_FALSE(std::filesystem::exists(dir / "cone.exr"));
  // Relaxed and mirror need more (4 wall channels; the 2W x 2H unfolded grid), and say so.
  const CommandResult relaxed = run(cli(), {"bake", "cone", (dir / "big.png").string(), "-o", (dir / "cone.exr").string(),
                                            "--kind", "relaxed", "--address", "mirror", "--max-memory", "1024"});
  EXPECT_EQ(relaxed.exit_code, 2);
  EXPECT_NE(relaxed.output.find("16384x16384 relaxed cone map (address mirror) needs an estimated"), std::string::npos)
      << relaxed.output;
  // The limit is the only refusal: with a 2048^2 header, 1 MiB refuses, 1 GiB lets the bake go on to decode the
  // pixels, which fails on the invalid data.
  write_file(dir / "mid.png", png_header_only(2048, 2048));
  const CommandResult small = run(cli(), {"bake", "cone", (dir / "mid.png").string(), "-o", (dir / "cone.exr").string(),
                                          "--max-memory", "1"});
  EXPECT_EQ(small.exit_code, 2);
  EXPECT_NE(small.output.find("needs an estimated"), std::string::npos) << small.output;
  const CommandResult decoded = run(cli(), {"bake", "cone", (dir / "mid.png").string(), "-o", (dir / "cone.exr").string(),
                                            "--max-memory", "1024"});
  EXPECT_EQ(decoded.exit_code, 2);
  EXPECT_EQ(decoded.output.find("needs an estimated"), std::string::npos) << decoded.output;
  EXPECT_NE(decoded.output.find("cannot read"), std::string::npos) << decoded.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "cone.exr"));
}

TEST(MaxMemory, BakeConeUnderTheLimitAndTheFlagsRange) {
  TempDir dir;
  std::string pgm = "P5\n64 64\n255\n";
  for (int k = 0; k < 64 * 64; ++k) pgm += char(k * 7 % 256);
  write_file(dir / "h.pgm", pgm);
  // A 64 x 64 map needs well under 1 MiB.
  EXPECT_LT(cone_bake_bytes(64, 64, ConeKind::Relaxed, AddressMode::Mirror), std::uint64_t(1) << 20);
  const CommandResult ok = run(cli(), {"bake", "cone", (dir / "h.pgm").string(), "-o", (dir / "cone.exr").string(),
                                       "--kind", "relaxed", "--address", "mirror", "--max-memory", "1"});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "cone.exr"));
  for (const char* bad : {"0", "-1", "1073741825"}) {
    const CommandResult r = run(cli(), {"bake", "cone", (dir / "h.pgm").string(), "-o", (dir / "c2.exr").string(),
                                        "--max-memory", bad});
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.output.find("--max-memory: must be from 1 to 1073741824 (MiB), got " + std::string(bad)), std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "c2.exr"));
  }
}

// The estimate grows as the baker's allocations do: the relaxed kind holds 4 channels per texel, mirror the
// unfolded 2W x 2H grid.
TEST(MaxMemory, ConeBakeEstimate) {
  const std::uint64_t t = std::uint64_t(1) << 28;  // 16384^2 texels
  const std::uint64_t conservative = cone_bake_bytes(16384, 16384, ConeKind::Conservative, AddressMode::Wrap);
  EXPECT_GT(conservative, 20 * t);  // heights and values as doubles (16 bytes), the map (4), the hierarchy (~1.3)
  EXPECT_LT(conservative, 22 * t);
  EXPECT_GT(cone_bake_bytes(16384, 16384, ConeKind::Relaxed, AddressMode::Wrap), 45 * t);
  EXPECT_GT(cone_bake_bytes(16384, 16384, ConeKind::Conservative, AddressMode::Mirror), 3 * conservative);
  EXPECT_EQ(cone_bake_bytes(16384, 16384, ConeKind::Conservative, AddressMode::Clamp), conservative);
}

}  // namespace
}  // namespace qdmr::test
