// qdmr check and qdmr diff through the command, as a CI job runs them: exit codes, --update, diff folders, JUnit,
// the HTML report, the one-off forms and the bits version.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "qdmr/core/version.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

std::string plane() { return (source_dir() / "scenes" / "plane.json").string(); }

// A small manifest of the plane: an exact check and a tolerance check against a PNG golden.
void write_manifest(const TempDir& dir, const std::string& extra_checks = "") {
  write_file(dir / "m.json", R"({
  "bits_version": )" + std::to_string(kBitsVersion) + R"(,
  "defaults": {"width": 64, "height": 36},
  "checks": [
    {"name": "exact", "scene": ")" + plane() + R"(", "outputs": ["color", "depth"],
     "variants": [{}, {"threads": 1, "tile": 8}]},
    {"name": "fuzzy", "scene": ")" + plane() + R"(", "mode": "tolerance", "golden": {"color": "g/fuzzy.png"}})" +
                                extra_checks + R"(
  ]
})");
}

CommandResult check(const TempDir& dir, std::vector<std::string> args) {
  args.insert(args.begin(), {"check", (dir / "m.json").string(), "--diff-dir", (dir / "diffs").string()});
  return run(cli(), args);
}

TEST(CheckCommand, MissingGoldensCannotRunUntilUpdateWritesThem) {
  TempDir dir;
  write_manifest(dir);
  const CommandResult first = check(dir, {});
  EXPECT_EQ(first.exit_code, 2) << first.output;
  EXPECT_NE(first.output.find("no hash for output 'color' yet: run qdmr check with --update"), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("no golden image yet"), std::string::npos) << first.output;

  const CommandResult update = check(dir, {"--update"});
  ASSERT_EQ(update.exit_code, 0) << update.output;
  EXPECT_NE(update.output.find("UPDATED exact"), std::string::npos) << update.output;
  EXPECT_TRUE(fs::exists(dir / "g" / "fuzzy.png"));
  // The manifest keeps its key order: "name" is still the first key of a check.
  const std::string text = read_file(dir / "m.json");
  EXPECT_LT(text.find("\"name\": \"exact\""), text.find("\"hash\""));
  const auto manifest = nlohmann::json::parse(text);
  EXPECT_EQ(manifest["checks"][0]["hash"]["color"].get<std::string>().substr(0, 5), "sha1:");
  EXPECT_TRUE(manifest["checks"][0]["hash"].contains("depth"));

  const CommandResult again = check(dir, {});
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("2 checks"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "diffs"));  // nothing failed, nothing written
  // --update on passing checks changes nothing.
  const std::string before = read_file(dir / "m.json");
  EXPECT_EQ(check(dir, {"--update"}).exit_code, 0);
  EXPECT_EQ(read_file(dir / "m.json"), before);
}

TEST(CheckCommand, AChangedImageFailsWithADiffFolderJUnitAndReport) {
  TempDir dir;
  write_manifest(dir);
  ASSERT_EQ(check(dir, {"--update"}).exit_code, 0);
  // A wrong hash for the exact check, and a third check whose camera differs from the golden it shares.
  auto manifest = nlohmann::json::parse(read_file(dir / "m.json"));
  manifest["checks"][0]["hash"]["color"] = "sha1:" + std::string(40, '0');
  manifest["checks"].push_back({{"name", "moved"}, {"scene", plane()}, {"mode", "tolerance"},
                                {"golden", {{"color", "g/fuzzy.png"}}}, {"set", {{"/camera/fov_deg", 40}}}});
  write_file(dir / "m.json", manifest.dump(2));

  const CommandResult failed = check(dir, {"--junit", (dir / "junit.xml").string(), "--report", (dir / "report").string()});
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_NE(failed.output.find("FAIL    exact"), std::string::npos) << failed.output;
  EXPECT_NE(failed.output.find("color: hash sha1:"), std::string::npos);
  EXPECT_NE(failed.output.find("expected sha1:0000"), std::string::npos);
  EXPECT_NE(failed.output.find("PASS    fuzzy"), std::string::npos);
  EXPECT_NE(failed.output.find("FAIL    moved"), std::string::npos);
  EXPECT_NE(failed.output.find("color: pixels over max_abs"), std::string::npos) << failed.output;

  // With --report the diff folders go into the report folder.
  const fs::path exact = dir / "report" / "exact", moved = dir / "report" / "moved";
  for (const char* name : {"color.rendered.exr", "color.rendered.png", "failures.txt"})
    EXPECT_TRUE(fs::exists(exact / name)) << name;
  for (const char* name : {"color.rendered.png", "color.golden.png", "color.diff.png", "color.histogram.svg",
                           "color.histogram.csv", "failures.txt"})
    EXPECT_TRUE(fs::exists(moved / name)) << name;
  EXPECT_NE(read_file(moved / "failures.txt").find("pixels over max_abs"), std::string::npos);
  EXPECT_NE(read_file(moved / "color.histogram.svg").find("<svg"), std::string::npos);
  const std::string html = read_file(dir / "report" / "index.html");
  EXPECT_NE(html.find("src=\"moved/color.diff.png\""), std::string::npos);
  EXPECT_NE(html.find("1 passed, 2 failed"), std::string::npos);

  const std::string junit = read_file(dir / "junit.xml");
  EXPECT_NE(junit.find("<testsuites name=\"qdmr check\" tests=\"3\" failures=\"2\" errors=\"0\""), std::string::npos) << junit;
  EXPECT_NE(junit.find("<testcase classname=\"qdmr.check.m\" name=\"fuzzy\""), std::string::npos);
  EXPECT_NE(junit.find("<failure message=\"color: hash sha1:"), std::string::npos);

  // --jobs 2 gives the same verdicts.
  const CommandResult parallel = check(dir, {"--jobs", "2"});
  EXPECT_EQ(parallel.exit_code, 1);
  EXPECT_NE(parallel.output.find("1 passed, 2 failed"), std::string::npos) << parallel.output;
  // --update re-blesses the failing hash.
  manifest["checks"].erase(2);
  write_file(dir / "m.json", manifest.dump(2));
  const CommandResult update = check(dir, {"--update"});
  EXPECT_EQ(update.exit_code, 0) << update.output;
  EXPECT_NE(update.output.find("color: hash sha1:0000000000000000000000000000000000000000 -> sha1:"), std::string::npos);
}

TEST(CheckCommand, AnotherBitsVersionFailsWithOneClearLineNotPixelDifferences) {
  TempDir dir;
  write_manifest(dir);
  ASSERT_EQ(check(dir, {"--update"}).exit_code, 0);
  auto manifest = nlohmann::json::parse(read_file(dir / "m.json"));
  manifest["bits_version"] = kBitsVersion + 1;
  write_file(dir / "m.json", manifest.dump(2));
  const CommandResult r = check(dir, {});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("the goldens were made by bits version " + std::to_string(kBitsVersion + 1) +
                          ", this qdmr"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("renders bits version " + std::to_string(kBitsVersion)), std::string::npos);
  EXPECT_EQ(r.output.find("pixels over"), std::string::npos);
}

TEST(CheckCommand, SkipIfMissingSkipsAndBadManifestsExitTwo) {
  TempDir dir;
  write_file(dir / "m.json", R"({"bits_version": )" + std::to_string(kBitsVersion) + R"(, "checks": [
    {"name": "big", "scene": ")" + plane() + R"(", "skip_if_missing": ["no/such/asset.png"]}]})");
  const CommandResult skipped = check(dir, {"--junit", (dir / "j.xml").string()});
  EXPECT_EQ(skipped.exit_code, 0) << skipped.output;
  EXPECT_NE(skipped.output.find("SKIP    big"), std::string::npos);
  EXPECT_NE(read_file(dir / "j.xml").find("<skipped message=\"skipped: "), std::string::npos);

  write_file(dir / "m.json", R"({"bits_version": )" + std::to_string(kBitsVersion) + R"(, "checks": [{"name": "x", "scene": ")" + plane() + R"(", "outptus": []}]})");
  const CommandResult bad = check(dir, {});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("m.json: /checks/0: unknown key 'outptus'; did you mean 'outputs'?"), std::string::npos) << bad.output;
}

TEST(CheckCommand, OneOffFormsAgainstAGoldenImageOrAHash) {
  TempDir dir;
  const std::string golden = (dir / "plane.exr").string();
  const std::vector<std::string> scene{"check", plane(), "--width", "48", "--height", "27"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = scene;
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.end(), {"--diff-dir", (dir / "diffs").string()});
    return run(cli(), args);
  };
  const CommandResult missing = with({"--golden", golden});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("no golden image yet: run qdmr check with --update"), std::string::npos) << missing.output;
  ASSERT_EQ(with({"--golden", golden, "--update"}).exit_code, 0);
  EXPECT_EQ(with({"--golden", golden}).exit_code, 0);
  const CommandResult moved = with({"--golden", golden, "--set", "/camera/fov_deg=45"});
  EXPECT_EQ(moved.exit_code, 1) << moved.output;
  EXPECT_EQ(with({"--golden", golden, "--set", "/camera/fov_deg=45", "--max-abs", "1"}).exit_code, 0);

  const CommandResult printed = with({"--hash", "none", "--update"});
  ASSERT_EQ(printed.exit_code, 0) << printed.output;
  const auto at = printed.output.find("hash of ");
  ASSERT_NE(at, std::string::npos) << printed.output;
  const std::string hash = printed.output.substr(printed.output.find("sha1:", at), 45);
  EXPECT_EQ(with({"--hash", hash}).exit_code, 0);
  EXPECT_EQ(with({"--hash", "sha1:" + std::string(40, 'a')}).exit_code, 1);
  EXPECT_EQ(with({"--hash", hash, "--golden", golden}).exit_code, 2);
}

TEST(DiffCommand, ComparesAnyTwoImagesWithTheCheckMetrics) {
  TempDir dir;
  const std::string a = (dir / "a.exr").string(), b = (dir / "b.exr").string(), small = (dir / "s.png").string();
  ASSERT_EQ(run(cli(), {"render", plane(), "-o", a, "--width", "64", "--height", "36"}).exit_code, 0);
  ASSERT_EQ(run(cli(), {"render", plane(), "-o", b, "--width", "64", "--height", "36", "--set", "/camera/fov_deg=45"}).exit_code, 0);
  ASSERT_EQ(run(cli(), {"render", plane(), "-o", small, "--width", "32", "--height", "18"}).exit_code, 0);

  const CommandResult same = run(cli(), {"diff", a, a});
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("max |delta| 0,"), std::string::npos) << same.output;
  const std::string heatmap = (dir / "heat.png").string();
  const CommandResult differ = run(cli(), {"diff", a, b, "--heatmap", heatmap});
  EXPECT_EQ(differ.exit_code, 1) << differ.output;
  EXPECT_NE(differ.output.find("FAIL pixels over max_abs"), std::string::npos);
  EXPECT_TRUE(fs::exists(heatmap));
  EXPECT_EQ(run(cli(), {"diff", a, b, "--max-abs", "10"}).exit_code, 0);
  const CommandResult sizes = run(cli(), {"diff", a, small});
  EXPECT_EQ(sizes.exit_code, 1);
  EXPECT_NE(sizes.output.find("size: rendered 64x36 with 3 channel(s), golden 32x18 with 3"), std::string::npos) << sizes.output;
  const CommandResult unreadable = run(cli(), {"diff", a, (dir / "none.exr").string()});
  EXPECT_EQ(unreadable.exit_code, 2);
  EXPECT_NE(unreadable.output.find("none.exr"), std::string::npos);
  EXPECT_EQ(run(cli(), {"diff", a, b, "--heatmap", a}).exit_code, 2);  // never over an input
}

}  // namespace
}  // namespace qdmr::test

namespace qdmr::test {
namespace {

TEST(BitsVersion, EveryImageAndStatsFileCarriesIt) {
  TempDir dir;
  const std::vector<std::string> files{"a.png", "a.exr", "a.tif"};
  for (const std::string& name : files) {
    ASSERT_EQ(run(cli(), {"render", plane(), "-o", (dir / name).string(), "--width", "16", "--height", "9", "--stats",
                          (dir / "stats.json").string(), "--aov", "depth=" + (dir / ("depth_" + name)).string()})
                  .exit_code,
              0);
    for (const std::string& file : {name, "depth_" + name}) {
      auto in = OIIO::ImageInput::open((dir / file).string());
      ASSERT_TRUE(in) << file;
      const std::string software = std::string("qdmr ") + version() + " (bits version " + std::to_string(kBitsVersion) + ")";
      EXPECT_EQ(in->spec().get_string_attribute("Software"), software) << file;
      if (!name.ends_with(".tif")) {  // TIFF keeps only its own tags
        EXPECT_EQ(in->spec().get_string_attribute("qdmr:bits_version"), std::to_string(kBitsVersion)) << file;
      }
    }
  }
  const auto stats = nlohmann::json::parse(read_file(dir / "stats.json"));
  EXPECT_EQ(stats["bits_version"], kBitsVersion);
  EXPECT_EQ(stats["qdmr_version"], version());
  const CommandResult v = run(cli(), {"--version"});
  EXPECT_EQ(v.exit_code, 0);
  EXPECT_NE(v.output.find("bits version " + std::to_string(kBitsVersion)), std::string::npos) << v.output;
}

}  // namespace
}  // namespace qdmr::test
