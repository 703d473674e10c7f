#pragma once
// Local refinement with NLopt (thesis section 4.4): from a starting point, maximise similarity in
// the bounded unit parameter space; restart from the terminal point while it still improves; try
// the ends of continuous parameters' ranges (one more pass if that helped); then polish discrete
// parameters by trying their neighbouring whole values.
#include <string>
#include <vector>

#include "search/objective.h"

namespace proctex::search {

enum class Optimizer {
  NelderMead,  // LN_NELDERMEAD: the thesis's downhill simplex
  Subplex,     // LN_SBPLX: Nelder-Mead on subspaces (default: measured better, see docs/search.md)
  Bobyqa,      // LN_BOBYQA: quadratic models, few evaluations on smooth surfaces
  Global,      // GN_CRS2_LM: controlled random search, for rugged surfaces
  Gradient,    // LD_MMA with central finite differences, for "unforgiving" shaders
};

Optimizer parse_optimizer(const std::string& name);  // UsageError on an unknown name
std::string to_string(Optimizer optimizer);
std::vector<std::string> optimizer_names();

struct RefineOptions {
  Optimizer optimizer = Optimizer::Subplex;
  double initial_step = 0.08;     // simplex size per unit dimension (at least one bin for discrete)
  double tolerance = 1e-3;        // stop when a pass improves similarity by less than this
  int max_restarts = 3;           // restarts from the terminal point
  long max_evaluations = 400;     // renders per refinement, across restarts
  int sweep_levels = 16;          // discrete parameters with at most this many values are enumerated first
  bool probe_bounds = true;       // after the passes, try each continuous parameter at its range's ends
};

struct RefineResult {
  std::vector<double> unit;
  double similarity = 0.0;
  long evaluations = 0;
  int passes = 0;
};

RefineResult refine(Objective& objective, std::vector<double> start, const RefineOptions& options = {});

// A global line search along each continuous scalar (Float) parameter in turn: `levels` evenly
// spaced values across its whole range with the others held, the best kept, for `rounds` passes
// (fewer when a pass moves nothing). Every candidate of a pass renders in one launch per
// parameter. It never returns a worse point than `start`. For what a local search cannot leave:
// a stripe pattern's waviness frequency, whose spectral sidebands only meet the target's near the
// true spacing, so the objective is flat or falling everywhere between.
RefineResult scan_coordinates(Objective& objective, std::vector<double> start, int levels, int rounds);

// Every whole value of each discrete parameter with at most `max_discrete_levels` values, each
// jointly with `levels` values across the range of each continuous scalar (the others held): a
// count whose evidence depends on another parameter. A soft 8-pointed star with inner radius 0.87
// is nearly a disc; at the inner radius 0.95 of a 4-pointed look-alike every count renders alike,
// so neither a sweep of the count nor one of the radius leaves the look-alike. Never returns a
// worse point than `start`.
RefineResult scan_discrete_pairs(Objective& objective, std::vector<double> start, int max_discrete_levels, int levels);

// For each searched float that declares `needs=G` (shaders/shader.h) with G searched too: the two
// jointly, G at `gate_levels` values above its minimum (where the other has no effect) times the
// other at `levels` values across its range, the rest held. A wave's frequency is invisible while
// the wave is off and a wave at the wrong frequency mostly scores worse than none (stripes 43 with
// a wave of 0.30 at 2.73 waves: the blurred magnitude's distance is below straight stripes' only
// within about 0.3 of the frequency), so scans of one parameter at a time miss it. Never
// returns a worse point than `start`. It needs the rest near the target: from stripes 0.9 degrees
// off the target's angle the best grid point is a slow wave (1.5 waves) that mimics the turn.
RefineResult scan_dependent_pairs(Objective& objective, std::vector<double> start, int gate_levels, int levels);
// The renders scan_dependent_pairs spends in `space` (0 when nothing declares a dependency).
long dependent_pair_renders(const ParameterSpace& space, int gate_levels, int levels);

}  // namespace proctex::search
