// The shading options reach the image: settings that must change nothing give the same bits as the option
// off, and settings that must change something do.
#include <gtest/gtest.h>

#include "cli/cli_test_util.hpp"
#include "kernel/displacement_test_util.hpp"

namespace qdmr::test {
namespace {

// surface_blend_4layers as QDM, rendered to EXR (float pixels) with extra overrides; the pixels' hash.
std::uint64_t render_hash(const std::vector<std::string>& sets) {
  const TempDir dir;
  std::vector<std::string> args{"--set", "/materials/blend/technique/name=qdm"};
  for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
  render_scene(cli(), {"surface_blend_4layers", false}, dir.path() / "image.exr", args);
  return pixel_hash(read_float_image(dir.path() / "image.exr"));
}

TEST(CliShadingOptions, NeutralSettingsGiveTheSameBitsAsOff) {
  const std::uint64_t off = render_hash({});
  // A hard shadow whose start is lifted all the way to the polygon sees nothing above it: visibility 1.
  EXPECT_EQ(render_hash({"/materials/blend/shadow/mode=hard", "/materials/blend/shadow/bias=1"}), off);
  // AO at strength 0 is 1 - 0 (1 - ao) = 1 exactly.
  EXPECT_EQ(render_hash({"/materials/blend/ao/mode=frame", "/materials/blend/ao/strength=0"}), off);
  // Baked AO of a blend is the AO of the combined surface: layers of one constant height alpha-blend to a flat
  // surface, whose AO is 1 (the map stores 1 exactly: 16 bits hide the rounding of the blend), so the image is
  // the AO-off one.
  {
    const TemporaryConeCache cache;  // the bake goes to a temporary cache
    std::vector<std::string> flat{"/materials/blend/blend/operator=alpha"};
    for (int i = 0; i < 4; ++i) {
      const std::string layer = "/materials/blend/layers/" + std::to_string(i);
      flat.push_back(layer + R"(/height={"procedural": "flat", "size": 512})");
      flat.push_back(layer + "/height_scale=1");
    }
    const std::uint64_t flat_off = render_hash(flat);
    flat.push_back("/materials/blend/ao/mode=baked");
    EXPECT_EQ(render_hash(flat), flat_off);
  }
  // Specular generated from the albedo with scale 0 is the constant specular 0.
  const std::uint64_t no_specular = render_hash({"/materials/blend/lighting/specular=0"});
  EXPECT_EQ(render_hash({"/materials/blend/lighting/specular=0", "/materials/blend/layers/0/specular/scale=0"}),
            no_specular);
}

TEST(CliShadingOptions, EachOptionChangesTheImage) {
  const std::uint64_t off = render_hash({});
  for (const char* mode : {"hard", "horizon", "qdm_soft"})
    EXPECT_NE(render_hash({std::string("/materials/blend/shadow/mode=") + mode}), off) << mode;
  for (const char* mode : {"frame", "baked"}) {
    const TemporaryConeCache cache;  // baked AO maps go to a temporary cache
    EXPECT_NE(render_hash({std::string("/materials/blend/ao/mode=") + mode}), off) << mode;
  }
  EXPECT_NE(render_hash({"/materials/blend/lighting/model=cook_torrance"}), off);
  EXPECT_NE(render_hash({"/materials/blend/layers/0/specular/scale=2"}), off);
}

}  // namespace
}  // namespace qdmr::test
