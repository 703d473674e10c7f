// proctex rgbn from the command line: the round trip a user makes, and the error paths.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "../support/run.h"
#include "rgbn/rgbn.h"
#include "support.h"

using proctex::testing::run_proctex;
using namespace proctex::rgbn;
namespace fs = std::filesystem;

namespace {
const fs::path kTextures = fs::path(PROCTEX_SHARED_DIR) / "textures";
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }
}  // namespace

TEST(RgbnCli, PhotoToRgbnEditLightExportRoundTrip) {
  rgbn_test::TempDir dir("cli");
  const fs::path d = dir.path;
  // A height map from the brick photo, with the photo as albedo.
  auto r = run_proctex("rgbn import --height " + q(kTextures / "brick.png") + " --scale 6 --albedo " +
                           q(kTextures / "brick.png") + " -o " + q(d / "brick.exr") + " --json",
                       d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_LT(j["integrability"].get<double>(), 1e-3);
  const Rgbn brick = load_rgbn(d / "brick.exr");
  EXPECT_LT(max_norm_error(brick), 1e-5);

  std::ofstream(d / "ops.json") << R"([{"op":"stamp","at":[60,60],"shape":"dome","radius":20,"height":8},
    {"op":"pen","points":[[10,100],[120,130]],"width":4,"depth":2,"profile":"vee","xi":15}])";
  r = run_proctex("rgbn edit " + q(d / "ops.json") + " " + q(d / "brick.exr") + " -o " + q(d / "edited.exr") + " --json", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto e = nlohmann::json::parse(r.out);
  ASSERT_EQ(e["edits"].size(), 2u);
  EXPECT_GT(e["edits"][0]["pixels_changed"].get<int>(), 1000);

  r = run_proctex("rgbn light " + q(d / "edited.exr") + " --light 135,40 --model blinn -o " + q(d / "lit.png"), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(d / "lit.png"));
  for (const char* v : {"albedo", "normals", "base", "needles", "mean", "gaussian", "segments"}) {
    r = run_proctex("rgbn view " + q(d / "edited.exr") + " --view " + v + " -o " + q(d / (std::string(v) + ".png")), d);
    EXPECT_EQ(r.exit_code, 0) << v << r.err;
  }
  // Export in DirectX, import back as DirectX: the same normals (16-bit).
  r = run_proctex("rgbn export " + q(d / "edited.exr") + " --convention dx --bits 16 -o " + q(d / "n.png"), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_proctex("rgbn import " + q(d / "n.png") + " --convention dx -o " + q(d / "back.exr"), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(rgbn_test::max_angle(load_rgbn(d / "edited.exr"), load_rgbn(d / "back.exr")), 0.02);
}

TEST(RgbnCli, ErrorsAreOneLineNonZeroAndWriteNothing) {
  rgbn_test::TempDir dir("clierr");
  const fs::path d = dir.path;
  save_rgbn(Rgbn(16, 16), d / "flat.exr");
  save_rgbn(Rgbn(8, 8), d / "tiny.exr");
  struct Case {
    std::string args;
    int code;
  };
  const std::vector<Case> cases = {
      {"rgbn export " + q(d / "flat.exr") + " --convention up -o " + q(d / "out.png"), 2},
      {"rgbn filter " + q(kTextures / "brick.png") + " -o " + q(d / "out.exr"), 2},
      {"rgbn import --height " + q(kTextures / "brick.png") + " --albedo " + q(kTextures / "hubble_deep_field.jpg") + " -o " + q(d / "out.exr"), 1},
      {"rgbn stereo " + q(d / "a.png") + " " + q(d / "b.png") + " --light 0,45 --light 90,45 -o " + q(d / "out.exr"), 2},
      {"rgbn edit " + q(d / "missing.json") + " " + q(d / "flat.exr") + " -o " + q(d / "out.exr"), 1},
      // synthesis: an example below synth/'s 16 px, an unknown method, a fill without a mask, a bad bound
      {"rgbn synth " + q(d / "tiny.exr") + " --width 32 --height 32 --no-cache -o " + q(d / "out.exr"), 2},
      {"rgbn synth " + q(d / "flat.exr") + " --method quilt -o " + q(d / "out.exr"), 2},
      {"rgbn synth " + q(d / "flat.exr") + " --fill " + q(d / "flat.exr") + " -o " + q(d / "out.exr"), 2},
      {"rgbn synth " + q(d / "flat.exr") + " --xi 95 -o " + q(d / "out.exr"), 2},
  };
  for (const auto& c : cases) {
    const auto r = run_proctex(c.args, d);
    EXPECT_EQ(r.exit_code, c.code) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(d / "out.exr")) << c.args;
    EXPECT_FALSE(fs::exists(d / "out.png")) << c.args;
  }
}

TEST(RgbnCli, MipSynthStereoAndPtmRunFromTheCommandLine) {
  rgbn_test::TempDir dir("cli2");
  const fs::path d = dir.path;
  Rgbn r = from_height(rgbn_test::periodic_field(32, 32, 51, 4.0f), 1.0f, true);
  save_rgbn(r, d / "r.exr");
  auto res = run_proctex("rgbn mip " + q(d / "r.exr") + " -o " + q(d / "mips") +
                             " --footprints 2,4 --methods naive,toksvig,vmf --exponents 16 --json",
                         d);
  ASSERT_EQ(res.exit_code, 0) << res.err;
  const auto j = nlohmann::json::parse(res.out);
  ASSERT_EQ(j["levels"].size(), 2u);
  EXPECT_LE(j["levels"][1]["error"]["vmf"]["16"].get<double>(), j["levels"][1]["error"]["toksvig"]["16"].get<double>());
  EXPECT_TRUE(fs::exists(d / "mips" / "vmf_f4.exr"));
  res = run_proctex("rgbn synth " + q(d / "r.exr") + " --width 48 --height 40 --seed 3 --json -o " + q(d / "s.exr"), d);
  ASSERT_EQ(res.exit_code, 0) << res.err;
  EXPECT_EQ(nlohmann::json::parse(res.out)["seed"].get<int>(), 3);
  EXPECT_EQ(load_rgbn(d / "s.exr").width, 48);
  // Stereo from renders written by `rgbn light` (linear EXR, no ambient).
  std::string photos, lights;
  for (const char* l : {"0,65", "120,65", "240,65", "60,80"}) {
    const std::string name = std::string("p") + l[0] + l[1] + ".exr";
    res = run_proctex("rgbn light " + q(d / "r.exr") + " --light " + l + " --ambient 0 -o " + q(d / name), d);
    ASSERT_EQ(res.exit_code, 0) << res.err;
    photos += " " + q(d / name);
    lights += std::string(" --light ") + l;
  }
  res = run_proctex("rgbn stereo" + photos + lights + " --json -o " + q(d / "ps.exr"), d);
  ASSERT_EQ(res.exit_code, 0) << res.err;
  const Rgbn ps = load_rgbn(d / "ps.exr");
  double mean = 0;
  for (size_t i = 0; i < r.size(); ++i) mean += rgbn_test::angle_deg(&ps.normal[3 * i], &r.normal[3 * i]);
  EXPECT_LT(mean / double(r.size()), 1.0);
  // A PTM needs 6 photos: 4 is a usage error, and nothing is written.
  res = run_proctex("rgbn ptm fit" + photos + lights + " -o " + q(d / "x.ptm.exr"), d);
  EXPECT_EQ(res.exit_code, 2);
  EXPECT_FALSE(fs::exists(d / "x.ptm.exr"));
}

TEST(RgbnCli, SynthFillsAHoleAndKeepsTheRest) {
  rgbn_test::TempDir dir("clisynth");
  const fs::path d = dir.path;
  auto r = run_proctex("rgbn import --height " + q(kTextures / "gravel.png") + " --scale 4 --albedo " +
                           q(kTextures / "gravel.png") + " -o " + q(d / "g.exr"),
                       d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Rgbn g = load_rgbn(d / "g.exr");
  // The example: a 96^2 corner; the target: the whole photo with a 40^2 hole.
  Rgbn ex(96, 96);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      std::copy_n(g.a(x, y), 3, ex.a(x, y));
      std::copy_n(g.n(x, y), 3, ex.n(x, y));
    }
  save_rgbn(ex, d / "ex.exr");
  proctex::Image mask(g.width, g.height, 0.0f);
  for (int y = 100; y < 140; ++y)
    for (int x = 120; x < 160; ++x) std::fill_n(mask.pixel(x, y), 3, 1.0f);
  proctex::save_image(mask, d / "hole.png");
  r = run_proctex("rgbn synth " + q(d / "ex.exr") + " --fill " + q(d / "g.exr") + " --mask " + q(d / "hole.png") +
                      " --compose --xi 20 --seed 9 --no-cache --json -o " + q(d / "f.exr"),
                  d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "synth");
  EXPECT_EQ(j["seed"].get<int>(), 9);
  EXPECT_EQ(j["pixels"].get<int>(), 40 * 40);
  const Rgbn f = load_rgbn(d / "f.exr");
  size_t changed = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const bool in = x >= 120 && x < 160 && y >= 100 && y < 140;
      // Through a file: loading renormalises normals, which may move the last bit.
      bool same = true;
      for (int c = 0; c < 3; ++c)
        same = same && std::fabs(g.n(x, y)[c] - f.n(x, y)[c]) < 1e-6f && g.a(x, y)[c] == f.a(x, y)[c];
      if (!in) ASSERT_TRUE(same) << x << "," << y << ": " << g.n(x, y)[0] << " " << f.n(x, y)[0] << " " << g.a(x, y)[0] << " " << f.a(x, y)[0];
      changed += in && !same;
      if (in) EXPECT_GE(f.n(x, y)[2], std::sin(20 * M_PI / 180) - 1e-4);
    }
  EXPECT_GT(changed, size_t(40 * 40 * 9 / 10));
}
