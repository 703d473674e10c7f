#pragma once
// The function the search maximises: similarity between the target's features and a shader's
// render at a point of its unit parameter space. Renders go to the device in batches, repeated
// points (common on discrete parameters) are answered from a cache, and the best point seen so far
// is kept so a budget or Ctrl-C can stop the search at any time with a result.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <vector>

#include "metrics/metric.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"

namespace proctex::search {

struct Evaluation {
  std::vector<float> packed;
  double similarity = 0.0;
};

struct Budget {
  long max_evaluations = 0;  // 0 = unlimited
  double max_seconds = 0.0;  // 0 = unlimited
};

class Objective {
 public:
  Objective(const ParameterSpace& space, const metrics::Features& target, const metrics::Metric& metric,
            Renderer& renderer, uint32_t seed, int resolution = metrics::kDefaultResolution);

  // Similarities of several unit points, rendered together in one launch. Points outside [0, 1]
  // are clamped; discrete coordinates snap to whole values (ParameterSpace::to_packed).
  std::vector<double> evaluate(const std::vector<std::vector<double>>& units);
  double evaluate(const std::vector<double>& unit);

  long evaluations() const { return evaluations_; }  // renders actually made (cache hits excluded)
  const Evaluation& best() const { return best_; }
  const ParameterSpace& space() const { return space_; }
  uint32_t seed() const { return seed_; }

  // What a search changes here (the cache, the best point, the render count): saved before a
  // speculative search and restored when its result is not wanted, so that the objective is as if
  // the search had not run (same cache hits, same counts afterwards).
  struct State {
    std::map<std::vector<float>, double> cache;
    Evaluation best;
    long evaluations = 0;
  };
  State save() const { return {cache_, best_, evaluations_}; }
  void restore(State state) {
    cache_ = std::move(state.cache);
    best_ = std::move(state.best);
    evaluations_ = state.evaluations;
  }

  void set_budget(Budget budget);
  // True once the budget is spent or stop() was called (from a signal handler too).
  bool exhausted() const;
  void stop() { stopped_ = true; }

  // Called after each batch with the best so far (progress display).
  std::function<void(const Objective&)> on_progress;

 private:
  const ParameterSpace& space_;
  const metrics::Features& target_;
  const metrics::Metric& metric_;
  Renderer& renderer_;
  uint32_t seed_;
  int resolution_;
  std::map<std::vector<float>, double> cache_;
  Evaluation best_;
  long evaluations_ = 0;
  Budget budget_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::atomic<bool> stopped_{false};
};

}  // namespace proctex::search
