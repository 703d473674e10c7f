#include "search/refine.h"

#include <algorithm>
#include <cmath>

#include <nlopt.hpp>

#include "core/error.h"

namespace proctex::search {
namespace {

struct Names {
  Optimizer optimizer;
  const char* name;
};
constexpr Names kNames[] = {{Optimizer::NelderMead, "neldermead"},
                            {Optimizer::Subplex, "subplex"},
                            {Optimizer::Bobyqa, "bobyqa"},
                            {Optimizer::Global, "global"},
                            {Optimizer::Gradient, "gradient"}};

nlopt::algorithm algorithm_for(Optimizer o) {
  switch (o) {
    case Optimizer::NelderMead: return nlopt::LN_NELDERMEAD;
    case Optimizer::Subplex: return nlopt::LN_SBPLX;
    case Optimizer::Bobyqa: return nlopt::LN_BOBYQA;
    case Optimizer::Global: return nlopt::GN_CRS2_LM;
    case Optimizer::Gradient: return nlopt::LD_MMA;
  }
  return nlopt::LN_NELDERMEAD;
}

// Unit-space width of one value of a discrete dimension: steps smaller than this never leave the
// current whole value, so simplex steps and finite differences use at least one bin.
double bin_width(const Dimension& d) { return d.levels ? 1.0 / d.levels : 0.0; }

// Renders the candidates in one launch and moves `result` to the best of them when it is better
// than where it stands; returns whether it moved. The step every sweep and probe below repeats.
bool move_to_best(Objective& objective, const std::vector<std::vector<double>>& candidates, RefineResult& result) {
  if (candidates.empty()) return false;
  const auto values = objective.evaluate(candidates);
  const auto best = std::max_element(values.begin(), values.end()) - values.begin();
  if (values[best] <= result.similarity) return false;
  result.similarity = values[best];
  result.unit = candidates[best];
  return true;
}

// A scan's result before it moves: the start, snapped, and its similarity.
RefineResult scan_start(Objective& objective, const std::vector<double>& start) {
  RefineResult result;
  result.unit = objective.space().snap(start);
  result.similarity = objective.evaluate(result.unit);
  return result;
}

// A continuous parameter (what the line scans sweep): a Float without discrete levels.
bool is_continuous(const Dimension& dim) { return !dim.levels && dim.param->type == ParamType::Float; }

// The k-th of `levels` evenly spaced unit values across the whole range, both ends included.
double sweep_value(int k, int levels) { return levels > 1 ? double(k) / (levels - 1) : 0.5; }

struct Context {
  Objective* objective;
  long evaluation_cap;  // Objective::evaluations() value at which this refinement stops
  RefineResult* result;
  const std::vector<Dimension>* dims;
  double fd_step;
};

// The optimizers see log(similarity): similarities are exp(-distance / scale) and so nearly flat
// (1e-5 vs 1e-6) far from the target, while their logarithm keeps a usable slope everywhere. The
// maximiser is the same.
double log_similarity(double s) { return std::log(std::max(s, 1e-300)); }

// NLopt callback: log similarity to maximise; for the gradient method, central differences
// rendered in the same launch as the point itself.
double nlopt_objective(unsigned n, const double* x, double* grad, void* data) {
  auto& c = *static_cast<Context*>(data);
  if (c.objective->exhausted() || c.objective->evaluations() >= c.evaluation_cap) throw nlopt::forced_stop();
  std::vector<std::vector<double>> points = {std::vector<double>(x, x + n)};
  std::vector<double> steps(n, 0.0);
  if (grad) {
    for (unsigned i = 0; i < n; ++i) {
      steps[i] = std::max(c.fd_step, bin_width((*c.dims)[i]));
      for (double sign : {1.0, -1.0}) {
        auto p = points.front();
        p[i] = std::clamp(p[i] + sign * steps[i], 0.0, 1.0);
        points.push_back(p);
      }
    }
  }
  const auto values = c.objective->evaluate(points);
  if (grad)
    for (unsigned i = 0; i < n; ++i) {
      const double span = std::clamp(x[i] + steps[i], 0.0, 1.0) - std::clamp(x[i] - steps[i], 0.0, 1.0);
      grad[i] = span > 0 ? (log_similarity(values[1 + 2 * i]) - log_similarity(values[2 + 2 * i])) / span : 0.0;
    }
  if (values.front() > c.result->similarity) {
    c.result->similarity = values.front();
    c.result->unit = points.front();
  }
  return log_similarity(values.front());
}

// One NLopt run from `x`; returns when it converges, hits its evaluation cap or the budget ends.
void run_pass(Objective& objective, const RefineOptions& options, long max_evals, RefineResult& result) {
  const auto& dims = objective.space().dims();
  const unsigned n = static_cast<unsigned>(dims.size());
  nlopt::opt opt(algorithm_for(options.optimizer), n);
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  std::vector<double> steps(n);
  for (unsigned i = 0; i < n; ++i) steps[i] = std::max(options.initial_step, 1.01 * bin_width(dims[i]));
  if (options.optimizer != Optimizer::Global) opt.set_initial_step(steps);
  if (options.optimizer == Optimizer::Global) opt.set_population(std::max(10u, 10 * (n + 1)));
  opt.set_ftol_abs(options.tolerance * 0.1);  // on log similarity: a relative change of S
  opt.set_xtol_abs(1e-4);
  opt.set_maxeval(static_cast<int>(std::max<long>(1, max_evals)));
  Context context{&objective, objective.evaluations() + max_evals, &result, &dims, 0.02};
  opt.set_max_objective(nlopt_objective, &context);
  std::vector<double> x = result.unit;
  double f = 0.0;
  try {
    opt.optimize(x, f);
  } catch (const nlopt::forced_stop&) {
  } catch (const nlopt::roundoff_limited&) {
  } catch (const std::invalid_argument& e) {
    throw Error(std::string("optimizer rejected the problem: ") + e.what(), "try --optimizer neldermead");
  }
}

// Tries the neighbouring whole values of every discrete parameter (all in one launch) and keeps
// the best, until none improves: the simplex can stall on the plateaus of a discrete dimension.
void polish_discrete(Objective& objective, RefineResult& result) {
  const auto& dims = objective.space().dims();
  for (int round = 0; round < 8 && !objective.exhausted(); ++round) {
    std::vector<std::vector<double>> candidates;
    for (size_t i = 0; i < dims.size(); ++i) {
      if (!dims[i].levels) continue;
      for (double sign : {-1.0, 1.0}) {
        auto p = objective.space().snap(result.unit);
        p[i] += sign * bin_width(dims[i]);
        if (p[i] < 0.0 || p[i] > 1.0) continue;
        candidates.push_back(p);
      }
    }
    if (!move_to_best(objective, candidates, result)) return;
  }
}

// Evaluates every value of each discrete parameter with at most `max_levels` values (the others
// held), all in one launch, and moves to the best: a count like a star's points is cheaper to
// enumerate than to search, and the simplex cannot see across its plateaus.
void sweep_discrete(Objective& objective, RefineResult& result, int max_levels) {
  const auto& dims = objective.space().dims();
  for (size_t i = 0; i < dims.size() && !objective.exhausted(); ++i) {
    if (!dims[i].levels || dims[i].levels > max_levels) continue;
    std::vector<std::vector<double>> candidates;
    for (int k = 0; k < dims[i].levels; ++k) {
      auto p = result.unit;
      p[i] = (k + 0.5) / dims[i].levels;
      candidates.push_back(p);
    }
    move_to_best(objective, candidates, result);
  }
}

// Tries each continuous scalar parameter at both ends of its range (all in one launch) and moves
// to the best while that improves, at most 3 times. Shaders' "amount" parameters (wear, roughness,
// variation) are often exactly off in a target, and the simplex reaches a bound only slowly; a
// worn-edge local optimum with narrow mortar held a clean bricks target at S 0.55. Returns
// whether it moved. Costs 2 renders per such parameter per round.
bool probe_bounds(Objective& objective, RefineResult& result, long max_renders) {
  const auto& dims = objective.space().dims();
  bool moved = false;
  for (int round = 0; round < 3 && !objective.exhausted(); ++round) {
    std::vector<std::vector<double>> candidates;
    for (size_t i = 0; i < dims.size(); ++i) {
      if (dims[i].levels || dims[i].param->type != ParamType::Float) continue;
      for (double end : {0.0, 1.0}) {
        if (std::fabs(result.unit[i] - end) < 0.02) continue;
        auto p = result.unit;
        p[i] = end;
        candidates.push_back(p);
      }
    }
    if (candidates.empty() || static_cast<long>(candidates.size()) > max_renders) break;
    max_renders -= static_cast<long>(candidates.size());
    if (!move_to_best(objective, candidates, result)) break;
    moved = true;
  }
  return moved;
}

}  // namespace

Optimizer parse_optimizer(const std::string& name) {
  for (const auto& n : kNames)
    if (name == n.name) return n.optimizer;
  std::string known;
  for (const auto& n : kNames) known += (known.empty() ? "" : ", ") + std::string(n.name);
  throw UsageError("unknown optimizer '" + name + "'", "choose one of: " + known);
}

std::string to_string(Optimizer optimizer) {
  for (const auto& n : kNames)
    if (n.optimizer == optimizer) return n.name;
  return "?";
}

std::vector<std::string> optimizer_names() {
  std::vector<std::string> out;
  for (const auto& n : kNames) out.emplace_back(n.name);
  return out;
}

RefineResult refine(Objective& objective, std::vector<double> start, const RefineOptions& options) {
  RefineResult result;
  const long first_evaluation = objective.evaluations();
  result.unit = objective.space().snap(start);
  if (objective.space().dimensions() == 0) {
    result.similarity = objective.evaluate(result.unit);
    return result;
  }
  result.similarity = objective.evaluate(result.unit);
  sweep_discrete(objective, result, options.sweep_levels);
  // Renders kept back from the passes for one round of probe_bounds when the budget allows it.
  long probe_renders = 0;
  for (const auto& d : objective.space().dims()) probe_renders += !d.levels && d.param->type == ParamType::Float ? 2 : 0;
  if (!options.probe_bounds || options.max_evaluations < 4 * probe_renders) probe_renders = 0;
  const long pass_budget = options.max_evaluations - probe_renders;
  for (int pass = 0; pass <= options.max_restarts && !objective.exhausted(); ++pass) {
    const double before = result.similarity;
    const long used = objective.evaluations() - first_evaluation;
    if (used >= pass_budget) break;
    run_pass(objective, options, pass_budget - used, result);
    ++result.passes;
    // Restart from the terminal point only while a pass still gains (thesis 4.4).
    if (result.similarity - before < options.tolerance) break;
  }
  // Then the ends of the "amount" parameters, and one more pass from there if one helped.
  const long left = options.max_evaluations - (objective.evaluations() - first_evaluation);
  if (probe_renders > 0 && probe_bounds(objective, result, left)) {
    const long used = objective.evaluations() - first_evaluation;
    if (used < options.max_evaluations && !objective.exhausted()) {
      run_pass(objective, options, options.max_evaluations - used, result);
      ++result.passes;
    }
  }
  polish_discrete(objective, result);
  result.evaluations = objective.evaluations() - first_evaluation;
  return result;
}

RefineResult scan_coordinates(Objective& objective, std::vector<double> start, int levels, int rounds) {
  const auto& dims = objective.space().dims();
  const long first_evaluation = objective.evaluations();
  RefineResult result = scan_start(objective, start);
  for (int round = 0; round < rounds && !objective.exhausted(); ++round) {
    bool moved = false;
    for (size_t i = 0; i < dims.size() && !objective.exhausted(); ++i) {
      if (!is_continuous(dims[i])) continue;
      std::vector<std::vector<double>> candidates;
      for (int k = 0; k < levels; ++k) {
        auto p = result.unit;
        p[i] = sweep_value(k, levels);
        candidates.push_back(p);
      }
      moved = move_to_best(objective, candidates, result) || moved;
    }
    ++result.passes;
    if (!moved) break;
  }
  result.evaluations = objective.evaluations() - first_evaluation;
  return result;
}

RefineResult scan_discrete_pairs(Objective& objective, std::vector<double> start, int max_discrete_levels, int levels) {
  const auto& dims = objective.space().dims();
  const long first_evaluation = objective.evaluations();
  RefineResult result = scan_start(objective, start);
  const auto from = result.unit;  // every pair varies the start's point, not a moving one
  for (size_t i = 0; i < dims.size() && !objective.exhausted(); ++i) {
    if (!dims[i].levels || dims[i].levels > max_discrete_levels) continue;
    for (size_t j = 0; j < dims.size() && !objective.exhausted(); ++j) {
      if (!is_continuous(dims[j])) continue;
      std::vector<std::vector<double>> candidates;
      for (int a = 0; a < dims[i].levels; ++a)
        for (int b = 0; b < levels; ++b) {
          auto p = from;
          p[i] = (a + 0.5) / dims[i].levels;
          p[j] = sweep_value(b, levels);
          candidates.push_back(p);
        }
      move_to_best(objective, candidates, result);
    }
  }
  result.evaluations = objective.evaluations() - first_evaluation;
  return result;
}

namespace {

// (gate, dependent) dimension indices of the searched floats declaring `needs=` a searched gate.
std::vector<std::pair<size_t, size_t>> dependent_pairs(const ParameterSpace& space) {
  const auto& dims = space.dims();
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t j = 0; j < dims.size(); ++j) {
    if (!is_continuous(dims[j]) || dims[j].param->needs.empty()) continue;
    for (size_t i = 0; i < dims.size(); ++i)
      if (is_continuous(dims[i]) && dims[i].param->name == dims[j].param->needs) pairs.push_back({i, j});
  }
  return pairs;
}

}  // namespace

long dependent_pair_renders(const ParameterSpace& space, int gate_levels, int levels) {
  return long(dependent_pairs(space).size()) * gate_levels * levels;
}

RefineResult scan_dependent_pairs(Objective& objective, std::vector<double> start, int gate_levels, int levels) {
  const long first_evaluation = objective.evaluations();
  RefineResult result = scan_start(objective, start);
  for (const auto& [gate, dependent] : dependent_pairs(objective.space())) {
    if (objective.exhausted()) break;
    const auto from = result.unit;
    std::vector<std::vector<double>> candidates;
    for (int a = 1; a <= gate_levels; ++a)
      for (int b = 0; b < levels; ++b) {
        auto p = from;
        p[gate] = double(a) / gate_levels;
        p[dependent] = sweep_value(b, levels);
        candidates.push_back(p);
      }
    move_to_best(objective, candidates, result);
  }
  result.evaluations = objective.evaluations() - first_evaluation;
  return result;
}

}  // namespace proctex::search
