#include "search/objective.h"

namespace proctex::search {

Objective::Objective(const ParameterSpace& space, const metrics::Features& target, const metrics::Metric& metric,
                     Renderer& renderer, uint32_t seed, int resolution)
    : space_(space), target_(target), metric_(metric), renderer_(renderer), seed_(seed), resolution_(resolution) {
  metric_.check(target_);
}

void Objective::set_budget(Budget budget) {
  budget_ = budget;
  start_ = std::chrono::steady_clock::now();
}

bool Objective::exhausted() const {
  if (stopped_) return true;
  if (budget_.max_evaluations > 0 && evaluations_ >= budget_.max_evaluations) return true;
  if (budget_.max_seconds > 0 &&
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() >= budget_.max_seconds)
    return true;
  return false;
}

std::vector<double> Objective::evaluate(const std::vector<std::vector<double>>& units) {
  std::vector<double> out(units.size(), 0.0);
  std::vector<std::vector<float>> todo;
  std::vector<size_t> todo_index;
  std::vector<std::vector<float>> packed(units.size());
  for (size_t i = 0; i < units.size(); ++i) {
    packed[i] = space_.to_packed(units[i]);
    if (auto it = cache_.find(packed[i]); it != cache_.end()) {
      out[i] = it->second;
    } else {
      todo_index.push_back(i);
      todo.push_back(packed[i]);
    }
  }
  if (!todo.empty()) {
    RenderSettings settings;
    settings.width = settings.height = resolution_;
    const std::vector<uint32_t> seeds(todo.size(), seed_);
    const auto images = renderer_.render_batch(space_.decl(), todo, seeds, settings);
    for (size_t k = 0; k < images.size(); ++k) {
      const double s = metric_.similarity(target_, metric_.features(images[k], resolution_));
      cache_[todo[k]] = s;
      out[todo_index[k]] = s;
      // Duplicates within one batch share the result.
      for (size_t i = 0; i < units.size(); ++i)
        if (packed[i] == todo[k]) out[i] = s;
    }
    evaluations_ += static_cast<long>(todo.size());
  }
  for (size_t i = 0; i < units.size(); ++i)
    if (out[i] > best_.similarity || best_.packed.empty()) best_ = {packed[i], out[i]};
  if (on_progress) on_progress(*this);
  return out;
}

double Objective::evaluate(const std::vector<double>& unit) { return evaluate(std::vector<std::vector<double>>{unit}).front(); }

}  // namespace proctex::search
