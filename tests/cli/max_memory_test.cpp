// --max-memory: the plan's memory estimate is checked by Renderer::set_scene before anything is built, once (no
// second plan in the command), with the flag named in the message.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace qdmr::test
