#pragma once
// proctex serve: the HTTP service. Thin handlers parse a request, call the same library function
// the CLI calls (shaders/ render, metrics/ compare, search::match, transform/ morph and synth/
// synthesis as jobs, catalog::info) and map proctex::Error to a JSON error body. The job store (job_store.h) is the
// only state; the web UI (web/) is embedded and served from "/". API: server/openapi.json,
// served at /api/openapi.json; docs/service.md.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

namespace proctex::server {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;                    // 0: any free port (bind() returns it)
  std::filesystem::path catalog;      // for match, morph and catalogue info
  std::filesystem::path data;         // job store and result files
  int workers = 1;                    // jobs at the same time (each uses the OpenCL device)
  int queue_limit = 8;                // jobs waiting beyond the running ones; more: 429
  std::string token;                  // bearer token; required when bind is not loopback
  int threads = 128;                  // HTTP threads (each progress stream and kept-alive connection holds one)
  std::size_t max_upload_bytes = 32u << 20;  // request bodies; larger: 413
  int max_upload_dimension = 8192;    // per side of an uploaded image (checked before decoding)
  int64_t max_upload_pixels = int64_t(1) << 24;  // 16.7 M pixels (192 MB as float RGB)
  int max_render_size = 4096;         // per side of /api/render
  int preview_size = 128;             // live preview side
  int max_synth_size = 2048;          // per side of a synth job's output
  bool ui_render_priority = true;     // a match pauses between batches while a UI render waits (bench: off for A/B)
  // Retention (0 = no limit): finished jobs kept, and bytes of the jobs' files plus the synth
  // analysis cache; the oldest finished jobs go first, never a queued or running one.
  int keep_jobs = 1000;
  uint64_t max_data_bytes = uint64_t(4096) << 20;
};

// True for 127.0.0.0/8, ::1 and "localhost".
bool is_loopback(const std::string& host);

class Server {
 public:
  // Opens the job store (marks interrupted jobs) and starts the job workers. Throws UsageError for
  // a non-loopback bind without a token, proctex::Error for an unusable data folder.
  explicit Server(ServerOptions options);
  ~Server();

  // Binds the socket; returns the port (the chosen one for port 0). Throws proctex::Error.
  int bind();
  // Serves until stop() (from another thread or a signal handler's thread).
  void run();
  void stop();
  std::string url() const;  // http://HOST:PORT/

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace proctex::server
