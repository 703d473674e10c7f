// Multiscale exemplar graphs (Han 2011): the graph's admissible sets and schedule on Han's fig. 4.2
// graph, bad graph files, and the synthesis on a graph on the real OpenCL device: one exemplar
// behaves like plain synthesis, windows are exact, a self edge zooms without end at bounded cost,
// and the colour-offset correction keeps the coarse exemplar's colour on a finer, recoloured one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "core/error.h"
#include "image/image.h"
#include "synth/analysis.h"
#include "synth/graph.h"
#include "synth/graph_synthesis.h"
#include "synth/synthesis.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex::synth {
namespace {

using testing::TempDir;

// Han's fig. 4.2: edges (0, 1, 2), (0, 2, 3), (2, 2, 1).
const char* kFig42 = R"({"exemplars": ["e0.png", "e1.png", "e2.png"],
  "edges": [{"from": 0, "to": 1, "scale": 4}, {"from": 0, "to": 2, "r": 3}, {"from": 2, "to": 2, "scale": 2}]})";

std::vector<StackLevel> set(std::initializer_list<StackLevel> l) {
  std::set<StackLevel> s(l);
  return {s.begin(), s.end()};
}

TEST(SynthGraph, AdmissibleSetsOfHansFigure42) {
  const ExemplarGraph g = parse_graph_text(kFig42, "/x", "fig42.json");
  const int L = 7;  // 128^2 exemplars as in the thesis
  // Han §5.2.1.2: A(E^0_5) = {E^0_5, E^1_3, E^2_2}; E^2_1 is not admissible (no link (0, 2, 4)).
  EXPECT_EQ(admissible(g, L, {0, 5}), set({{0, 5}, {1, 3}, {2, 2}}));
  // The finest level is never admissible: E^0_7 must move on to E^1 or E^2.
  EXPECT_EQ(admissible(g, L, {0, 7}), set({{1, 5}, {2, 4}}));
  // The self loop: E^2_5 is admissible for E^2_6.
  EXPECT_EQ(admissible(g, L, {2, 6}), set({{2, 5}, {2, 6}}));
  EXPECT_EQ(admissible(g, L, {2, 7}), set({{2, 6}}));
  // No edge leaves E^1: nothing at its finest level (unless the finest level is allowed, the output).
  EXPECT_TRUE(admissible(g, L, {1, 7}).empty());
  EXPECT_EQ(admissible(g, L, {1, 7}, true), set({{1, 7}}));
  EXPECT_EQ(admissible(g, L, {0, 1}), set({{0, 1}}));
  // The superexemplar (fig. 5.1c): stack levels at red depth t.
  EXPECT_EQ(superexemplar_level(g, L, 1), set({{0, 1}}));
  EXPECT_EQ(superexemplar_level(g, L, 2), set({{0, 2}, {1, 0}}));
  EXPECT_EQ(superexemplar_level(g, L, 3), set({{0, 3}, {1, 1}, {2, 0}}));
  EXPECT_EQ(superexemplar_level(g, L, 5), set({{0, 5}, {1, 3}, {2, 0}, {2, 1}, {2, 2}}));
  // Below the root's resolution only E^1 and E^2 remain; E^0 can never reach depth 8.
  for (const auto& s : superexemplar_level(g, L, 8)) EXPECT_NE(s.exemplar, 0);
}

TEST(SynthGraph, ZoomDepthAndLevelSchedule) {
  const int L = 7;
  const ExemplarGraph g = parse_graph_text(kFig42, "/x", "fig42.json");
  EXPECT_EQ(max_zoom(g, L), -1) << "the self edge on E^2 zooms without end";
  const ExemplarGraph no_loop = parse_graph_text(
      R"({"exemplars": ["a", "b", "c"], "edges": [{"from": 0, "to": 1, "scale": 4}, {"from": 0, "to": 2, "scale": 8}]})",
      "/x", "g");
  EXPECT_EQ(max_zoom(no_loop, L), 3);
  const ExemplarGraph single = parse_graph_text(R"({"exemplars": ["a"]})", "/x", "g");
  EXPECT_EQ(max_zoom(single, L), 0);
  EXPECT_THROW(level_schedule(single, L, 1), UsageError);
  // At zoom 10 only E^2 has detail that fine: from level L on, E^1 is never valid (its pixels would
  // be stranded at E^1_7), and at the output every pixel is in E^2.
  const LevelSchedule s = level_schedule(g, L, 10);
  ASSERT_EQ(s.depth, L + 10);
  for (int t = L; t <= s.depth; ++t)
    for (size_t n = 0; n < s.valid[t].size(); ++n)
      if (s.valid[t][n]) EXPECT_EQ(static_cast<int>(n) / (L + 1), 2) << "t " << t << " node " << n;
  // At zoom 0 the root is valid at every level and its finest level at the output.
  const LevelSchedule z0 = level_schedule(g, L, 0);
  for (int t = 1; t <= L; ++t) EXPECT_TRUE(z0.valid[t][t]) << t;
}

TEST(SynthGraph, BadGraphFilesAreRejectedWithTheReason) {
  struct Case {
    std::string json, expect;
  };
  const std::vector<Case> cases = {
      {"{\"exemplars\": [\"a.png\"", "not valid JSON"},
      {"[1, 2]", "top level"},
      {R"({"exemplars": []})", "non-empty"},
      {R"({"exemplars": ["a.png"], "edgez": []})", "unknown key 'edgez'"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": 0, "to": 2, "scale": 2}]})", "\"to\" is 2"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": -1, "to": 1, "scale": 2}]})", "\"from\" is -1"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": 0, "to": 1, "scale": 3}]})", "not a power of two"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": 0, "to": 1, "scale": 0}]})", "not a power of two"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": 0, "to": 1}]})", "one of \"scale\""},
      {R"({"exemplars": ["a.png"], "edges": [{"from": 0, "to": 0, "scale": 1}]})", "implicit self edge"},
      {R"({"exemplars": ["a.png", "b.png"], "edges": [{"from": 0, "to": 1, "scale": 2}, {"from": 0, "to": 1, "r": 1}]})",
       "twice"},
      {R"({"exemplars": ["a.png", "b.png", "c.png"], "edges": [{"from": 0, "to": 1, "scale": 1},
          {"from": 1, "to": 2, "scale": 1}, {"from": 2, "to": 1, "scale": 1}]})",
       "loop 1 -> 2 -> 1"},
  };
  for (const auto& c : cases) {
    try {
      parse_graph_text(c.json, "/x", "g.json");
      ADD_FAILURE() << "accepted: " << c.json;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << c.json << "\n -> " << e.what();
      EXPECT_NE(std::string(e.what()).find("g.json"), std::string::npos) << e.what();
    }
  }
  // A loop that changes scale is allowed (infinite zoom through two exemplars).
  EXPECT_NO_THROW(parse_graph_text(
      R"({"exemplars": ["a", "b"], "edges": [{"from": 0, "to": 1, "scale": 2}, {"from": 1, "to": 0, "scale": 2}]})",
      "/x", "g"));
  // Checks that need the exemplar size: scale at most 2^(L-2); every exemplar reachable.
  const auto big = parse_graph_text(R"({"exemplars": ["a", "b"], "edges": [{"from": 0, "to": 1, "scale": 32}]})", "/x", "g");
  EXPECT_THROW(validate_graph(big, 6), Error);
  EXPECT_NO_THROW(validate_graph(big, 7));
  const auto orphan = parse_graph_text(R"({"exemplars": ["a", "b", "c"], "edges": [{"from": 0, "to": 1, "scale": 2}]})", "/x", "g");
  EXPECT_THROW(validate_graph(orphan, 6), Error);
}

// --- synthesis on the device ---

Image gravel(int size, int x0 = 0, int y0 = 0) {
  static const Image full = load_image(std::filesystem::path(PROCTEX_SHARED_DIR) / "textures" / "gravel.png");
  return resize(crop(full, x0, y0, 256, 256), size, size);
}

// A toroidal exemplar with unique 5x5 neighbourhoods (as in synthesis_test.cpp).
Image periodic_exemplar(int m) {
  Image im(m, m);
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < m; ++x) {
      uint32_t h = static_cast<uint32_t>(x * 73856093u) ^ static_cast<uint32_t>(y * 19349663u);
      h ^= h >> 13;
      h *= 0x5bd1e995u;
      h ^= h >> 15;
      const float noise = (h & 1023) / 1023.0f;
      const float wave = 0.5f + 0.25f * std::sin(2 * M_PI * 3 * x / m) * std::cos(2 * M_PI * 2 * y / m);
      float* p = im.pixel(x, y);
      p[0] = 0.7f * wave + 0.3f * noise;
      p[1] = 0.5f * wave + 0.2f * noise;
      p[2] = 0.3f + 0.4f * noise;
    }
  return im;
}

struct Fixture {
  TempDir dir;
  LoadedGraph graph;
  GraphAnalysis analysis;
  std::unique_ptr<GraphSynthesizer> synth;
  Fixture(const std::vector<Image>& images, const std::string& edges, const std::string& tiles = "auto") {
    std::string list;
    for (size_t i = 0; i < images.size(); ++i) {
      const auto name = "e" + std::to_string(i) + ".exr";
      save_image(images[i], dir / name);
      list += (i ? ", " : "") + std::string("{\"image\": \"") + name + "\", \"tiles\": \"" + tiles + "\"}";
    }
    std::ofstream(dir / "g.json") << "{\"exemplars\": [" << list << "], \"edges\": [" << edges << "]}";
    graph = load_graph(dir / "g.json");
    analysis = analyse_graph(graph);
    synth = std::make_unique<GraphSynthesizer>(graph, analysis);
  }
};

// Fraction of horizontally adjacent pixels that continue one patch.
double coherence_of(const std::vector<int32_t>& xy, int w, int h, int m) {
  int same = 0, total = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      same += xy[2 * (i + 1)] == (xy[2 * i] + 1) % m && xy[2 * (i + 1) + 1] == xy[2 * i + 1];
      ++total;
    }
  return double(same) / total;
}

std::vector<int32_t> coords_of(const std::vector<GraphPixel>& px) {
  std::vector<int32_t> out;
  for (const auto& p : px) out.push_back(p.x), out.push_back(p.y);
  return out;
}

TEST(SynthGraph, OneExemplarGraphWithZeroRandomnessIsTheSameTilingAsPlainSynthesis) {
  Fixture f({periodic_exemplar(64)}, "", "yes");
  SynthOptions o;
  o.randomness = {0.0f};
  const Window w{-37, 1000003, 150, 90};
  const auto px = f.synth->synthesise(w, o, 0);
  Exemplar ex;
  ex.colour = load_image(f.dir / "e0.exr");
  AnalysisOptions ao;
  ao.tiling = Tiling::Toroidal;
  const Analysis plain_analysis = analyse(ex, ao);
  Synthesizer plain(plain_analysis);
  const auto S = plain.synthesise(w, o);
  ASSERT_EQ(S, coords_of(px));
  // ... which is the exact tiling S[p] = p + c mod 64, at the finest level, with no colour offset.
  const int cx = ((S[0] - static_cast<int>(w.x % 64)) % 64 + 64) % 64;
  for (int x = 0; x < w.width; ++x) EXPECT_EQ(S[2 * x], ((w.x + x + cx) % 64 + 64) % 64);
  for (const auto& p : px) {
    ASSERT_EQ(p.level, 6);
    ASSERT_EQ(p.exemplar, 0);
    ASSERT_EQ(p.r | p.g | p.b, 0);
  }
}

TEST(SynthGraph, OneExemplarGraphLooksLikePlainSynthesis) {
  Fixture f({gravel(64)}, "");
  const Window w{0, 0, 160, 160};
  const auto px = f.synth->synthesise(w, {}, 0);
  Exemplar ex;
  ex.colour = load_image(f.dir / "e0.exr");
  const Analysis pa = analyse(ex);
  Synthesizer plain(pa);
  const auto S = plain.synthesise(w, {});
  const double cg = coherence_of(coords_of(px), w.width, w.height, 64);
  const double cp = coherence_of(S, w.width, w.height, 64);
  EXPECT_NEAR(cg, cp, 0.15) << "patch continuity: graph " << cg << " plain " << cp;
  EXPECT_LT(cg, 0.97);
  EXPECT_GT(cg, 0.35);
  // Same colour statistics (sRGB mean and spread of the output).
  const auto col = f.synth->colours(px);
  double mg = 0, mp = 0, vg = 0, vp = 0;
  for (size_t i = 0; i < px.size(); ++i) {
    const float g = col[3 * i];
    const float p = linear_to_srgb(ex.colour.pixel(S[2 * i], S[2 * i + 1])[0]);
    mg += g, mp += p, vg += g * g, vp += p * p;
  }
  const double n = double(px.size());
  mg /= n, mp /= n;
  EXPECT_NEAR(mg, mp, 0.03);
  EXPECT_NEAR(std::sqrt(vg / n - mg * mg), std::sqrt(vp / n - mp * mp), 0.03);
  // Every exemplar region is used.
  std::set<int> blocks;
  for (const auto& p : px) blocks.insert(p.x / 8 + 8 * (p.y / 8));
  EXPECT_GE(blocks.size(), 56u);
}

bool same(const GraphPixel& a, const GraphPixel& b) {
  return a.x == b.x && a.y == b.y && a.exemplar == b.exemplar && a.level == b.level && a.r == b.r && a.g == b.g &&
         a.b == b.b;
}

TEST(SynthGraph, WindowsAreExactRegionsOfALargerSynthesisAndDeepZoomHasNoEnd) {
  // Han's fig. 4.2 graph on 64^2 exemplars (L = 6): three gravel crops, E^2 zooms into itself.
  Fixture f({gravel(64, 0, 0), gravel(64, 256, 0), gravel(64, 0, 256)},
            R"({"from": 0, "to": 1, "scale": 4}, {"from": 0, "to": 2, "scale": 8}, {"from": 2, "to": 2, "scale": 2})");
  SynthOptions o;
  o.randomness = {1, 1, 0.5, 0.3};
  for (const int zoom : {0, 2, 30}) {
    const int64_t x0 = zoom == 30 ? (int64_t(1) << 45) + 7 : -1000;
    const Window big{x0, 12345, 70, 40};
    const auto all = f.synth->synthesise(big, o, zoom);
    // Pieces: the left part, a column, a single pixel, and a window overlapping the right border.
    const std::vector<Window> parts = {{x0, 12345, 33, 40}, {x0 + 33, 12345, 1, 40}, {x0 + 50, 12360, 1, 1},
                                       {x0 + 60, 12350, 10, 30}};
    for (const auto& pw : parts) {
      const auto part = f.synth->synthesise(pw, o, zoom);
      for (int y = 0; y < pw.height; ++y)
        for (int x = 0; x < pw.width; ++x) {
          const auto& a = part[static_cast<size_t>(y) * pw.width + x];
          const auto& b = all[static_cast<size_t>(pw.y - big.y + y) * big.width + (pw.x - big.x + x)];
          ASSERT_TRUE(same(a, b)) << "zoom " << zoom << " at " << pw.x + x << "," << pw.y + y;
        }
    }
    std::set<int> exemplars, texels;
    for (const auto& p : all) exemplars.insert(p.exemplar), texels.insert(p.exemplar * 4096 + p.y * 64 + p.x);
    if (zoom == 0) EXPECT_TRUE(exemplars.count(0)) << "the root shows at its own scale";
    if (zoom >= 3) EXPECT_EQ(exemplars, std::set<int>{2}) << "only E^2 has detail below E^1's finest scale";
    EXPECT_GT(texels.size(), 400u) << "zoom " << zoom << ": the output is texture, not a few texels";
  }
  // Bounded cost: a deep zoom window costs about as much as a shallow one (the extra levels are
  // tiny padded regions). Process CPU time, robust to other load on the machine.
  const Window w{(int64_t(1) << 50) - 3, -(int64_t(1) << 49), 64, 64};
  auto cpu = [&](int zoom) {
    const std::clock_t c0 = std::clock();
    f.synth->synthesise(w, o, zoom);
    return double(std::clock() - c0) / CLOCKS_PER_SEC;
  };
  cpu(4);  // warm up (kernel build, first allocations)
  const double shallow = cpu(4), deep = cpu(44);
  EXPECT_LT(deep, 8 * shallow + 0.5) << "zoom 4: " << shallow << " s, zoom 44: " << deep << " s";
}

TEST(SynthGraph, ColourOffsetKeepsTheCoarseExemplarsColourOnAFinerRecolouredOne) {
  // The root is a gravel photo; the finer exemplar is another part of it, tinted (red up, blue down).
  // Zoomed in by 2 (E^1 is 2x finer and has no edge: the deepest zoom), every pixel must come from the finer exemplar, but the coarse levels are the prior:
  // the colour offsets (upsampled from the four parents) bring the output back to the root's colours.
  const Image root = gravel(64, 0, 0);
  Image tinted = gravel(64, 200, 200);
  for (size_t i = 0; i < tinted.pixels.size(); i += 3) {
    tinted.pixels[i] = srgb_to_linear(std::min(1.0f, linear_to_srgb(tinted.pixels[i]) + 0.25f));
    tinted.pixels[i + 2] = srgb_to_linear(std::max(0.0f, linear_to_srgb(tinted.pixels[i + 2]) - 0.2f));
  }
  Fixture f({root, tinted}, R"({"from": 0, "to": 1, "scale": 2})");
  const Window w{-300, 500, 128, 128};
  const auto px = f.synth->synthesise(w, {}, 1);  // below the root's finest scale: E^1 only
  const auto col = f.synth->colours(px);
  double mean[3] = {0, 0, 0}, root_mean[3] = {0, 0, 0}, tint_mean[3] = {0, 0, 0};
  for (const auto& p : px) ASSERT_EQ(p.exemplar, 1);
  for (size_t i = 0; i < px.size(); ++i)
    for (int c = 0; c < 3; ++c) mean[c] += col[3 * i + c] / px.size();
  const size_t n = 64 * 64;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      root_mean[c] += linear_to_srgb(root.pixels[3 * i + c]) / n;
      tint_mean[c] += linear_to_srgb(tinted.pixels[3 * i + c]) / n;
    }
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(mean[c], root_mean[c], 0.04) << "channel " << c << " tinted mean " << tint_mean[c];
  }
  EXPECT_GT(std::abs(tint_mean[0] - root_mean[0]), 0.15);
}

// --- the command line ---

std::vector<std::string> files_in(const std::filesystem::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && e.path().filename() != "stdout.txt" && e.path().filename() != "stderr.txt")
      out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SynthGraphCli, WritesTheOutputCoordsAndJson) {
  TempDir dir;
  setenv("PROCTEX_CACHE_DIR", (dir / "cache").c_str(), 1);  // the analysis cache of the child process
  save_image(gravel(64, 0, 0), dir / "a.png");
  save_image(gravel(64, 256, 256), dir / "b.png");
  std::ofstream(dir / "g.json") << R"({"exemplars": ["a.png", "b.png"],
      "edges": [{"from": 0, "to": 1, "scale": 4}, {"from": 1, "to": 1, "scale": 2}]})";
  const auto r = testing::run_proctex("synth --graph '" + (dir / "g.json").string() + "' -o '" +
                                          (dir / "out.png").string() + "' --size 96x64 --zoom 5 --json --coords '" +
                                          (dir / "uv.exr").string() + "'",
                                      dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"max_zoom\": \"unbounded\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"zoom\": 5"), std::string::npos) << r.out;
  const Image out = load_image(dir / "out.png");
  EXPECT_EQ(out.width, 96);
  EXPECT_EQ(out.height, 64);
  const Image uv = load_image(dir / "uv.exr");
  for (size_t i = 0; i < uv.pixels.size(); i += 3) {
    ASSERT_EQ(uv.pixels[i + 2], 1.0f) << "zoom 5 is below the root's detail: exemplar 1 everywhere";
    ASSERT_GE(uv.pixels[i], 0.0f);
    ASSERT_LT(uv.pixels[i], 64.0f);
  }
  // The same command again, with one device thread instead of the default pool, gives the same bytes.
  const std::string again = "env POCL_MAX_PTHREAD_COUNT=1 '" + std::string(PROCTEX_BINARY) + "' -q synth --graph '" +
                            (dir / "g.json").string() + "' -o '" + (dir / "out2.png").string() +
                            "' --size 96x64 --zoom 5";
  ASSERT_EQ(std::system(again.c_str()), 0) << again;
  EXPECT_EQ(testing::read_text(dir / "out.png"), testing::read_text(dir / "out2.png"));
}

TEST(SynthGraphCli, BadGraphsAreOneLineAndLeaveNoFile) {
  TempDir dir;
  setenv("PROCTEX_CACHE_DIR", (dir / "cache").c_str(), 1);
  save_image(gravel(64), dir / "a.png");
  save_image(gravel(32), dir / "small.png");
  auto graph = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  struct Case {
    std::string file, expect;
    std::string extra;
  };
  const std::vector<Case> cases = {
      {graph("nonjson.json", "exemplars: a.png"), "not valid JSON"},
      {graph("missing.json", R"({"exemplars": ["a.png", "nothere.png"], "edges": [{"from": 0, "to": 1, "scale": 2}]})"),
       "nothere.png"},
      {graph("index.json", R"({"exemplars": ["a.png"], "edges": [{"from": 0, "to": 3, "scale": 2}]})"), "\"to\" is 3"},
      {graph("pow2.json", R"({"exemplars": ["a.png", "a.png"], "edges": [{"from": 0, "to": 1, "scale": 6}]})"),
       "not a power of two"},
      {graph("loop.json", R"({"exemplars": ["a.png", "a.png"], "edges": [{"from": 0, "to": 1, "scale": 1},
          {"from": 1, "to": 0, "scale": 1}]})"),
       "loop"},
      {graph("size.json", R"({"exemplars": ["a.png", "small.png"], "edges": [{"from": 0, "to": 1, "scale": 2}]})"),
       "same size"},
      {graph("far.json", R"({"exemplars": ["a.png", "a.png"], "edges": [{"from": 0, "to": 1, "scale": 64}]})"),
       "at most 16"},
      {graph("orphan.json", R"({"exemplars": ["a.png", "a.png"]})"), "not reachable"},
      {graph("deep.json", R"({"exemplars": ["a.png", "a.png"], "edges": [{"from": 0, "to": 1, "scale": 2}]})"),
       "deepest zoom is 1", " --zoom 2"},
      {(dir / "nofile.json").string(), "cannot read graph"},
  };
  const auto before = files_in(dir.path());
  for (const auto& c : cases) {
    const auto r = testing::run_proctex(
        "synth --graph '" + c.file + "' -o '" + (dir / "out.png").string() + "' --size 32" + c.extra, dir.path());
    EXPECT_NE(r.exit_code, 0) << c.file;
    EXPECT_EQ(testing::line_count(r.err), 1) << c.file << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.file << "\n" << r.err;
  }
  const auto r = testing::run_proctex("synth '" + (dir / "a.png").string() + "' --graph '" + cases[2].file + "' -o '" +
                                          (dir / "out.png").string() + "'",
                                      dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(files_in(dir.path()), before) << "no output or temporary left behind";
}

}  // namespace
}  // namespace proctex::synth
