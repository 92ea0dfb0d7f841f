// The emulated texture cache in a frame: off by default, the same statistics and cache_misses AOV for every ISA,
// thread count and tile size, the image untouched by it, and settings the frame cannot honour refused.
#include <gtest/gtest.h>

#include <numeric>

#include "cli/cli_test_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"

namespace qdmr::test {
namespace {

SceneDesc cache_scene(const std::string& name, std::vector<SceneOverride> overrides = {}) {
  return test::small_scene(name, std::move(overrides), 160, 96);
}

const PixelBuffer& misses_plane(const Frame& frame) {
  for (const AovImage& a : frame.aovs)
    if (a.aov == Aov::CacheMisses) return a.pixels;
  throw Error("test", "no cache_misses AOV");
}

TEST(TextureCache, IsOffUnlessAsked) {
  const Frame frame = render_frame(cache_scene("plane"), RenderOptions{});
  EXPECT_FALSE(frame.stats.texture_cache.enabled);
  EXPECT_FALSE(frame.stats.to_json().contains("texture_cache"));
}

TEST(TextureCache, AskingForTheMissesAovTurnsItOn) {
  RenderOptions options;
  options.aovs = {Aov::CacheMisses};
  const Frame frame = render_frame(cache_scene("plane"), options);
  const TextureCacheStats& c = frame.stats.texture_cache;
  ASSERT_TRUE(c.enabled);
  EXPECT_EQ(c.layout, "linear");
  EXPECT_EQ(c.size_bytes, 8192);
  // Normal mapping reads albedo and normal trilinearly: 2 x 8 texels per shaded pixel, plus the helper lanes of
  // partly covered quads (a few per cent on this plane).
  EXPECT_GE(c.accesses_per_pixel, 16.0);
  EXPECT_LT(c.accesses_per_pixel, 17.0);
  EXPECT_GT(c.misses, 0u);
  EXPECT_EQ(c.hits + c.misses, c.accesses);
  // The AOV holds the misses of covered pixels' own lanes: at most all misses, and most of them (the helper
  // lanes outside the plane are few).
  const PixelBuffer& misses = misses_plane(frame);
  const double sum = std::accumulate(misses.begin(), misses.end(), 0.0);
  EXPECT_LE(sum, double(c.misses));
  EXPECT_GT(sum, 0.9 * double(c.misses));
}

// Every ISA this machine runs, 1 and 2 threads, tiles of 32, 64 and 96 pixels: bit-identical statistics and
// AOV. The scenes cover every fetch path: QDM over a per-pixel 4-layer blend with qdm_soft shadows and baked AO
// (terrain), and POM, relief and QDM on meshes (objects_displaced).
TEST(TextureCache, TheSameForEveryIsaThreadCountAndTileSize) {
  for (const char* name : {"terrain", "objects_displaced"}) {
    SCOPED_TRACE(name);
    const SceneDesc scene = cache_scene(name, {{"/texture_cache/layout", "\"tiled4\""}});
    struct Setting {
      Isa isa;
      int threads, tile;
    };
    std::vector<Setting> settings;
    for (Isa isa : usable_isas()) settings.push_back({isa, 2, 64});
    settings.push_back({Isa::Sse42, 1, 32});
    settings.push_back({usable_isas().front(), 2, 96});
    std::optional<Frame> first;
    for (const Setting& s : settings) {
      RenderOptions options;
      options.isa = s.isa;
      options.threads = s.threads;
      options.tile_size = s.tile;
      options.aovs = {Aov::CacheMisses};
      Frame frame = render_frame(scene, options);
      SCOPED_TRACE(std::string(isa_name(s.isa)) + ", " + std::to_string(s.threads) + " threads, tile " +
                   std::to_string(s.tile));
      if (!first) {
        first = std::move(frame);
        EXPECT_GT(first->stats.texture_cache.accesses, 0u);
        continue;
      }
      EXPECT_EQ(frame.stats.texture_cache.accesses, first->stats.texture_cache.accesses);
      EXPECT_EQ(frame.stats.texture_cache.hits, first->stats.texture_cache.hits);
      EXPECT_TRUE(same_bits(misses_plane(frame), misses_plane(*first)));
    }
  }
}

// Also what the batch pairing and quad packing do: with the cache on, the rasterizer hands a program one batch at a
// time, holding the quads of one triangle; off, it packs the quads of batches with an empty quad into shared
// batches across triangles (where a batch holds several quads), and hands QDM, relief, POM and normal mapping two
// batches at a time (ShadingProgram::grouping). Every lane's result must be the same: image, displacement AOVs,
// the loop statistics per pixel; only the batch count may fall. Programs also run their loops without the recorder's tests
// when none listens. objects_displaced has single-layer QDM, POM and relief (paired) on meshes, and again with
// CSM and RCSM (not paired) for its two QDM materials; terrain a 256x256 grid of small triangles under QDM over
// a 4-layer blend with per-pixel weights (grouped: the covered lanes of up to eight sparse batches packed into
// fewer), with and without the displaced depth, on its combined quadtree and on the product of the layers' and
// weights' trees; surface_blend_4layers under POM and QDM, its 4 layers blended by vertex weights (grouped alike);
// plane normal mapping (paired, no trace).
TEST(TextureCache, LeavesTheImageAsItIs) {
  struct Case {
    const char* scene;
    std::vector<SceneOverride> overrides;
  };
  const Case cases[] = {{"objects_displaced", {}},
                        {"objects_displaced",
                         {{"/materials/floor/technique/name", "\"csm\""}, {"/materials/stone_box/technique/name", "\"rcsm\""}}},
                        {"terrain", {}},
                        {"terrain", {{"/materials/ground/technique/write_depth", "true"}}},
                        {"terrain", {{"/materials/ground/blend/quadtree", "\"product\""}}},
                        {"surface_blend_4layers", {}},
                        {"surface_blend_4layers", {{"/materials/blend/technique/name", "\"qdm\""}}},
                        {"plane", {}}};
  for (const Case& c : cases) {
    const char* name = c.scene;
    for (Isa isa : usable_isas()) {
      SCOPED_TRACE(std::string(name) + (c.overrides.empty() ? "" : " with " + c.overrides[0].pointer) + ", " +
                   std::string(isa_name(isa)));
      const SceneDesc off = cache_scene(name, c.overrides);
      auto cache_overrides = c.overrides;
      cache_overrides.push_back({"/texture_cache/layout", "\"morton\""});
      const SceneDesc on = cache_scene(name, cache_overrides);
      ASSERT_TRUE(on.texture_cache.enabled);
      RenderOptions options;
      options.isa = isa;
      options.aovs = {Aov::Depth, Aov::Normal, Aov::Iterations, Aov::HitUV, Aov::HitDepth, Aov::Shadow, Aov::Ao};
      const Frame a = render_frame(off, options), b = render_frame(on, options);
      EXPECT_TRUE(same_bits(a.color, b.color));
      ASSERT_EQ(a.aovs.size(), b.aovs.size());
      for (std::size_t i = 0; i < a.aovs.size(); ++i)
        EXPECT_TRUE(same_bits(a.aovs[i].pixels, b.aovs[i].pixels)) << aov_name(a.aovs[i].aov);
      const bool traces = std::string(name) != "plane";  // plane: normal mapping, no loop to count
      if (traces) {
        EXPECT_GT(a.stats.iterations_mean, 0.0);
      }
      EXPECT_EQ(a.stats.iterations_mean, b.stats.iterations_mean);
      EXPECT_EQ(a.stats.iterations_max, b.stats.iterations_max);
      EXPECT_EQ(a.stats.quads, b.stats.quads);
      EXPECT_EQ(a.stats.pixels_shaded, b.stats.pixels_shaded);
      EXPECT_EQ(a.stats.pixels_depth_failed, b.stats.pixels_depth_failed);
      // Rasterized batches: with one quad per batch there are no quads of different triangles to pack into one.
      if (isa == Isa::Sse42) {
        EXPECT_EQ(a.stats.batches, b.stats.batches);
      } else {
        EXPECT_LT(a.stats.batches, b.stats.batches);
      }
      // The loops' lane utilisation counts what they executed: more of it useful where quads were packed (not
      // with one quad per batch) or a blend's groups packed sparse batches' lanes (every kernel).
      const bool grouped = std::string(name) == "terrain" || std::string(name) == "surface_blend_4layers";
      if (traces && (grouped || isa != Isa::Sse42)) {
        EXPECT_GT(a.stats.lane_utilisation, b.stats.lane_utilisation);
      } else {
        EXPECT_EQ(a.stats.lane_utilisation, b.stats.lane_utilisation);
      }
    }
  }
}

TEST(TextureCache, LayoutsChangeTheMissesNotTheReads) {
  const auto stats = [](const char* layout) {
    return render_frame(cache_scene("plane", {{"/texture_cache/layout", std::string("\"") + layout + "\""}}),
                        RenderOptions{})
        .stats.texture_cache;
  };
  const TextureCacheStats linear = stats("linear"), morton = stats("morton");
  EXPECT_EQ(linear.accesses, morton.accesses);
  // A trilinear footprint is 2x2 texels: in rows it spans two lines, in Morton order usually one.
  EXPECT_LT(morton.misses, linear.misses);
}

TEST(TextureCache, RefusesATileThatIsNotAWholeNumberOfRegions) {
  RenderOptions options;
  options.tile_size = 40;
  EXPECT_THROW(render_frame(cache_scene("plane", {{"/texture_cache/region", "32"}}), options), Error);
  options.tile_size = 48;
  EXPECT_NO_THROW(render_frame(cache_scene("plane", {{"/texture_cache/region", "16"}}), options));
}

TEST(TextureCache, SceneSettingsAreChecked) {
  const auto message = [](const std::string& pointer, const std::string& value) {
    try {
      cache_scene("plane", {{pointer, value}});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("/texture_cache/line_bytes", "48").find("/texture_cache/line_bytes"), std::string::npos);
  EXPECT_NE(message("/texture_cache/size_bytes", "1000").find("whole number of sets"), std::string::npos);
  EXPECT_NE(message("/texture_cache/layout", "\"swizzled\"").find("/texture_cache/layout"), std::string::npos);
  EXPECT_NE(message("/texture_cache/colour", "1").find("colour"), std::string::npos);
  EXPECT_EQ(message("/texture_cache/enabled", "false"), "accepted");
}

}  // namespace
}  // namespace qdmr::test
