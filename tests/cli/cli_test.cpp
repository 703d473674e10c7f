// End-to-end tests of the proctex binary in a scratch folder: what a user types, what they get.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "image/image.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using testing::line_count;
using testing::run_proctex;

class Cli : public ::testing::Test {
 protected:
  testing::TempDir dir;
  testing::RunResult run(const std::string& args) { return run_proctex(args, dir.path()); }
  std::string path(const std::string& name) { return (dir / name).string(); }

  // Bad input: a non-zero exit with exactly one line on stderr that starts "proctex: error:".
  void expect_clean_error(const testing::RunResult& r, int code, const std::string& mentions) {
    EXPECT_EQ(r.exit_code, code) << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
  }
};

TEST_F(Cli, HelpOnEveryCommand) {
  for (const char* cmd : {"", "devices", "shaders", "shaders list", "shaders show", "render"}) {
    const auto r = run(std::string(cmd) + " --help");
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd;
  }
}

TEST_F(Cli, NoCommandIsBadUsage) {
  const auto r = run("");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("proctex: error:"), std::string::npos);
}

TEST_F(Cli, DevicesJsonMarksTheSelectedDevice) {
  const auto r = run("devices --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_FALSE(j.empty());
  int selected = 0;
  for (const auto& d : j) selected += d["selected"].get<bool>();
  EXPECT_EQ(selected, 1);
}

TEST_F(Cli, ShadersListAndShowAgree) {
  const auto list = run("shaders list --json");
  ASSERT_EQ(list.exit_code, 0) << list.err;
  const auto shaders = nlohmann::json::parse(list.out);
  EXPECT_GE(shaders.size(), 12u);
  const std::string name = shaders[0]["name"];
  const auto show = run("shaders show " + name + " --json");
  ASSERT_EQ(show.exit_code, 0) << show.err;
  const auto j = nlohmann::json::parse(show.out);
  EXPECT_EQ(j["name"], name);
  EXPECT_EQ(j["params"].size(), shaders[0]["parameter_count"].get<size_t>());
  for (const auto& p : j["params"]) {
    EXPECT_TRUE(p.contains("type") && p.contains("default") && p.contains("help")) << p.dump();
  }
  const auto human = run("shaders show " + name);
  EXPECT_NE(human.out.find("default"), std::string::npos);
}

// A parameter's declared symmetry (shader.h: period, exchange) is what a shader author checks:
// `shaders show` prints it in the table and in the JSON.
TEST_F(Cli, ShadersShowTellsADeclaredSymmetryOrDependency) {
  const auto human = run("shaders show superellipse");
  ASSERT_EQ(human.exit_code, 0) << human.err;
  EXPECT_NE(human.out.find("exchange width/height"), std::string::npos) << human.out;
  const auto star = run("shaders show star");
  EXPECT_NE(star.out.find("period 360/points"), std::string::npos) << star.out;
  const auto j = nlohmann::json::parse(run("shaders show rectangle --json").out);
  for (const auto& p : j["params"]) {
    if (p["name"] == "rotation") EXPECT_EQ(p["exchange"], nlohmann::json({"width", "height"})) << p.dump();
    else EXPECT_FALSE(p.contains("exchange")) << p.dump();
  }
  // A dependency, told the same way: what a shader author reads before wondering why a frequency
  // does nothing.
  EXPECT_NE(run("shaders show stripes").out.find("needs wave"), std::string::npos);
  const auto stripes = nlohmann::json::parse(run("shaders show stripes --json").out);
  for (const auto& p : stripes["params"])
    if (p["name"] == "wave_frequency") EXPECT_EQ(p["needs"], "wave") << p.dump();
    else EXPECT_FALSE(p.contains("needs")) << p.dump();
}

TEST_F(Cli, RendersInlineSpecAtRequestedSize) {
  const auto r = run("render 'checker:squares=4,color_a=#ff0000' -o " + path("c.png") + " --size 200 --width 300");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image img = load_image(path("c.png"));
  EXPECT_EQ(img.width, 300);
  EXPECT_EQ(img.height, 200);
  // Top-left square is color_a: pure red.
  const float* p = img.pixel(10, 10);
  EXPECT_NEAR(p[0], 1.0f, 0.01f);
  EXPECT_NEAR(p[1], 0.0f, 0.01f);
}

TEST_F(Cli, RendersJsonSpecFileAndRecordsFullSpec) {
  std::ofstream(path("spec.json")) << R"({"shader": "checker", "params": {"squares": 6}, "seed": 11})";
  const auto r = run("render " + path("spec.json") + " -o " + path("c.exr") + " --size 64 --json --spec-out " +
                     path("full.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["spec"]["seed"], 11);
  EXPECT_EQ(j["spec"]["params"]["squares"], 6);
  const auto full = nlohmann::json::parse(testing::read_text(path("full.json")));
  EXPECT_EQ(full["params"].size(), 3u);  // every parameter written out
  EXPECT_EQ(load_image(path("c.exr")).width, 64);
}

TEST_F(Cli, SeedOptionChangesAStochasticTexture) {
  ASSERT_EQ(run("render clouds -o " + path("a.png") + " --size 64 --seed 1").exit_code, 0);
  ASSERT_EQ(run("render clouds -o " + path("b.png") + " --size 64 --seed 2").exit_code, 0);
  ASSERT_EQ(run("render clouds -o " + path("c.png") + " --size 64 --seed 1").exit_code, 0);
  EXPECT_NE(load_image(path("a.png")).pixels, load_image(path("b.png")).pixels);
  EXPECT_EQ(load_image(path("a.png")).pixels, load_image(path("c.png")).pixels);
}

TEST_F(Cli, UnknownShaderIsAOneLineUsageError) {
  const auto r = run("render chcker -o " + path("x.png"));
  expect_clean_error(r, 2, "unknown shader 'chcker'");
  EXPECT_NE(r.err.find("checker"), std::string::npos) << "should suggest the close name";
  EXPECT_FALSE(std::filesystem::exists(path("x.png")));
}

TEST_F(Cli, OutOfRangeAndUnknownParametersAreUsageErrors) {
  expect_clean_error(run("render checker:squares=1000 -o " + path("x.png")), 2, "out of range");
  expect_clean_error(run("render checker:nope=1 -o " + path("x.png")), 2, "no parameter 'nope'");
  expect_clean_error(run("render checker --size 0 -o " + path("x.png")), 2, "--size");
}

TEST_F(Cli, HugeRenderIsRefusedCleanly) {
  expect_clean_error(run("render checker --size 60000 -o " + path("x.png")), 1, "exceeds the limit");
}

TEST_F(Cli, UnwritableOutputIsARuntimeError) {
  const auto r = run("render checker --size 16 -o " + path("missing-dir/x.png"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
}

TEST_F(Cli, BadDeviceIsAUsageError) {
  expect_clean_error(run("--device no-such-device render checker --size 16 -o " + path("x.png")), 2, "no OpenCL device");
}

TEST_F(Cli, UserShaderFolderAndCompileErrorsNameFileAndLine) {
  std::filesystem::create_directories(dir / "mine");
  std::ofstream(dir / "mine" / "broken.cl") << "// @shader \"broken on purpose\"\n"
                                               "// @param float a = 0.5 [0, 1] \"a\"\n"
                                               "float3 shade(float2 p, float fw, uint seed, const Params P) {\n"
                                               "  return undefined_thing;\n}\n";
  const auto r = run_proctex("render broken -o " + path("x.png"), dir.path());
  expect_clean_error(r, 2, "unknown shader");  // not on the path yet
  const std::string env = "PROCTEX_SHADER_PATH='" + (dir / "mine").string() + "' ";
  const std::string cmd = env + "'" + PROCTEX_BINARY + "' render broken -o " + path("x.png") + " 2>" + path("err.txt");
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = testing::read_text(path("err.txt"));
  EXPECT_NE(err.find("broken.cl:4"), std::string::npos) << err;
  EXPECT_EQ(line_count(err), 1) << err;
}

}  // namespace
}  // namespace proctex
