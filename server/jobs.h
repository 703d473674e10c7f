#pragma once
// Running the jobs of `proctex serve`: a bounded queue and N worker threads (default 1: one
// OpenCL job at a time per device; UI renders run between the job's launches on the same queue).
// A job calls the same library function as the CLI (search::match, transform::plan + render_frames)
// and reports live progress (stage, evaluations, best similarity, a small preview PNG of the best
// render so far) that the SSE stream and the status endpoint read.
#include <array>
#include <atomic>
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

// A PNG of `image` in memory (written through image/'s atomic save into `tmp_dir`, read back).
std::string encode_png(const Image& image, const std::filesystem::path& tmp_dir, const std::string& ext = ".png");

}  // namespace proctex::server
