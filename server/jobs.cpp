#include "server/jobs.h"

#include <chrono>
#include <climits>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "core/error.h"
#include "kernels/runtime.h"
#include "shaders/renderer.h"
#include "synth/render.h"
#include "transform/frames.h"
#include "transform/morph.h"

namespace proctex::server {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string tmp_name(const std::string& ext) {
  static std::mutex m;
  static std::mt19937_64 rng{std::random_device{}()};
  std::lock_guard lock(m);
  return fmt::format("{:016x}{}", rng(), ext);
}

void write_file_atomic(const fs::path& path, const std::string& data) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    if (!out) throw Error("cannot write '" + path.string() + "'", "check the free space of the --data folder");
  }
  fs::rename(tmp, path);
}

template <typename T>
T field(const nlohmann::json& j, const char* name, T fallback, T lo, T hi) {
  if (!j.contains(name) || j[name].is_null()) return fallback;
  const auto& v = j[name];
  if (!v.is_number()) throw UsageError(fmt::format("'{}' must be a number", name), "see /api/openapi.json");
  if constexpr (std::is_integral_v<T>) {
    if (!v.is_number_integer()) throw UsageError(fmt::format("'{}' must be a whole number", name), "see /api/openapi.json");
  }
  const T x = v.get<T>();
  if (!(x >= lo && x <= hi))
    throw UsageError(fmt::format("'{}' is {}, outside [{}, {}]", name, x, lo, hi), "see /api/openapi.json");
  return x;
}

search::Budget parse_budget(const nlohmann::json& v) {
  search::Budget b;
  if (v.is_null()) return b;
  const std::string text = v.is_string() ? v.get<std::string>() : v.dump();
  try {
    size_t used = 0;
    const double x = std::stod(text, &used);
    const std::string unit = text.substr(used);
    if (!(x > 0) || x > 1e7) throw std::invalid_argument(text);
    if (unit == "s") b.max_seconds = x;
    else if (unit == "m") b.max_seconds = 60 * x;
    else if (unit.empty() || unit == "e") b.max_evaluations = static_cast<long>(x);
    else throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw UsageError("'budget' " + text + " is not a time (\"30s\", \"2m\") or an evaluation count (500)",
                     "send \"budget\": \"20s\" or \"budget\": 400");
  }
  return b;
}

}  // namespace

std::array<int, 4> crop_from_json(const nlohmann::json& v) {
  std::array<int, 4> c{};
  int n = 0;
  if (v.is_string()) {
    std::stringstream in(v.get<std::string>());
    std::string item;
    while (std::getline(in, item, ',') && n < 5) {
      try {
        size_t used = 0;
        const int x = std::stoi(item, &used);
        if (used != item.size()) throw std::invalid_argument(item);
        if (n < 4) c[n] = x;
        ++n;
      } catch (const std::exception&) {
        n = -100;
        break;
      }
    }
  }
  if (n != 4 || c[0] < 0 || c[1] < 0 || c[2] < 32 || c[3] < 32)
    throw UsageError("'crop' must be \"x,y,w,h\" in pixels (w and h at least 32)", "send \"crop\": \"0,0,512,512\"");
  return c;
}

search::MatchOptions match_options_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw UsageError("match options must be a JSON object", "send e.g. {\"budget\": \"20s\"}");
  static const std::vector<std::string> known = {"shaders", "candidates", "screen", "race", "starts", "evaluations",
                                                 "budget", "fix", "optimizer", "render_size", "threshold", "crop"};
  for (const auto& [k, v] : j.items())
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw UsageError("unknown match option '" + k + "'", "known: shaders, candidates, screen, race, starts, "
                                                           "evaluations, budget, fix, optimizer, threshold, render_size, crop");
  search::MatchOptions o;
  if (j.contains("shaders") && !j["shaders"].is_null()) {
    const auto& s = j["shaders"];
    std::vector<std::string> names;
    if (s.is_string()) {
      std::stringstream in(s.get<std::string>());
      std::string item;
      while (std::getline(in, item, ','))
        if (!item.empty()) names.push_back(item);
    } else if (s.is_array()) {
      for (const auto& n : s) {
        if (!n.is_string()) throw UsageError("'shaders' must be names", "send [\"bricks\", \"tiles\"]");
        names.push_back(n.get<std::string>());
      }
    } else {
      throw UsageError("'shaders' must be a list of names", "send [\"bricks\", \"tiles\"]");
    }
    for (const auto& n : names) ShaderLibrary::builtin().get(n);  // UsageError naming close matches
    o.shaders = names;
  }
  o.candidate_shaders = field<int>(j, "candidates", o.candidate_shaders, 0, 100000);
  o.screen = field<int>(j, "screen", o.screen, 1, 1000);
  o.race = field<int>(j, "race", o.race, 1, 256);
  o.starts = field<int>(j, "starts", o.starts, 1, 64);
  o.shader_threshold = field<double>(j, "threshold", 0.0, 0.0, 1.0);
  o.refine.max_evaluations = field<long>(j, "evaluations", o.refine.max_evaluations, 1, 1000000);
  field<int>(j, "render_size", 512, 16, 4096);
  if (j.contains("crop")) crop_from_json(j["crop"]);
  if (j.contains("optimizer")) {
    if (!j["optimizer"].is_string()) throw UsageError("'optimizer' must be a name", "neldermead, subplex, bobyqa, global or gradient");
    o.refine.optimizer = search::parse_optimizer(j["optimizer"].get<std::string>());
  }
  if (j.contains("budget")) o.budget = parse_budget(j["budget"]);
  if (j.contains("fix")) {
    if (!j["fix"].is_object()) throw UsageError("'fix' must be an object of parameter values", "send {\"rows\": 8}");
    for (const auto& [k, v] : j["fix"].items()) o.fixed[k] = v;
  }
  return o;
}

namespace {

// A job stopped by its stop flag (cancel) where no partial result is worth keeping (synth).
struct JobStopped {};

int level_count(int w, int h) {
  int L = 0;
  while ((1 << L) < std::max(w, h)) ++L;
  return L;
}

std::array<int, 2> parse_synth_size(const nlohmann::json& v, int max_size) {
  const std::string hint = fmt::format("send \"size\": 512, \"size\": \"1024x512\" or \"size\": [1024, 512] (16..{} px a side)", max_size);
  int64_t w = 0, h = 0;
  auto whole = [&](const nlohmann::json& x) -> int64_t {
    if (!x.is_number_integer()) throw UsageError("'size' must be whole numbers of pixels", hint);
    return x.get<int64_t>();
  };
  if (v.is_number()) {
    w = h = whole(v);
  } else if (v.is_array() && v.size() == 2) {
    w = whole(v[0]);
    h = whole(v[1]);
  } else if (v.is_string()) {
    const std::string t = v.get<std::string>();
    const auto x = t.find_first_of("xX");
    try {
      size_t a = 0, b = 0;
      const std::string ws = x == std::string::npos ? t : t.substr(0, x);
      const std::string hs = x == std::string::npos ? t : t.substr(x + 1);
      w = std::stoll(ws, &a);
      h = std::stoll(hs, &b);
      if (a != ws.size() || b != hs.size()) throw std::invalid_argument(t);
    } catch (const std::exception&) {
      throw UsageError("'size' \"" + t + "\" is not N or WxH", hint);
    }
  } else {
    throw UsageError("'size' must be N, \"WxH\" or [W, H]", hint);
  }
  if (w < 16 || h < 16 || w > max_size || h > max_size)
    throw UsageError(fmt::format("'size' {}x{} is outside 16..{} px a side", w, h, max_size),
                     "larger syntheses: proctex synth EXEMPLAR -o out.png --size N (strip by strip, any size)");
  return {static_cast<int>(w), static_cast<int>(h)};
}

}  // namespace

nlohmann::json SynthJobOptions::to_json() const {
  auto decimal = [](float v) { return std::round(double(v) * 1e6) / 1e6; };
  nlohmann::json j = {{"size", {width, height}},
                      {"tileable", tileable},
                      {"seed", synth.seed},
                      {"passes", synth.passes},
                      {"finest_passes", synth.finest_passes},
                      {"coherence", decimal(synth.kappa)},
                      {"randomness_scale", randomness_scale},
                      {"exemplar_tiles", exemplar_tiles == synth::Tiling::Auto       ? "auto"
                                         : exemplar_tiles == synth::Tiling::Toroidal ? "yes"
                                                                                      : "no"},
                      {"downscale", downscale},
                      {"blend_seams", blend_seams}};
  if (randomness_given) {
    j["randomness"] = nlohmann::json::array();
    for (float r : synth.randomness) j["randomness"].push_back(decimal(r));
  }
  if (!from_job.empty()) j["from_job"] = from_job;
  return j;
}

SynthJobOptions synth_options_from_json(const nlohmann::json& j, int max_size) {
  if (!j.is_object()) throw UsageError("synth options must be a JSON object", "send e.g. {\"size\": 512, \"seed\": 3}");
  static const std::vector<std::string> known = {"size",     "tileable",       "seed",     "randomness", "randomness_scale",
                                                 "passes",   "finest_passes",  "coherence",      "exemplar_tiles", "downscale", "blend_seams", "from_job"};
  for (const auto& [k, v] : j.items())
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw UsageError("unknown synth option '" + k + "'",
                       "known: size, tileable, seed, randomness, randomness_scale, passes, finest_passes, coherence, exemplar_tiles, "
                       "downscale, blend_seams, from_job");
  SynthJobOptions o;
  if (j.contains("size") && !j["size"].is_null()) {
    const auto s = parse_synth_size(j["size"], max_size);
    o.width = s[0];
    o.height = s[1];
  } else if (o.width > max_size) {
    o.width = o.height = max_size;
  }
  auto flag = [&](const char* name, bool fallback) {
    if (!j.contains(name) || j[name].is_null()) return fallback;
    if (!j[name].is_boolean()) throw UsageError(fmt::format("'{}' must be true or false", name), "see /api/openapi.json");
    return j[name].get<bool>();
  };
  o.tileable = flag("tileable", false);
  o.downscale = flag("downscale", false);
  o.blend_seams = flag("blend_seams", true);
  o.synth.seed = static_cast<uint32_t>(field<int64_t>(j, "seed", 1, 0, 0xffffffffLL));
  // Defaults: the library's (= the command line's, so the result equals `proctex synth`'s).
  if (j.contains("passes") && !j["passes"].is_null()) {
    const auto& p = j["passes"];
    const char* hint = "send \"passes\": 2 or a list coarse to fine, [0, 2], each in [0, 8]";
    std::vector<int> values;
    if (p.is_number_integer()) values.push_back(p.get<int>());
    else if (p.is_array() && !p.empty() && p.size() <= 32)
      for (const auto& x : p) {
        if (!x.is_number_integer()) throw UsageError("'passes' must be whole numbers", hint);
        values.push_back(x.get<int>());
      }
    else throw UsageError("'passes' must be a whole number or a list of 1-32 of them", hint);
    for (int v : values)
      if (v < 0 || v > 8) throw UsageError(fmt::format("'passes' {} is outside [0, 8]", v), hint);
    o.synth.passes = values;
  }
  o.synth.finest_passes = field<int>(j, "finest_passes", o.synth.finest_passes, -1, 8);
  o.synth.kappa = static_cast<float>(field<double>(j, "coherence", synth::kSingleExemplarCoherence, 0.0, 100.0));
  o.randomness_scale = field<double>(j, "randomness_scale", 1.0, 0.0, 4.0);
  if (j.contains("randomness") && !j["randomness"].is_null()) {
    const auto& r = j["randomness"];
    std::vector<float> values;
    const char* hint = "send \"randomness\": 0.5 or a list coarse to fine, [1, 1, 0.5, 0.2, 0], each in [0, 4]";
    if (r.is_number()) values.push_back(r.get<float>());
    else if (r.is_array() && !r.empty() && r.size() <= 32) {
      for (const auto& x : r) {
        if (!x.is_number()) throw UsageError("'randomness' must be numbers", hint);
        values.push_back(x.get<float>());
      }
    } else {
      throw UsageError("'randomness' must be a number or a list of 1-32 numbers", hint);
    }
    for (float v : values)
      if (!(v >= 0.0f && v <= 4.0f)) throw UsageError(fmt::format("'randomness' {} is outside [0, 4]", v), hint);
    o.synth.randomness = values;
    o.randomness_given = true;
  }
  if (j.contains("exemplar_tiles") && !j["exemplar_tiles"].is_null()) {
    const std::string t = j["exemplar_tiles"].is_string() ? j["exemplar_tiles"].get<std::string>() : "?";
    if (t == "auto") o.exemplar_tiles = synth::Tiling::Auto;
    else if (t == "yes") o.exemplar_tiles = synth::Tiling::Toroidal;
    else if (t == "no") o.exemplar_tiles = synth::Tiling::Bounded;
    else throw UsageError("'exemplar_tiles' must be \"auto\", \"yes\" or \"no\"", "auto measures the seam");
  }
  if (o.tileable && (o.width % 2 || o.height % 2))
    throw UsageError(fmt::format("a tileable synthesis needs an even size, got {}x{}", o.width, o.height),
                     "use a multiple of a large power of two, e.g. 512 or 1024");
  if (j.contains("from_job") && !j["from_job"].is_null()) {
    if (!j["from_job"].is_string() || !JobStore::valid_id(j["from_job"].get<std::string>()))
      throw UsageError("'from_job' must be a job id (32 hex digits)", "list jobs with GET /api/jobs");
    o.from_job = j["from_job"].get<std::string>();
  }
  return o;
}

std::array<int, 2> synth_exemplar_size(const SynthJobOptions& o, int w, int h) {
  if (o.downscale && std::max(w, h) > synth::kMaxExemplarSide) {
    const double f = double(synth::kMaxExemplarSide) / std::max(w, h);
    w = std::max(1, static_cast<int>(std::lround(w * f)));
    h = std::max(1, static_cast<int>(std::lround(h * f)));
  }
  if (std::max(w, h) > synth::kMaxExemplarSide)
    throw UsageError(fmt::format("the exemplar is {}x{} pixels; the synthesizer takes {}..{} px a side", w, h,
                                 synth::kMinExemplarSide, synth::kMaxExemplarSide),
                     "crop a typical patch of the texture, or send \"downscale\": true to scale it down to 512 px");
  if (std::min(w, h) < synth::kMinExemplarSide)
    throw UsageError(fmt::format("the exemplar is {}x{} pixels; the synthesizer needs at least {} px a side", w, h,
                                 synth::kMinExemplarSide),
                     "send a larger example of the texture");
  return {w, h};
}

synth::SynthOptions resolve_synth_options(const SynthJobOptions& o, int ew, int eh) {
  synth::SynthOptions s = o.synth;
  const int levels = level_count(ew, eh);
  // The default profile has 5 values (coarse to fine); a 16 px exemplar has only 4 levels.
  if (!o.randomness_given && static_cast<int>(s.randomness.size()) > levels) s.randomness.resize(std::max(1, levels));
  if (static_cast<int>(s.randomness.size()) > levels)
    throw UsageError(fmt::format("'randomness' has {} values but a {}x{} exemplar has {} levels", s.randomness.size(), ew, eh, levels),
                     "give one value, or at most one per level, coarse to fine");
  for (float& r : s.randomness) {
    r = static_cast<float>(r * o.randomness_scale);
    if (!(r <= 4.0f))
      throw UsageError(fmt::format("'randomness' x 'randomness_scale' is {}, over 4", r), "use a smaller randomness_scale");
  }
  if (o.tileable) {
    s.period_x = o.width;
    s.period_y = o.height;
  }
  synth::Analysis shape;  // check_options reads only the exemplar's size and levels
  shape.width = ew;
  shape.height = eh;
  shape.levels = levels;
  synth::check_options(shape, s);
  return s;
}

std::string encode_png(const Image& image, const fs::path& tmp_dir, const std::string& ext) {
  const fs::path path = tmp_dir / tmp_name(ext);
  save_image(image, path);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::error_code ec;
  fs::remove(path, ec);
  return bytes;
}

JobRunner::JobRunner(JobStore& store, RunnerOptions options) : store_(store), options_(std::move(options)) {
  for (int i = 0; i < std::max(1, options_.workers); ++i) workers_.emplace_back([this] { work(); });
}

JobRunner::~JobRunner() {
  {
    std::lock_guard lock(mutex_);
    shutting_down_ = true;
    for (auto& [id, live] : live_) live->stop = true;
  }
  wake_.notify_all();
  for (auto& t : workers_) t.join();
}

bool JobRunner::has_room() {
  std::lock_guard lock(mutex_);
  return !shutting_down_ && static_cast<int>(queue_.size()) < options_.queue_limit;
}

void JobRunner::enqueue(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    if (shutting_down_) throw QueueFull("the server is shutting down");
    if (static_cast<int>(queue_.size()) >= options_.queue_limit)
      throw QueueFull(fmt::format("the job queue is full ({} waiting, {} running)", queue_.size(), running_));
    queue_.push_back(id);
    live_[id] = std::make_shared<LiveJob>();
  }
  wake_.notify_one();
}

bool JobRunner::cancel(const std::string& id) {
  std::shared_ptr<LiveJob> live;
  bool was_queued = false;
  {
    std::lock_guard lock(mutex_);
    auto it = live_.find(id);
    if (it == live_.end()) return false;
    live = it->second;
    {
      std::lock_guard state_lock(live->mutex);
      if (live->state != "queued" && live->state != "running") return false;  // finishing: nothing to cancel
    }
    live->stop = true;
    auto q = std::find(queue_.begin(), queue_.end(), id);
    if (q != queue_.end()) {
      queue_.erase(q);
      live_.erase(id);
      was_queued = true;
    }
  }
  if (was_queued) {
    store_.finish(id, "cancelled", nullptr, "");
    std::lock_guard lock(live->mutex);
    live->state = "cancelled";
    live->changed.notify_all();
  }
  return true;
}

std::shared_ptr<LiveJob> JobRunner::live(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = live_.find(id);
  return it == live_.end() ? nullptr : it->second;
}

void JobRunner::wait(const std::string& id, double seconds) {
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  auto l = live(id);
  if (!l) return;
  std::unique_lock lock(l->mutex);
  l->changed.wait_until(lock, deadline, [&] { return l->state != "running" && l->state != "queued"; });
}

nlohmann::json JobRunner::stats() {
  std::lock_guard lock(mutex_);
  return {{"queued", queue_.size()}, {"running", running_}, {"workers", workers_.size()}, {"queue_limit", options_.queue_limit}};
}

void JobRunner::work() {
  for (;;) {
    std::string id;
    std::shared_ptr<LiveJob> live;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return shutting_down_ || !queue_.empty(); });
      if (shutting_down_) return;
      id = queue_.front();
      queue_.pop_front();
      live = live_[id];
      ++running_;
    }
    const auto job = store_.get(id);
    if (job) {
      {
        std::lock_guard lock(live->mutex);
        live->state = "running";
      }
      store_.set_running(id);
      run(*job, *live);
    }
    {
      std::lock_guard lock(mutex_);
      --running_;
      live_.erase(id);
    }
    // After the job has left live_: a cancel or status request sees it finished meanwhile.
    if (job && options_.on_finished) {
      try {
        options_.on_finished(id);
      } catch (const std::exception&) {
        // Retention is housekeeping: it never fails a job (it runs again after the next one).
      }
    }
  }
}

void JobRunner::run(const JobRecord& job, LiveJob& live) {
  std::string state, error;
  nlohmann::json result;
  try {
    result = job.kind == "match"   ? run_match(job, live)
             : job.kind == "synth" ? run_synth(job, live)
                                   : run_morph(job, live);
    state = live.stop ? "cancelled" : "done";
  } catch (const JobStopped&) {
    state = "cancelled";
    result = nullptr;
  } catch (const Error& e) {
    state = "failed";
    error = e.message() + (e.hint().empty() ? "" : " (" + e.hint() + ")");
  } catch (const std::bad_alloc&) {
    state = "failed";
    error = "out of memory";
  } catch (const std::exception& e) {
    state = "failed";
    error = std::string("internal error: ") + e.what();
  }
  bool shutting_down;
  {
    std::lock_guard lock(mutex_);
    shutting_down = shutting_down_;
  }
  // Stopped by a shutdown, not by a user: left "interrupted" so that it can be re-run.
  if (shutting_down && live.stop) {
    state = "interrupted";
    result = nullptr;
  }
  store_.set_progress(job.id, live.progress);
  store_.finish(job.id, state, result, error);
  std::lock_guard lock(live.mutex);
  live.state = state;
  live.changed.notify_all();
}

void JobRunner::yield_to_ui_renders() {
  if (!options_.ui_renders) return;
  // Bounded: a stream of renders from many clients cannot stop a match for more than 2 s at a time.
  const auto deadline = Clock::now() + std::chrono::seconds(2);
  while (options_.ui_renders->load() > 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

nlohmann::json JobRunner::run_match(const JobRecord& job, LiveJob& live) {
  const fs::path dir = store_.job_dir(job.id);
  const fs::path tmp = store_.data_dir() / "tmp";
  const nlohmann::json& opts = job.params.value("options", nlohmann::json::object());
  const search::MatchOptions options = match_options_from_json(opts);
  const int render_size = opts.value("render_size", 512);
  const fs::path input = dir / job.params.at("input").get<std::string>();
  ImageLimits limits;
  limits.max_dimension = job.params.value("max_dimension", 8192);
  limits.max_pixels = job.params.value("max_pixels", int64_t(1) << 25);
  Image target = load_image(input, limits);
  if (opts.contains("crop")) {
    const auto c = crop_from_json(opts["crop"]);
    if (c[0] + c[2] > target.width || c[1] + c[3] > target.height)
      throw UsageError(fmt::format("crop {},{},{},{} is outside the {}x{} photo", c[0], c[1], c[2], c[3], target.width, target.height),
                       "crop inside the photo");
    target = crop(target, c[0], c[1], c[2], c[3]);
  }
  if (!fs::exists(options_.catalog))
    throw Error("no catalogue at '" + options_.catalog.string() + "'", "start the server with --db CATALOG");
  catalog::Store store(options_.catalog, catalog::Store::Access::Read);
  catalog::require_current_sources(store);  // it may have changed since the job was accepted

  Renderer renderer;
  auto last_preview = Clock::now() - std::chrono::hours(1);
  auto last_saved = Clock::now();
  std::string preview_shader;
  nlohmann::json preview_spec;
  auto publish = [&](const search::MatchProgress& p, bool force_preview) {
    nlohmann::json progress = {{"stage", p.stage}, {"evaluations", p.evaluations}, {"best", p.best},
                               {"best_shader", p.best_shader}, {"elapsed", p.elapsed}};
    std::string png;
    const bool new_best = !p.best_spec.shader.empty() && p.best_spec.to_json() != preview_spec;
    if (new_best && (force_preview || since(last_preview) >= options_.preview_interval)) {
      RenderSettings rs;
      rs.width = rs.height = options_.preview_size;
      try {
        png = encode_png(renderer.render(p.best_spec, rs), tmp);
      } catch (const Error&) {
        // A preview is a courtesy: it never fails the match (the result is rendered again below).
      }
      preview_spec = p.best_spec.to_json();
      last_preview = Clock::now();
    }
    if (!preview_spec.is_null()) progress["best_spec"] = preview_spec;
    {
      std::lock_guard lock(live.mutex);
      live.progress = progress;
      if (!png.empty()) {
        live.preview_png = std::move(png);
        ++live.preview_version;
      }
    }
    live.changed.notify_all();
    if (since(last_saved) > 1.0) {
      store_.set_progress(job.id, progress);
      last_saved = Clock::now();
    }
  };
  search::MatchProgress last;
  auto result = search::match(target, store, options, [&](const search::MatchProgress& p) {
    last = p;
    publish(p, false);
    // Between batches: let a waiting slider render have the device and the cores.
    yield_to_ui_renders();
  }, &live.stop);

  nlohmann::json j = result.to_json();
  j["target"] = {{"file", job.params.at("input")}, {"width", target.width}, {"height", target.height}};
  // The result's files: the match rendered, target and match side by side, the spec.
  RenderSettings rs;
  rs.width = rs.height = render_size;
  const Image img = renderer.render(result.spec, rs);
  save_image(img, dir / "render.png");
  const int side = std::min(512, std::max(render_size, 256));
  const Image t = resize(center_crop_square(target), side, side);
  save_image(contact_sheet({t, resize(img, side, side)},
                           {"target", fmt::format("{} S={:.2f} ({})", result.spec.shader, result.similarity, result.verdict)},
                           2, side),
             dir / "compare.png");
  write_file_atomic(dir / "spec.json", result.spec.to_json().dump(2) + "\n");
  j["files"] = {{"spec", "spec.json"}, {"render", "render.png"}, {"compare", "compare.png"}, {"result", "result.json"},
                {"target", job.params.at("input")}};
  write_file_atomic(dir / "result.json", j.dump(2) + "\n");
  // The final preview is the result itself.
  last.best = result.similarity;
  last.best_shader = result.spec.shader;
  last.best_spec = result.spec;
  last.stage = "done";
  publish(last, true);
  return j;
}

nlohmann::json JobRunner::run_morph(const JobRecord& job, LiveJob& live) {
  const fs::path dir = store_.job_dir(job.id);
  const auto& p = job.params;
  std::vector<TextureSpec> keys;
  for (const auto& k : p.at("keys")) keys.push_back(TextureSpec::from_json(k));
  transform::MorphOptions o;
  o.frames = p.value("frames", 24);
  o.dissolve = p.value("dissolve", 0);
  o.jobs = 1;
  const int size = p.value("size", 256);
  const int fps = p.value("fps", 12);
  if (!fs::exists(options_.catalog))
    throw Error("no catalogue at '" + options_.catalog.string() + "'", "start the server with --db CATALOG");
  catalog::Store store(options_.catalog, catalog::Store::Access::Read);
  Renderer renderer;
  const auto t0 = Clock::now();
  auto publish = [&](const std::string& stage, double fraction) {
    std::lock_guard lock(live.mutex);
    live.progress = {{"stage", stage}, {"fraction", fraction}, {"elapsed", since(t0)}};
    live.changed.notify_all();
  };
  transform::Morph m = transform::plan(keys, store, renderer, o, [&](const transform::MorphProgress& mp) {
    publish(mp.stage, mp.fraction);
  });
  fs::create_directories(dir / "frames");
  RenderSettings rs;
  rs.width = rs.height = size;
  std::vector<Image> small, strip;
  nlohmann::json manifest = m.manifest();
  const int gif_side = std::min(size, 256);
  for (size_t first = 0; first < m.frames.size(); first += 8) {
    if (live.stop) break;
    const auto images = transform::render_frames(m.frames, first, 8, renderer, rs);
    for (size_t k = 0; k < images.size(); ++k) {
      const std::string name = fmt::format("frame_{:04d}.png", first + k + 1);
      save_image(images[k], dir / "frames" / name);
      manifest["frames"][first + k]["file"] = "frames/" + name;
      small.push_back(resize(images[k], gif_side, gif_side));
    }
    publish("frames", double(std::min(m.frames.size(), first + 8)) / m.frames.size());
  }
  nlohmann::json files = {{"manifest", "manifest.json"}};
  if (!small.empty()) {
    transform::write_gif(small, dir / "morph.gif", fps);
    files["gif"] = "morph.gif";
    std::vector<Image> tiles;
    std::vector<std::string> labels;
    const size_t n = std::min<size_t>(small.size(), 8);
    for (size_t i = 0; i < n; ++i) {
      const size_t f = n == 1 ? 0 : i * (small.size() - 1) / (n - 1);
      tiles.push_back(resize(small[f], 128, 128));
      labels.push_back(fmt::format("frame {}", f + 1));
    }
    save_image(contact_sheet(tiles, labels, static_cast<int>(n), 128), dir / "filmstrip.png");
    files["filmstrip"] = "filmstrip.png";
  }
  nlohmann::json frames = nlohmann::json::array();
  for (size_t i = 0; i < small.size(); ++i) frames.push_back(fmt::format("frames/frame_{:04d}.png", i + 1));
  files["frames"] = frames;
  write_file_atomic(dir / "manifest.json", manifest.dump(2) + "\n");
  nlohmann::json j = m.summary();
  j["files"] = files;
  j["size"] = size;
  j["fps"] = fps;
  publish("done", 1.0);
  return j;
}

}  // namespace proctex::server

namespace proctex::server {

nlohmann::json JobRunner::run_synth(const JobRecord& job, LiveJob& live) {
  const fs::path dir = store_.job_dir(job.id);
  const auto& p = job.params;
  const SynthJobOptions o = synth_options_from_json(p.at("options"), p.value("max_size", INT_MAX));
  const auto t0 = Clock::now();
  auto publish = [&](const std::string& stage, double fraction) {
    {
      std::lock_guard lock(live.mutex);
      live.progress = {{"stage", stage}, {"fraction", fraction}, {"elapsed", since(t0)}};
    }
    live.changed.notify_all();
  };
  publish("exemplar", 0.0);
  ImageLimits limits;
  limits.max_dimension = p.value("max_dimension", 8192);
  limits.max_pixels = p.value("max_pixels", int64_t(1) << 24);
  Image image = load_image(dir / p.at("input").get<std::string>(), limits);
  const int uploaded_w = image.width, uploaded_h = image.height;
  const auto size = synth_exemplar_size(o, image.width, image.height);
  if (size[0] != image.width || size[1] != image.height) image = resize(image, size[0], size[1]);
  synth::Exemplar ex;
  ex.name = "exemplar";
  ex.colour = std::move(image);
  synth::validate(ex);
  save_image(ex.colour, dir / "exemplar.png");
  const synth::SynthOptions options = resolve_synth_options(o, ex.width(), ex.height());
  if (live.stop) throw JobStopped{};

  publish("analysis", 0.0);
  synth::AnalysisOptions ao;
  ao.tiling = o.exemplar_tiles;
  const synth::Analysis analysis = synth::analyse_cached(ex, ao, options_.synth_cache);
  if (!options_.synth_cache.empty()) {  // last use = modification time: retention drops the least recently used first
    std::error_code ec;
    fs::last_write_time(options_.synth_cache / (analysis.hash + ".bin"), fs::file_time_type::clock::now(), ec);
  }
  if (live.stop) throw JobStopped{};

  publish("synthesis", 0.0);
  synth::Synthesizer synthesizer(analysis);
  synth::RenderOutputs outputs;
  outputs.colour = dir / "synth.png";
  outputs.blend_seams = o.blend_seams;
  outputs.blend_radius = synth::kSingleExemplarBlendRadius;  // as `proctex synth`
  const synth::Window window{0, 0, o.width, o.height};
  // Strips of at most 1 M pixels: progress and a cancel between strips; the output does not depend
  // on the strips (spatial determinism).
  const synth::RenderStats stats = synth::render(
      synthesizer, ex, window, options, outputs,
      [&](double f) {
        publish("synthesis", f);
        if (live.stop) throw JobStopped{};  // the unfinished file is removed by synth::render
      },
      size_t(1) << 20);

  // Floats as the decimals a user typed (0.2, not 0.20000000298).
  auto decimal = [](float v) { return std::round(double(v) * 1e6) / 1e6; };
  nlohmann::json randomness = nlohmann::json::array();
  for (float r : options.randomness) randomness.push_back(decimal(r));
  nlohmann::json j = {{"seed", options.seed},
                      {"size", {o.width, o.height}},
                      {"tileable", o.tileable},
                      {"randomness", randomness},
                      {"passes", options.passes},
                      {"finest_passes", options.finest_passes},
                      {"coherence", decimal(options.kappa)},
                      {"levels", analysis.levels},
                      {"first_level", synth::first_level(analysis, options)},
                      {"exemplar", {{"width", analysis.width}, {"height", analysis.height}, {"tiles", analysis.toroidal},
                                    {"uploaded", {uploaded_w, uploaded_h}},
                                    {"downscaled", uploaded_w != analysis.width || uploaded_h != analysis.height}}},
                      {"analysis_hash", analysis.hash},
                      {"analysis_cached", analysis.from_cache},
                      {"timings", {{"analysis", analysis.seconds}, {"synthesis", stats.seconds}, {"total", since(t0)}}},
                      {"strips", stats.strips},
                      {"device", ocl::Runtime::instance().device().name},
                      {"command", fmt::format("proctex synth exemplar.png -o synth.png --size {}x{} --seed {}{} --passes {} "
                                              "--finest-passes {} --coherence {} --randomness {} --blend-seams {}{}",
                                              o.width, o.height, options.seed, o.tileable ? " --tileable" : "",
                                              fmt::join(options.passes, ","), options.finest_passes, options.kappa,
                                              fmt::join(options.randomness, ","), o.blend_seams ? "on" : "off",
                                              o.exemplar_tiles == synth::Tiling::Auto       ? ""
                                              : o.exemplar_tiles == synth::Tiling::Toroidal ? " --exemplar-tiles yes"
                                                                                             : " --exemplar-tiles no")},
                      {"files", {{"synth", "synth.png"}, {"exemplar", "exemplar.png"}, {"input", p.at("input")},
                                 {"result", "result.json"}}}};
  write_file_atomic(dir / "result.json", j.dump(2) + "\n");
  publish("done", 1.0);
  return j;
}

}  // namespace proctex::server
