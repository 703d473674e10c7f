// proctex serve: the HTTP service and web UI (server/), on loopback by default.
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "catalog/catalog.h"
#include "cli/commands.h"
#include "core/error.h"
#include "server/server.h"

namespace proctex::cli {
namespace {

server::Server* g_server = nullptr;
extern "C" void on_stop_signal(int) {
  // httplib's stop() only flips flags and shuts the listening socket down: safe enough here.
  if (g_server) g_server->stop();
}

std::filesystem::path default_data_dir() {
  if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return std::filesystem::path(x) / "proctex" / "serve";
  if (const char* h = std::getenv("HOME"); h && *h) return std::filesystem::path(h) / ".local" / "share" / "proctex" / "serve";
  return "proctex-serve";
}

}  // namespace

void add_serve_command(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<server::ServerOptions>();
  auto db = std::make_shared<std::string>();
  auto data = std::make_shared<std::string>();
  auto max_data_mb = std::make_shared<int64_t>(static_cast<int64_t>(o->max_data_bytes >> 20));
  auto* cmd = app.add_subcommand("serve", "Run the HTTP service and web UI (match, library, morph, synth)");
  cmd->footer(
      "Serves the web UI at / and the JSON API at /api (described by /api/openapi.json).\n"
      "Jobs (match, morph, synth) are kept in DATA/jobs.sqlite with their files under DATA/jobs/; a restart\n"
      "keeps finished results and marks interrupted jobs (POST /api/jobs/ID/retry re-runs them).\n"
      "Retention: beyond --keep-jobs finished jobs or --max-data-mb of files, the oldest finished jobs\n"
      "are deleted (never a queued or running one; the synth analysis cache goes before any job).\n"
      "  proctex serve --db build/demo/catalog.sqlite          then open http://127.0.0.1:8080/\n"
      "  proctex serve --bind 0.0.0.0 --token SECRET           clients send 'Authorization: Bearer SECRET'\n"
      "See docs/service.md.");
  cmd->add_option("--bind", o->bind, "Address to listen on (anything but loopback needs --token)")->capture_default_str();
  cmd->add_option("--port", o->port, "Port (0: any free port, printed)")->capture_default_str()->check(CLI::Range(0, 65535));
  cmd->add_option("--db", *db, "Catalogue for match and morph (default: $PROCTEX_CATALOG or ~/.cache/proctex/catalog.sqlite)");
  cmd->add_option("--data", *data, "Folder of the job store and result files (default: ~/.local/share/proctex/serve)");
  cmd->add_option("--workers", o->workers, "Jobs run at the same time (each uses the OpenCL device)")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--queue", o->queue_limit, "Jobs that may wait beyond the running ones; more get HTTP 429")->capture_default_str()->check(CLI::Range(0, 10000));
  cmd->add_option("--token", o->token, "Bearer token every request must carry (required off loopback)");
  cmd->add_option("--max-upload", o->max_upload_bytes, "Largest request body in bytes")->capture_default_str()->check(CLI::Range(1024, 1 << 30));
  cmd->add_option("--max-render", o->max_render_size, "Largest /api/render side in pixels")->capture_default_str()->check(CLI::Range(16, 16384));
  cmd->add_option("--max-synth", o->max_synth_size, "Largest synth job output side in pixels")->capture_default_str()->check(CLI::Range(16, 16384));
  cmd->add_option("--keep-jobs", o->keep_jobs, "Finished jobs kept, the newest (0: all)")->capture_default_str()->check(CLI::Range(0, 100000000));
  cmd->add_option("--max-data-mb", *max_data_mb, "Size limit of the jobs' files and caches in MiB (0: none); the oldest finished jobs go first")
      ->capture_default_str()->check(CLI::Range(int64_t(0), int64_t(1) << 30));
  cmd->callback([o, db, data, max_data_mb, &global] {
    o->catalog = db->empty() ? catalog::default_catalog_path() : std::filesystem::path(*db);
    o->data = data->empty() ? default_data_dir() : std::filesystem::path(*data);
    o->max_data_bytes = static_cast<uint64_t>(*max_data_mb) << 20;
    server::Server srv(*o);
    const int port = srv.bind();
    (void)port;
    if (!std::filesystem::exists(o->catalog))
      std::fprintf(stderr, "proctex serve: warning: no catalogue at '%s'; match and morph answer 503 (build one: proctex catalog build --db %s)\n",
                   o->catalog.string().c_str(), o->catalog.string().c_str());
    std::printf("proctex serve: listening on %s  (data: %s, catalogue: %s)\n", srv.url().c_str(), o->data.string().c_str(),
                o->catalog.string().c_str());
    std::fflush(stdout);
    g_server = &srv;
    auto prev_int = std::signal(SIGINT, on_stop_signal);
    auto prev_term = std::signal(SIGTERM, on_stop_signal);
    srv.run();
    std::signal(SIGINT, prev_int);
    std::signal(SIGTERM, prev_term);
    g_server = nullptr;
    if (!global.quiet) std::fprintf(stderr, "proctex serve: stopped\n");
  });
}

}  // namespace proctex::cli
