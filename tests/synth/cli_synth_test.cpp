// `proctex synth` as a user runs it: outputs, determinism across runs and thread counts, windows
// that fit together, aligned maps, and one-line errors that leave no file behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <OpenImageIO/imageio.h>

#include "image/image.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using testing::run_proctex;
using testing::TempDir;

// A 64x64 exemplar cut from a real photo (gravel, CC0), saved as an 8-bit PNG.
std::filesystem::path make_exemplar(const TempDir& dir, int size = 64, const std::string& name = "ex.png") {
  const Image full = load_image(std::filesystem::path(PROCTEX_SHARED_DIR) / "textures" / "gravel.png");
  const auto path = dir / name;
  save_image(resize(crop(full, 64, 64, 256, 256), size, size), path);
  return path;
}

// Points the analysis cache of the commands run from this test at the scratch folder (inherited
// by the child process); returns "" so it reads as a prefix of the arguments.
std::string env(const TempDir& dir) {
  setenv("PROCTEX_CACHE_DIR", (dir / "cache").c_str(), 1);
  return "";
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  return testing::read_text(a) == testing::read_text(b);
}

// The raw pixel values of a file as written (no colour conversion), as floats.
std::vector<float> raw_pixels(const std::filesystem::path& p, int& w, int& h, int& channels, std::string& format) {
  auto in = OIIO::ImageInput::open(p.string());
  EXPECT_TRUE(in) << p;
  if (!in) return {};
  const auto& spec = in->spec();
  w = spec.width, h = spec.height, channels = spec.nchannels;
  format = spec.format.c_str();
  std::vector<float> px(static_cast<size_t>(w) * h * channels);
  in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data());
  return px;
}

std::string fmt_window(int64_t x, int64_t y, int w, int h) {
  return "--window " + std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(w) + "," + std::to_string(h);
}

std::vector<std::string> files_in(const std::filesystem::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) out.push_back(e.path().filename().string());
  return out;
}

TEST(SynthCli, WritesTheOutputAndReportsJson) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "out.png").string() +
                                 "' --size 200x120 --seed 9 --json",
                             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image out = load_image(dir / "out.png");
  EXPECT_EQ(out.width, 200);
  EXPECT_EQ(out.height, 120);
  EXPECT_NE(r.out.find("\"seed\": 9"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"analysis_cached\": false"), std::string::npos) << r.out;
  // The options that shape the result are recorded (the defaults of issue 13's fourth pass).
  EXPECT_NE(r.out.find("\"layout_shifts\": 32"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"rematch\": 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"refine_seams\": 0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"finest_passes\": 0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"rematch_candidates\": 1"), std::string::npos) << r.out;
  // The second run finds the analysis in the cache.
  const auto again = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "out2.png").string() +
                                     "' --size 200x120 --seed 9 --json",
                                 dir.path());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("\"analysis_cached\": true"), std::string::npos) << again.out;
  EXPECT_TRUE(same_file(dir / "out.png", dir / "out2.png"));
}

TEST(SynthCli, SameResultForAnyThreadCountAndStitchedWindows) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  const std::string common = "synth '" + ex.string() + "' --seed 3 --coords ";
  // The whole 128x96 region at (-300, 5000) with 1 and with 2 device threads (PoCL's pool size).
  for (const char* threads : {"1", "2"}) {
    const std::string cmd = env(dir) + "env POCL_MAX_PTHREAD_COUNT=" + threads + " '" +
                            PROCTEX_BINARY + "' " + common + "'" + (dir / (std::string("w") + threads + ".exr")).string() +
                            "' -o '" + (dir / (std::string("w") + threads + ".png")).string() +
                            "' --window -300,5000,128,96 > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  {
    int w1, h1, c1, w2, h2, c2;
    std::string f1, f2;  // EXR headers carry a date: compare the pixels
    EXPECT_TRUE(raw_pixels(dir / "w1.exr", w1, h1, c1, f1) == raw_pixels(dir / "w2.exr", w2, h2, c2, f2));
  }
  EXPECT_TRUE(same_file(dir / "w1.png", dir / "w2.png"));
  // Two windows side by side (64 px each) equal the two halves of the whole region.
  for (int k = 0; k < 2; ++k) {
    const auto r = run_proctex(env(dir) + common + "'" + (dir / ("h" + std::to_string(k) + ".exr")).string() +
                                   "' -o '" + (dir / ("h" + std::to_string(k) + ".png")).string() + "' --window " +
                                   std::to_string(-300 + 64 * k) + ",5000,64,96",
                               dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  int w, h, c;
  std::string f;
  const auto whole = raw_pixels(dir / "w1.exr", w, h, c, f);
  ASSERT_EQ(w, 128);
  for (int k = 0; k < 2; ++k) {
    int hw, hh, hc;
    const auto half = raw_pixels(dir / ("h" + std::to_string(k) + ".exr"), hw, hh, hc, f);
    ASSERT_EQ(hw, 64);
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 64; ++x)
        for (int ch = 0; ch < 2; ++ch)
          ASSERT_EQ(half[(static_cast<size_t>(y) * 64 + x) * hc + ch],
                    whole[(static_cast<size_t>(y) * 128 + 64 * k + x) * c + ch])
              << k << " " << x << "," << y;
  }
}

TEST(SynthCli, AppliedMapsStayAlignedAndSixteenBitPng) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  // A "height" map that is the exemplar's own red channel inverted, 8-bit.
  const Image colour = load_image(ex);
  Image height(colour.width, colour.height);
  for (size_t i = 0; i < height.pixels.size(); i += 3)
    for (int c = 0; c < 3; ++c)
      height.pixels[i + c] = srgb_to_linear(1.0f - linear_to_srgb(colour.pixels[i]));
  save_image(height, dir / "ex_height.png");
  const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "out.png").string() +
                                 "' --size 96 --apply height='" + (dir / "ex_height.png").string() + "':'" +
                                 (dir / "out_h.png").string() + "' --apply '" + ex.string() + "':'" +
                                 (dir / "out16.png").string() + "' --bits 16",
                             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int w, h, c, w2, h2, c2;
  std::string f, f2;
  const auto out = raw_pixels(dir / "out.png", w, h, c, f);
  const auto map = raw_pixels(dir / "out_h.png", w2, h2, c2, f2);
  ASSERT_EQ(w, 96);
  ASSERT_EQ(w2, 96);
  EXPECT_EQ(f2, "uint16");
  // Every output pixel's map value is 1 - its red code (to the 16-bit rounding).
  for (int i = 0; i < w * h; ++i) ASSERT_NEAR(map[i * c2], 1.0f - out[i * c], 1.0f / 255 + 1e-4f) << i;
}

TEST(SynthCli, TileableOutputRepeatsSeamlessly) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "tile.png").string() +
                                 "' --size 128 --tileable --coords '" + (dir / "tile.exr").string() + "'",
                             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The window one period to the right and down is the same picture.
  const auto shifted = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "shift.png").string() +
                                       "' --size 128 --tileable --window 128,-128,128,128",
                                   dir.path());
  ASSERT_EQ(shifted.exit_code, 0) << shifted.err;
  EXPECT_TRUE(same_file(dir / "tile.png", dir / "shift.png"));
}

// --blend-seams (default on) averages the colour across patch joins only: a plain tiling (zero
// randomness on a tiling exemplar) is one patch and stays an exact copy; blended windows side by
// side equal the halves of the whole region, byte for byte; blending changes some pixels otherwise.
TEST(SynthCli, SeamBlendingKeepsPatchesExactAndWindowsStitched) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  auto synth = [&](const std::string& out, const std::string& args) {
    const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / out).string() + "' " + args,
                               dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  };
  synth("t_on.png", "--size 96 --randomness 0 --exemplar-tiles yes --blend-seams on");
  synth("t_off.png", "--size 96 --randomness 0 --exemplar-tiles yes --blend-seams off");
  int w, h, c;
  std::string f;
  EXPECT_TRUE(raw_pixels(dir / "t_on.png", w, h, c, f) == raw_pixels(dir / "t_off.png", w, h, c, f));
  synth("on.png", "--window -300,5000,96,64 --seed 3");
  synth("off.png", "--window -300,5000,96,64 --seed 3 --blend-seams off");
  const auto whole = raw_pixels(dir / "on.png", w, h, c, f);
  ASSERT_EQ(w, 96);
  EXPECT_FALSE(whole == raw_pixels(dir / "off.png", w, h, c, f));
  for (int k = 0; k < 2; ++k) {
    synth("h" + std::to_string(k) + ".png", "--seed 3 --window " + std::to_string(-300 + 48 * k) + ",5000,48,64");
    int hw, hh, hc;
    const auto half = raw_pixels(dir / ("h" + std::to_string(k) + ".png"), hw, hh, hc, f);
    ASSERT_EQ(hw, 48);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 48 * c; ++x)
        ASSERT_EQ(half[static_cast<size_t>(y) * 48 * c + x], whole[static_cast<size_t>(y) * 96 * c + 48 * k * c + x])
            << k << " " << x << "," << y;
  }
}

// --blend-seams N ramps the colour across a join over N pixels on either side: a pixel whose
// (2N + 1)^2 window holds no join (every pair of adjacent pixels continues one exemplar patch, read
// from --coords) is an exact copy of the unblended output; with N = 3 pixels 2-3 px from a join
// change too (the old 1 px blend left them alone), with N = 1 they do not.
TEST(SynthCli, SeamBlendWidthReachesNPixelsFromAJoin) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  auto synth = [&](const std::string& out, const std::string& args) {
    const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / out).string() +
                                   "' --exemplar-tiles yes --seed 5 " + args,
                               dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  };
  const int X = 1000, Y = -700, W = 96, H = 64, M = 4;  // coordinates with a margin of M
  synth("big.png", fmt_window(X - M, Y - M, W + 2 * M, H + 2 * M) + " --blend-seams off --coords '" +
                       (dir / "uv.exr").string() + "'");
  synth("off.png", fmt_window(X, Y, W, H) + " --blend-seams off");
  synth("b1.png", fmt_window(X, Y, W, H) + " --blend-seams 1");
  synth("b3.png", fmt_window(X, Y, W, H) + " --blend-seams 3");
  int w, h, c, cw, ch, cc;
  std::string f;
  const auto uv = raw_pixels(dir / "uv.exr", cw, ch, cc, f);
  ASSERT_EQ(cw, W + 2 * M);
  const auto off = raw_pixels(dir / "off.png", w, h, c, f);
  const auto b1 = raw_pixels(dir / "b1.png", w, h, c, f);
  const auto b3 = raw_pixels(dir / "b3.png", w, h, c, f);
  ASSERT_EQ(w, W);
  auto u = [&](int x, int y, int k) { return static_cast<int>(uv[(static_cast<size_t>(y) * cw + x) * cc + k]); };
  // join(x, y): the pixel (margin coordinates) does not continue its right or lower neighbour's patch.
  auto breaks = [&](int x0, int y0, int x1, int y1) {
    return ((u(x0, y0, 0) + (x1 - x0)) % 64 != u(x1, y1, 0)) || ((u(x0, y0, 1) + (y1 - y0)) % 64 != u(x1, y1, 1));
  };
  auto near_join = [&](int x, int y, int n) {  // inner pixel (x, y): a broken pair inside its window
    for (int yy = y + M - n; yy <= y + M + n; ++yy)
      for (int xx = x + M - n; xx <= x + M + n; ++xx) {
        if (xx < x + M + n && breaks(xx, yy, xx + 1, yy)) return true;
        if (yy < y + M + n && breaks(xx, yy, xx, yy + 1)) return true;
      }
    return false;
  };
  auto same_pixel = [&](const std::vector<float>& a, int x, int y) {
    for (int k = 0; k < c; ++k)
      if (a[(static_cast<size_t>(y) * W + x) * c + k] != off[(static_cast<size_t>(y) * W + x) * c + k]) return false;
    return true;
  };
  int inside = 0, far_changed3 = 0, joins = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (breaks(x + M, y + M, x + M + 1, y + M) || breaks(x + M, y + M, x + M, y + M + 1)) ++joins;
      if (!near_join(x, y, 3)) {
        ++inside;
        ASSERT_TRUE(same_pixel(b3, x, y)) << x << "," << y;
      }
      if (!near_join(x, y, 1)) {
        ASSERT_TRUE(same_pixel(b1, x, y)) << x << "," << y;
        if (!same_pixel(b3, x, y)) ++far_changed3;
      }
    }
  EXPECT_GT(joins, 20);          // the window has joins to blend
  EXPECT_GT(inside, W * H / 10);  // and patch interiors that stay exact
  EXPECT_GT(far_changed3, joins / 4) << "the 3 px blend should reach 2-3 px from the joins";
  // A width out of range is a usage error.
  const auto bad = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "bad.png").string() +
                                   "' --size 32 --blend-seams 9",
                               dir.path());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--blend-seams"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));
}

// --png-compression only changes how the PNG is compressed (level 1 writes with the "sub" row
// filter, the others with libpng's adaptive filters): the pixels are the same at every level and
// bit depth, and the output is blended in several chunks of rows (160 rows: 5 chunks).
TEST(SynthCli, PngCompressionLevelsKeepThePixels) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  auto synth = [&](const std::string& out, const std::string& args) {
    const auto r = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / out).string() +
                                   "' --window 40,-70,120,160 " + args,
                               dir.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r;
  };
  for (const std::string bits : {"8", "16"}) {
    synth("l1.png", "--bits " + bits);
    synth("l0.png", "--bits " + bits + " --png-compression 0");
    synth("l9.png", "--bits " + bits + " --png-compression 9");
    int w, h, c;
    std::string f;
    const auto one = raw_pixels(dir / "l1.png", w, h, c, f);
    ASSERT_EQ(w, 120);
    ASSERT_EQ(h, 160);
    EXPECT_TRUE(one == raw_pixels(dir / "l0.png", w, h, c, f)) << bits;
    EXPECT_TRUE(one == raw_pixels(dir / "l9.png", w, h, c, f)) << bits;
    EXPECT_LT(std::filesystem::file_size(dir / "l1.png"), std::filesystem::file_size(dir / "l0.png")) << bits;
  }
  const auto bad = run_proctex(env(dir) + "synth '" + ex.string() + "' -o '" + (dir / "bad.png").string() +
                                   "' --size 32 --png-compression 10",
                               dir.path());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--png-compression"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));
}

TEST(SynthCli, BadInputIsOneLineAndLeavesNoFile) {
  TempDir dir;
  const auto ex = make_exemplar(dir);
  const auto tiny = make_exemplar(dir, 12, "tiny.png");
  const auto other = make_exemplar(dir, 32, "other.png");
  {
    Image huge(600, 20, 0.5f);
    save_image(huge, dir / "huge.png");
  }
  {
    Image nan_image(32, 32, 0.5f);
    nan_image.pixels[100] = std::numeric_limits<float>::quiet_NaN();
    save_image(nan_image, dir / "nan.exr");
  }
  std::ofstream(dir / "broken.png") << "not a png";
  const auto before = files_in(dir.path()).size();
  struct Case {
    std::string args, expect;
    int code;
  };
  const std::string o = " -o '" + (dir / "out.png").string() + "'";
  const std::vector<Case> cases = {
      {"synth '" + (dir / "missing.png").string() + "'" + o, "missing.png", 1},
      {"synth '" + (dir / "broken.png").string() + "'" + o, "broken.png", 1},
      {"synth '" + tiny.string() + "'" + o, "smaller than 16", 1},
      {"synth '" + (dir / "huge.png").string() + "'" + o, "larger than 512", 1},
      {"synth '" + (dir / "nan.exr").string() + "'" + o, "non-finite", 1},
      {"synth '" + ex.string() + "'" + o + " --apply '" + other.string() + "':'" + (dir / "m.png").string() + "'",
       "same size", 1},
      {"synth '" + ex.string() + "'" + o + " --window 1,2,3", "x,y,w,h", 2},
      {"synth '" + ex.string() + "'" + o + " --window 0,0,0,10", "out of range", 2},
      {"synth '" + ex.string() + "'" + o + " --randomness 1,x", "not a number", 2},
      {"synth '" + ex.string() + "'" + o + " --randomness 9", "outside", 2},
      {"synth '" + ex.string() + "'" + o + " --randomness 1,1,1,1,1,1,1,1,1,1", "levels", 2},
      {"synth '" + ex.string() + "'" + o + " --tileable --size 127", "even", 2},
      {"synth '" + ex.string() + "'" + o + " --rematch 9", "--rematch", 2},
      {"synth '" + ex.string() + "'" + o + " --rematch-candidates 9", "--rematch-candidates", 2},
      {"synth '" + ex.string() + "'" + o + " --layout-shifts 65", "--layout-shifts", 2},
      {"synth '" + ex.string() + "'" + o + " --coords '" + (dir / "uv.png").string() + "'", ".exr", 2},
      {"synth '" + ex.string() + "' -o '" + (dir / "nodir" / "out.png").string() + "'", "does not exist", 1},
      {"synth '" + ex.string() + "' -o '" + (dir / "out.bmpx").string() + "'", "unknown extension", 2},
  };
  for (const auto& c : cases) {
    const auto r = run_proctex(env(dir) + c.args, dir.path());
    EXPECT_EQ(r.exit_code, c.code) << c.args << "\n" << r.err;
    EXPECT_EQ(testing::line_count(r.err), 1) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  // No output and no temporary left behind (stdout.txt/stderr.txt are the harness's, cache/ the analysis).
  auto after = files_in(dir.path());
  std::erase_if(after, [](const std::string& f) { return f == "stdout.txt" || f == "stderr.txt"; });
  EXPECT_EQ(after.size(), before) << "left: " << ::testing::PrintToString(after);
}

}  // namespace
}  // namespace proctex
