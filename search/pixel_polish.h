#pragma once
// The pixel polish: the last step of recovering a deterministic pattern (issue 12, "every
// continuous parameter within 2% of its range"). After the magnitude polish and the align stage
// (match.h) a pattern renders within a few thousandths RGB RMS of the target, but some parameters
// can still be far off: a softness traded against a duty and a colour, or a duty complemented with
// the colours swapped and the pattern shifted by half a period. The statistics and the
// registered-pixel metric are (by design) blind to both. This step minimises the plain RGB
// difference instead (metrics/pixels.h) at a fixed registration, over every continuous
// parameter (colours included), discrete ones pinned, with BOBYQA: the difference is smooth and
// nearly quadratic there.
//
// It starts from the point as found and from its colour-swapped variants (two colour parameters
// swapped, and with a `duty` complemented as well): the swap that a shifted registration hid is
// undone, and the variant that lines up without a shift wins when it is as exact.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/image.h"
#include "shaders/renderer.h"
#include "shaders/shader.h"

namespace proctex::search {

// Points that register farther than this from the target are not polished: the pixels are only
// informative once the shape lines up (measured: the align stage's right answers end below 0.011).
inline constexpr double kPixelPolishStartRmse = 0.05;
// At the shader's own origin, after a least-squares colour fit, a start may be farther: only there
// can the parameters be the target's, and a duty off by a quarter of its range moves the pattern's
// phase (wavy stripes: RMS 0.076 at the origin, the truth one scan away). Fine stripes (43 across
// 256 px) reach this step with their duty and softness unseen: the align stage's finest renders
// are averaged by 2, which leaves a 3 px period nearly a sinusoid whatever its duty, so a start
// at duty 0.75 and softness 1 for the target's 0.42 and 0.2 registers at RMS 0.118 at the origin
// and polishes to 0.001 (at 0.1, session 21, it was left alone).
inline constexpr double kPixelPolishOriginStartRmse = 0.15;
// Both limits are also relative to the target's own contrast: a start is polished only if it is
// closer than this share of a flat image's RMS (flat_rmse). On a faint target (dark blue stripes,
// flat RMS 0.035) every wrong shader registers at the flat level, under the absolute limits, and
// their polishes (1500 renders each, ~12 s of a 36 s match) gained nothing; the right start was at
// 0.66 of it and polished to 0.0007.
inline constexpr double kPixelPolishFlatShare = 0.8;
// The RGB RMS difference between `image` and its mean colour: what a flat image of the best colour
// scores against it (per channel, averaged as metrics/pixels.h and aligned.h register_rgb do).
double flat_rmse(const Image& image);
// Renders per polished start (a 9-parameter swirl converges in about 300), and for the whole polish.
inline constexpr long kPixelPolishEvaluations = 600;
inline constexpr long kPixelPolishBudget = 1500;

// Basin hopping after the starts (pixel_polish.cpp): a polished point farther than this from the
// target, but not beyond kPixelPolishStartRmse (farther, the shape is not the target's: another
// shader, another count), is moved and polished again, each hop with this many renders, while the
// budget lasts; the random moves come from a fixed seed.
inline constexpr double kHopAboveRmse = 1e-3;
inline constexpr long kHopEvaluations = 150;
inline constexpr double kHopContinueShare = 0.9;  // a hop ending below this share of the best goes on
// A polished start this close at no shift ends the polish: nothing left to find.
inline constexpr double kExactAtOriginRmse = 2e-4;
inline constexpr uint32_t kHopSeed = 12;
// A parameter declaring `exchange=A/B` (shaders/shader.h) stopped within this share of its range
// of an end is carried to the other end (A and B exchanged: the same image) by the first hops. Only
// there: a superellipse 7 degrees from 0 was found turned 45 degrees from the target, and the
// exchange hop spent the renders its half-turn hop needed (session 21).
inline constexpr double kHopExchangeEnd = 0.02;
// A count that divides a rotation's declared period (shader.h `period=P/COUNT`: a star's points)
// is tried at every other value of its range by the first hop, the rotation at this many phases of
// the new count's period, each judged after a least-squares colour fit; the closest is polished.
inline constexpr int kHopCountPhases = 6;

struct PixelPolishResult {
  std::vector<float> packed;
  double rmse = -1.0;  // RGB RMS against the target at (dx, dy), on the overlap; < 0: nothing polished
  int dx = 0, dy = 0;  // render(x + dx, y + dy) ~ target(x, y)
  std::string start;   // "as found", "colours swapped", "colours swapped, duty complemented"
  long evaluations = 0;
};

// `target`: the target's linear RGB at the renders' side (square). `pinned`: parameters kept
// (the user's --fix); discrete parameters are always kept. Returns the best polished point over
// the starts (lowest RMS; within 1e-4 the shorter shift), or rmse < 0 when no start registered
// within kPixelPolishStartRmse. `report` gets each start's RMS before and after.
PixelPolishResult pixel_polish(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                               const std::vector<std::string>& pinned, const Image& target, Renderer& renderer,
                               long max_evaluations, nlohmann::json& report);

}  // namespace proctex::search
