// The align stage of a pattern's polish (search/align.h) as proctex match relies on it: from the
// point the magnitude polish hands over, the registered pixels bring the shape to the target's
// parameters - also when that point is the target's complement shifted by half the image (the
// superellipse that session 11's match lost to a rounded rectangle, docs/match-evaluation.md).
// Real renders through PoCL at the match's 256 px.
#include <gtest/gtest.h>

#include <cmath>

#include "search/align.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"

namespace proctex::search {
namespace {

constexpr int kResolution = 256;

std::vector<float> packed_of(const ShaderDecl& decl, const std::string& spec_text) {
  return resolve(decl, parse_spec_argument(spec_text));
}

// The align space as match.cpp builds it: colours pinned (they drop out of the registered pixels).
std::vector<std::string> colours_of(const ShaderDecl& decl) {
  std::vector<std::string> pinned;
  for (const auto& p : decl.params)
    if (p.type == ParamType::Color) pinned.push_back(p.name);
  return pinned;
}

// The starts match.cpp gives the stage: the point, and it mirrored (u -> 1 - u) in each dimension
// and each pair of dimensions.
std::vector<std::vector<double>> starts_from(const std::vector<double>& unit) {
  std::vector<std::vector<double>> starts = {unit};
  for (size_t d = 0; d < unit.size(); ++d)
    for (size_t e = d; e < unit.size(); ++e) {
      auto mirrored = unit;
      mirrored[d] = 1.0 - mirrored[d];
      if (e != d) mirrored[e] = 1.0 - mirrored[e];
      starts.push_back(mirrored);
    }
  return starts;
}

double worst_unit_error(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0;
  for (size_t d = 0; d < a.size(); ++d) worst = std::max(worst, std::fabs(a[d] - b[d]));
  return worst;
}

// The target: the point rendered at side `size` with seed 7.
Image render_at(Renderer& renderer, const ShaderDecl& decl, const std::vector<float>& packed, int size) {
  RenderSettings rs;
  rs.width = rs.height = size;
  return renderer.render_batch(decl, {packed}, {7u}, rs).front();
}

// Target 8 of the 18 deterministic benchmark targets: a soft yellow superellipse, rotated, wider
// than the image on its diagonal.
const char* kTarget = "superellipse:width=0.9254,height=0.672,exponent=8.057,rotation=42.353,softness=0.312,"
                      "fg=(0.86,0.806,0.109),bg=(0.65,0.221,0.423)";

}  // namespace

TEST(AlignRescue, FindsASuperellipseFromItsComplementAlias) {
  // What the magnitude polish and the settle handed over in session 11 (match JSON, CLI): a
  // narrower, taller shape (width 0.65 for 0.93, height 0.90 for 0.67), the target's complement
  // shifted by half the image, in which every start of the stage registers near 0 and the stages
  // alone ended at a dot of width 0.05 (registered similarity 0.008). The rescue's line scan finds
  // the basin; every parameter then comes back within 2% of its range.
  Renderer renderer;
  const ShaderDecl& decl = ShaderLibrary::builtin().get("superellipse");
  const auto truth = packed_of(decl, kTarget);
  const Image target = render_at(renderer, decl, truth, kResolution);
  const auto alias = packed_of(decl, "superellipse:width=0.6478,height=0.9042,exponent=12.83,rotation=42.98,"
                                     "softness=0.3466,fg=(0.86,0.83,0.1),bg=(0.66,0.23,0.42)");
  const ParameterSpace space(decl, alias, colours_of(decl));
  const auto stages = align_stages(target, kResolution);
  long evaluations = 0;
  nlohmann::json report;
  const auto r = align_pattern(space, starts_from(space.to_unit(alias)), stages, renderer, 7u, kResolution,
                               RefineOptions{}, evaluations, true, &report);
  EXPECT_FALSE(align_missed(stages, r.similarity)) << report.dump();
  EXPECT_LT(worst_unit_error(r.unit, space.to_unit(truth)), 0.02) << report.dump();
  ASSERT_TRUE(report.is_object());
  EXPECT_TRUE(report["kept"].get<bool>()) << report.dump();
  EXPECT_LE(evaluations, 2 * kAlignEvaluations + align_rescue_renders(space) + 64);
}

TEST(AlignRescue, ANearPointIsNotRescanned) {
  // A point the stages bring home (width and softness a few percent off) costs no more than the
  // stages: the rescue is only for a missed end point. At 128 px, as a catalogue built at 128 px
  // matches (the rescue's scan renders are then 64 px, not the first stage's 2 x 16).
  constexpr int kSmall = 128;  // the stages are the same code at any side; a quarter of the renders' cost
  Renderer renderer;
  const ShaderDecl& decl = ShaderLibrary::builtin().get("superellipse");
  const auto truth = packed_of(decl, kTarget);
  const Image target = render_at(renderer, decl, truth, kSmall);
  auto near = truth;
  near[decl.find("width")->offset] = 0.88f;
  near[decl.find("softness")->offset] = 0.33f;
  const ParameterSpace space(decl, near, colours_of(decl));
  const auto stages = align_stages(target, kSmall);
  long evaluations = 0;
  nlohmann::json report;
  const auto r = align_pattern(space, {space.to_unit(near)}, stages, renderer, 7u, kSmall, RefineOptions{},
                               evaluations, true, &report);
  EXPECT_FALSE(align_missed(stages, r.similarity));
  EXPECT_LT(worst_unit_error(r.unit, space.to_unit(truth)), 0.02);
  EXPECT_TRUE(report.is_null()) << report.dump();
  EXPECT_LE(evaluations, kAlignEvaluations + 8);
}

}  // namespace proctex::search
