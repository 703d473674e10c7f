#pragma once
// The durable job store of `proctex serve`: one SQLite file (DATA/jobs.sqlite) with every job's
// kind, parameters, state, progress summary and result, and one folder per job (DATA/jobs/<id>/)
// for its input and result files. It is the service's only state: a restart reads it back, keeps
// finished results and marks the jobs that were queued or running as "interrupted" (re-runnable).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace proctex::catalog::sql {
class Connection;
}

namespace proctex::server {

// queued -> running -> done | cancelled (stopped, best so far kept) | failed;
// queued/running at a restart -> interrupted (POST /api/jobs/ID/retry queues it again).
// Retention: what a prune keeps. 0 = no limit.
struct Retention {
  int keep_jobs = 0;         // finished jobs kept (the newest)
  uint64_t max_bytes = 0;    // the jobs' files plus the synth analysis cache
};

struct PruneReport {
  int jobs_deleted = 0;
  int cache_files_deleted = 0;
  uint64_t bytes_freed = 0;
  uint64_t bytes = 0;        // the jobs' files plus the cache, after the prune
  int finished_jobs = 0;     // after the prune
};

struct JobRecord {
  std::string id;     // 32 lowercase hex digits, chosen by the server
  std::string kind;   // "match", "morph"
  std::string state;
  nlohmann::json params = nlohmann::json::object();
  nlohmann::json result;              // null until done/cancelled
  nlohmann::json progress = nlohmann::json::object();  // last stage/evaluations/best recorded
  std::string error;                  // failed: the message
  double created = 0, started = 0, finished = 0;  // Unix seconds (0: not yet)

  bool finished_state() const { return state == "done" || state == "cancelled" || state == "failed"; }
  nlohmann::json to_json() const;
};

class JobStore {
 public:
  // Opens (creates) DATA/jobs.sqlite; jobs left queued or running become "interrupted".
  explicit JobStore(const std::filesystem::path& data_dir);
  ~JobStore();

  JobRecord create(const std::string& kind, const nlohmann::json& params);
  std::optional<JobRecord> get(const std::string& id);
  std::vector<JobRecord> list(int limit = 100);
  // Jobs in a state, oldest first.
  std::vector<JobRecord> with_state(const std::string& state);

  void set_running(const std::string& id);
  void set_queued(const std::string& id);  // a retry: clears result, error and times
  void set_progress(const std::string& id, const nlohmann::json& progress);
  void finish(const std::string& id, const std::string& state, const nlohmann::json& result,
              const std::string& error = "");

  // Deletes finished jobs (done, cancelled, failed, interrupted; never queued or running, nor one
  // for which `busy(id)` is true) oldest first - their row and their folder - until at most
  // `keep_jobs` finished jobs are left and the data is within `max_bytes`. Over `max_bytes`, the
  // files of `cache_dir` (synth analyses, re-computable) go first, least recently used first; the
  // most recently finished job is always kept. Folders under jobs/ without a row are removed.
  PruneReport prune(const Retention& retention, const std::filesystem::path& cache_dir,
                    const std::function<bool(const std::string&)>& busy = {});
  // Bytes of the jobs' files plus `cache_dir`.
  uint64_t data_bytes(const std::filesystem::path& cache_dir);

  // DATA/jobs/<id>/ (created); `id` must be a valid job id (checked: never a client path).
  std::filesystem::path job_dir(const std::string& id) const;
  const std::filesystem::path& data_dir() const { return data_; }
  int interrupted_at_open() const { return interrupted_; }

  static bool valid_id(const std::string& id);

 private:
  std::filesystem::path data_;
  std::unique_ptr<catalog::sql::Connection> db_;
  std::mutex mutex_;        // the connection
  std::mutex prune_mutex_;  // one prune at a time
  int interrupted_ = 0;
};

double unix_now();

}  // namespace proctex::server
