#pragma once
// Running the jobs of `proctex serve`: a bounded queue and N worker threads (default 1: one
// OpenCL job at a time per device; UI renders run between the job's launches on the same queue).
// A job calls the same library function as the CLI (search::match, transform::plan + render_frames,
// synth::analyse_cached + synth::render) and reports live progress (stage, evaluations, best similarity, a small preview PNG of the best
// render so far) that the SSE stream and the status endpoint read.
#include <array>
#include <atomic>
#include <functional>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/job_store.h"
#include "image/image.h"
#include "search/match.h"
#include "shaders/spec.h"
#include "synth/analysis.h"
#include "synth/synthesis.h"

namespace proctex::server {

// What a running job shows; guarded by `mutex`, `changed` notified on every update.
struct LiveJob {
  std::mutex mutex;
  std::condition_variable changed;
  nlohmann::json progress = nlohmann::json::object();  // stage, evaluations, best, best_shader, elapsed
  std::string preview_png;   // small render of the best spec so far (empty: none yet)
  int preview_version = 0;   // bumped with each new preview
  std::string state = "queued";
  std::atomic<bool> stop{false};
};

struct RunnerOptions {
  std::filesystem::path catalog;  // catalogue for match and morph
  int workers = 1;                // jobs run at the same time
  int queue_limit = 8;            // jobs waiting (beyond the running ones); more: 429
  int preview_size = 96;          // side of the live preview PNG
  double preview_interval = 0.25; // seconds between preview renders (at most)
  std::filesystem::path synth_cache;  // synth analyses (DATA/cache/synth); empty: no cache
  // Called on the worker thread after a job has finished and its state is stored (retention).
  std::function<void(const std::string& id)> on_finished;
  // UI renders waiting or running (owned by the server): a match waits between its batches while
  // this is non-zero, so a slider render has the device and both cores to itself.
  std::shared_ptr<std::atomic<int>> ui_renders;
};

class QueueFull : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JobRunner {
 public:
  JobRunner(JobStore& store, RunnerOptions options);
  ~JobRunner();  // stops the workers: running jobs are asked to stop and left "interrupted"

  // Queues a job already in the store (state queued). Throws QueueFull when the queue is full.
  void enqueue(const std::string& id);
  // True when one more job fits in the queue now.
  bool has_room();
  // Asks a queued or running job to stop. A running match returns its best so far ("cancelled"
  // with a result); a queued job is cancelled without one. False for an unknown or finished job.
  bool cancel(const std::string& id);
  // Live state of a queued or running job (nullptr otherwise).
  std::shared_ptr<LiveJob> live(const std::string& id);
  // Waits until the job has left the running state or `seconds` passed.
  void wait(const std::string& id, double seconds);

  nlohmann::json stats();  // queued, running, workers, queue_limit
  const RunnerOptions& options() const { return options_; }

 private:
  void work();
  void run(const JobRecord& job, LiveJob& live);
  nlohmann::json run_match(const JobRecord& job, LiveJob& live);
  nlohmann::json run_morph(const JobRecord& job, LiveJob& live);
  nlohmann::json run_synth(const JobRecord& job, LiveJob& live);
  void yield_to_ui_renders();

  JobStore& store_;
  RunnerOptions options_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  std::map<std::string, std::shared_ptr<LiveJob>> live_;
  int running_ = 0;
  bool shutting_down_ = false;
  std::vector<std::thread> workers_;
};

// Match options from the JSON of POST /api/jobs/match (names as on the command line); throws
// UsageError naming the bad field.
search::MatchOptions match_options_from_json(const nlohmann::json& j);
// The "crop" option, "x,y,w,h" in pixels (w, h >= 32); throws UsageError.
std::array<int, 4> crop_from_json(const nlohmann::json& v);

// Synth job options (POST /api/jobs/synth; names as on `proctex synth`'s command line where they
// exist). Parsed and checked before anything is stored; to_json() is what the job records.
struct SynthJobOptions {
  int width = 512, height = 512;   // output size (also the period when tileable)
  bool tileable = false;
  synth::SynthOptions synth;       // seed, randomness, passes, coherence (kappa), period
  bool randomness_given = false;   // false: the default profile, cut to the exemplar's levels
  double randomness_scale = 1.0;   // multiplies every level's randomness
  synth::Tiling exemplar_tiles = synth::Tiling::Auto;
  bool downscale = false;          // exemplars over 512 px a side are scaled down to fit
  bool blend_seams = true;         // as proctex synth --blend-seams (default on)
  std::string from_job;            // reuse the exemplar (input) of an earlier job

  nlohmann::json to_json() const;
};
// Throws UsageError naming the bad field. `max_size`: the largest output side allowed.
SynthJobOptions synth_options_from_json(const nlohmann::json& j, int max_size);
// The exemplar size synthesis will use for an upload of w x h (after `downscale`); throws
// UsageError when it is outside 16..512 px a side.
std::array<int, 2> synth_exemplar_size(const SynthJobOptions& o, int width, int height);
// The options for an exemplar of w x h pixels (the randomness profile cut or checked against its
// levels, the period set): throws UsageError like `proctex synth` would.
synth::SynthOptions resolve_synth_options(const SynthJobOptions& o, int exemplar_width, int exemplar_height);

// A PNG of `image` in memory (written through image/'s atomic save into `tmp_dir`, read back).
std::string encode_png(const Image& image, const std::filesystem::path& tmp_dir, const std::string& ext = ".png");

}  // namespace proctex::server
