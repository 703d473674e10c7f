// proctex morph and proctex catalog link as a user runs them: files written, JSON, exit codes.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;
using testing::run_proctex;
using testing::TempDir;

class MorphCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    catalog::BuildOptions o;
    o.db = *dir_ / "cat.sqlite";
    o.shaders = {"circle", "stripes", "superellipse"};
    o.settings.samples = 10;
    o.settings.resolution = o.settings.screen_resolution = 64;
    o.settings.thumbnail = 32;
    o.settings.probes = 0;
    o.settings.max_iterations = 1;
    o.seed = 3;
    o.jobs = 2;
    catalog::build(o);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  testing::RunResult run(const std::string& args) { return run_proctex(args, scratch_.path()); }
  static std::string db() { return "--db '" + (*dir_ / "cat.sqlite").string() + "'"; }
  static TempDir* dir_;
  TempDir scratch_;
};
TempDir* MorphCli::dir_ = nullptr;

TEST_F(MorphCli, WritesFramesSheetManifestAndGif) {
  const fs::path out = scratch_ / "frames";
  fs::create_directories(out);
  std::ofstream(out / "frame_0099.png") << "stale";  // from an earlier, longer run
  const auto r = run("-q morph 'stripes:duty=0.2,seed=4' 'stripes:duty=0.8,angle=40,seed=4' " + db() +
                     " --frames 12 --size 64 -o '" + out.string() + "' --gif '" + (scratch_ / "m.gif").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"].get<int>(), 12);
  EXPECT_TRUE(j["quality"]["morph"].contains("max_dissimilarity"));
  EXPECT_TRUE(j["quality"]["linear"].contains("layout_mean"));
  EXPECT_TRUE(j["quality"].contains("beats_linear_on_max"));
  for (int i = 1; i <= 12; ++i) EXPECT_TRUE(fs::exists(out / fmt::format("frame_{:04d}.png", i))) << i;
  EXPECT_FALSE(fs::exists(out / "frame_0099.png")) << "stale frames are removed";
  EXPECT_FALSE(fs::exists(out / "frame_0013.png"));
  EXPECT_TRUE(fs::exists(out / "sheet.png"));
  const auto manifest = nlohmann::json::parse(testing::read_text(out / "manifest.json"));
  ASSERT_EQ(manifest["frames"].size(), 12u);
  EXPECT_EQ(manifest["frames"][0]["file"], "frame_0001.png");
  EXPECT_EQ(manifest["frames"][0]["key"], 0);
  EXPECT_EQ(manifest["frames"][11]["key"], 1);
  EXPECT_TRUE(manifest["frames"][0]["similarity_to_previous"].is_null());
  EXPECT_TRUE(manifest["frames"][1]["similarity_to_previous"].is_number());
  EXPECT_FALSE(manifest["path"].empty());
  auto gif = OIIO::ImageInput::open((scratch_ / "m.gif").string());
  ASSERT_TRUE(gif);
  EXPECT_EQ(gif->spec().width, 64);
  int subimages = 0;
  while (gif->seek_subimage(subimages, 0)) ++subimages;
  EXPECT_EQ(subimages, 12);
}

TEST_F(MorphCli, HumanReportAndHelp) {
  auto r = run("-q morph stripes 'stripes:duty=0.7' " + db() + " --frames 8");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("morph: stripes, 8 frames"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("linear"), std::string::npos) << r.out;
  r = run("morph --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--dissolve"), std::string::npos);
  EXPECT_NE(r.out.find("perceptual"), std::string::npos);
}

TEST_F(MorphCli, ErrorsAreOneLineWithTheRightExitCode) {
  auto r = run("morph stripes " + db());  // one input
  EXPECT_EQ(r.exit_code, 2) << r.err;
  r = run("morph stripes circle " + db() + " --frames 8");  // no jump edges
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("proctex: error: no jump edges connect shader 'stripes' to 'circle'"), std::string::npos) << r.err;
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  r = run("morph 'stripes:nope=1' stripes " + db());  // unknown parameter
  EXPECT_EQ(r.exit_code, 2) << r.err;
  r = run("morph stripes stripes --db '" + (scratch_ / "missing.sqlite").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no catalogue"), std::string::npos) << r.err;
}

TEST_F(MorphCli, LinkThenMorphAcrossShaders) {
  const std::string copy = (scratch_ / "linked.sqlite").string();
  { catalog::Store(*dir_ / "cat.sqlite", catalog::Store::Access::Write); }  // fold the WAL into the file
  fs::copy_file(*dir_ / "cat.sqlite", copy);
  auto r = run("-q catalog link --db '" + copy + "' --shaders circle,superellipse --jumps 1 --rounds 1 --evaluations 8 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto link = nlohmann::json::parse(r.out);
  ASSERT_EQ(link["pairs"].size(), 1u);
  EXPECT_EQ(link["pairs"][0]["refined"].size(), 1u);
  r = run("-q morph superellipse circle --db '" + copy + "' --frames 10 --dissolve 3 --json --no-compare");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["jumps"].get<int>(), 1);
  EXPECT_EQ(j["shaders"], nlohmann::json({"superellipse", "circle"}));
  EXPECT_FALSE(j["quality"].contains("linear"));
  r = run("catalog link --db '" + copy + "' --shaders circle,marble");
  EXPECT_EQ(r.exit_code, 2) << r.err;
}

}  // namespace
}  // namespace proctex
