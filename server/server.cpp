#include "server/server.h"

#include <sys/socket.h>

#include <chrono>
#include <fstream>
#include <mutex>
#include <regex>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "core/error.h"
#include "core/version.h"
#include "image/image.h"
#include "kernels/runtime.h"
#include "metrics/composite.h"
#include "metrics/metric.h"
#include "server/job_store.h"
#include "server/jobs.h"
#include "shaders/library.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"
#include "synth/exemplar.h"

namespace proctex::embedded {
const std::vector<std::pair<std::string, std::string>>& web_files();
}

namespace proctex::server {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

// An HTTP error with a status: thrown by handlers, turned into a JSON body by `guarded`.
struct HttpError {
  int status;
  std::string message;
  std::string hint;
};

void send_json(httplib::Response& res, const json& j, int status = 200) {
  res.status = status;
  res.set_content(j.dump(), "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& message, const std::string& hint = "") {
  json j = {{"error", message}, {"status", status}};
  if (!hint.empty()) j["hint"] = hint;
  send_json(res, j, status);
}

// Runs a handler and maps every failure to a status and a JSON error body; nothing escapes.
template <typename Fn>
void guarded(httplib::Response& res, Fn&& fn) {
  try {
    fn();
  } catch (const HttpError& e) {
    send_error(res, e.status, e.message, e.hint);
  } catch (const QueueFull& e) {
    send_error(res, 429, e.what(), "retry later (Retry-After), or cancel a queued job");
    res.set_header("Retry-After", "5");
  } catch (const UsageError& e) {
    send_error(res, 400, e.message(), e.hint());
  } catch (const Error& e) {
    send_error(res, 400, e.message(), e.hint());
  } catch (const json::exception& e) {
    send_error(res, 400, std::string("bad JSON value: ") + e.what(), "see /api/openapi.json");
  } catch (const std::bad_alloc&) {
    send_error(res, 507, "out of memory", "use a smaller size");
  } catch (const std::exception& e) {
    send_error(res, 500, std::string("internal error: ") + e.what(), "this is a bug; please report it");
  }
}

json parse_body(const httplib::Request& req) {
  json j = json::parse(req.body, nullptr, false);
  if (j.is_discarded()) throw HttpError{400, "the request body is not valid JSON", "send Content-Type: application/json"};
  if (!j.is_object()) throw HttpError{400, "the request body must be a JSON object", "see /api/openapi.json"};
  return j;
}

// The image format from its first bytes; the client's file name and Content-Type are ignored.
std::string sniff_image(const std::string& bytes) {
  auto starts = [&](const char* magic, size_t n) { return bytes.size() >= n && std::memcmp(bytes.data(), magic, n) == 0; };
  if (starts("\x89PNG\r\n\x1a\n", 8)) return ".png";
  if (starts("\xff\xd8\xff", 3)) return ".jpg";
  if (starts("II*\0", 4) || starts("MM\0*", 4)) return ".tif";
  if (starts("\x76\x2f\x31\x01", 4)) return ".exr";
  return "";
}

json param_json(const ParamDecl& p) {
  json j = {{"name", p.name}, {"type", to_string(p.type)}, {"default", param_to_json(p, p.default_value.data())},
            {"scale", to_string(p.scale)}, {"searchable", p.searchable}, {"help", p.help}};
  if (p.type == ParamType::Enum) j["values"] = p.enum_values;
  else if (p.type != ParamType::Bool) j["range"] = {p.min, p.max};
  return j;
}

json shader_json(const ShaderDecl& d) {
  json j = {{"name", d.name}, {"family", d.family}, {"help", d.help}, {"params", json::array()}};
  for (const auto& p : d.params) j["params"].push_back(param_json(p));
  return j;
}

std::string content_type(const std::string& name) {
  auto ends = [&](const char* s) { return name.size() >= strlen(s) && name.compare(name.size() - strlen(s), strlen(s), s) == 0; };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".json")) return "application/json";
  if (ends(".png")) return "image/png";
  if (ends(".gif")) return "image/gif";
  if (ends(".exr")) return "image/x-exr";
  if (ends(".jpg")) return "image/jpeg";
  if (ends(".tif")) return "image/tiff";
  return "application/octet-stream";
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string base64(const std::string& in) {
  static const char* tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8 | (unsigned char)in[i + 2];
    out += {tab[v >> 18], tab[(v >> 12) & 63], tab[(v >> 6) & 63], tab[v & 63]};
  }
  if (i + 1 == in.size()) {
    const unsigned v = (unsigned char)in[i] << 16;
    out += {tab[v >> 18], tab[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8;
    out += {tab[v >> 18], tab[(v >> 12) & 63], tab[(v >> 6) & 63], '='};
  }
  return out;
}

// Compares a presented token with the server's in time independent of where they differ.
bool same_token(const std::string& given, const std::string& token) {
  unsigned char diff = given.size() == token.size() ? 0 : 1;
  for (size_t i = 0; i < given.size(); ++i) diff |= static_cast<unsigned char>(given[i] ^ token[i % token.size()]);
  return diff == 0;
}

}  // namespace

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

struct Server::Impl {
  ServerOptions options;
  std::unique_ptr<JobStore> store;
  std::unique_ptr<JobRunner> runner;
  httplib::Server http;
  int port = 0;
  socket_t listen_socket = -1;
  std::mutex render_mutex;  // UI renders one at a time (bounded memory), between the job's launches
  // UI renders waiting or running: a match job pauses between its batches while it is non-zero.
  std::shared_ptr<std::atomic<int>> ui_renders = std::make_shared<std::atomic<int>>(0);
  std::map<std::string, const std::string*> assets;
  fs::path synth_cache;
  std::mutex retention_mutex;
  PruneReport last_prune;
  int jobs_pruned = 0;

  explicit Impl(ServerOptions o) : options(std::move(o)) {
    if (!is_loopback(options.bind) && options.token.empty())
      throw UsageError("binding to '" + options.bind + "' (not loopback) needs a token",
                       "pass --token SECRET; clients send 'Authorization: Bearer SECRET'");
    if (options.data.empty()) throw UsageError("no data folder", "pass --data DIR");
    store = std::make_unique<JobStore>(options.data);
    RunnerOptions ro;
    ro.catalog = options.catalog;
    ro.workers = options.workers;
    ro.queue_limit = options.queue_limit;
    ro.preview_size = options.preview_size;
    synth_cache = options.data / "cache" / "synth";
    std::error_code ec;
    fs::create_directories(synth_cache, ec);
    ro.synth_cache = synth_cache;
    if (options.ui_render_priority) ro.ui_renders = ui_renders;
    ro.on_finished = [this](const std::string&) { prune(); };
    runner = std::make_unique<JobRunner>(*store, ro);
    prune();
    for (const auto& [path, content] : embedded::web_files()) assets[path] = &content;
    routes();
  }
  // The workers stop first: a job finishing now still prunes with the members below intact.
  ~Impl() { runner.reset(); }

  // The retention policy, after every finished job and at start-up.
  void prune() {
    Retention r;
    r.keep_jobs = options.keep_jobs;
    r.max_bytes = options.max_data_bytes;
    const PruneReport report = store->prune(r, synth_cache, [this](const std::string& id) {
      return runner && runner->live(id) != nullptr;
    });
    std::lock_guard lock(retention_mutex);
    last_prune = report;
    jobs_pruned += report.jobs_deleted;
  }

  ImageLimits upload_limits() const {
    ImageLimits l;
    l.max_dimension = options.max_upload_dimension;
    l.max_pixels = options.max_upload_pixels;
    return l;
  }

  // Checks an uploaded image (format by content, dimensions before decoding, a full decode for
  // truncated files) in the data folder's tmp/ under a server-chosen name; returns that path.
  fs::path accept_image(const std::string& bytes, const std::string& what, Image* decoded = nullptr, int min_side = 32) {
    if (bytes.empty()) throw HttpError{400, what + " is empty", "send a PNG, JPEG, TIFF or EXR file"};
    const std::string ext = sniff_image(bytes);
    if (ext.empty()) throw HttpError{415, what + " is not a PNG, JPEG, TIFF or EXR image", "send an image file"};
    static std::atomic<uint64_t> counter{0};
    const fs::path tmp = store->data_dir() / "tmp" / fmt::format("upload-{}-{}{}", port, counter++, ext);
    {
      std::ofstream out(tmp, std::ios::binary);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      if (!out) throw Error("cannot store the upload", "check the free space of the --data folder");
    }
    try {
      Image img;
      try {
        img = load_image(tmp, upload_limits());
      } catch (const Error& e) {
        // The message names the server's temporary file: keep only the reason.
        std::string reason = e.message();
        if (const size_t at = reason.find("': "); at != std::string::npos) reason = reason.substr(at + 3);
        throw HttpError{400, what + " cannot be read: " + reason, e.hint()};
      }
      if (std::min(img.width, img.height) < min_side)
        throw HttpError{400, fmt::format("{} is {}x{} pixels; a texture needs at least 32 on each side", what, img.width, img.height),
                        "send a larger image"};
      if (decoded) *decoded = std::move(img);
    } catch (...) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw;
    }
    return tmp;
  }

  const std::string* upload_field(const httplib::Request& req, const std::string& name) {
    if (!req.is_multipart_form_data() || !req.has_file(name)) return nullptr;
    return &req.files.find(name)->second.content;
  }

  void require_catalog() {
    if (options.catalog.empty() || !fs::exists(options.catalog))
      throw HttpError{503, "the server has no catalogue", "start it with --db CATALOG (proctex catalog build)"};
  }

  // A match against samples of another version of a shader's source would silently search the
  // old shader (as the CLI refuses it, catalog::require_current_sources): 409 before any job runs.
  void require_current_catalog() {
    require_catalog();
    try {
      catalog::Store catalogue(options.catalog, catalog::Store::Access::Read);
      catalog::require_current_sources(catalogue);
    } catch (const Error& e) {
      throw HttpError{409, e.what(), e.hint()};
    }
  }

  JobRecord job_or_404(const std::string& id) {
    auto j = store->get(id);
    if (!j) throw HttpError{404, "no job '" + id + "'", "list jobs with GET /api/jobs"};
    return *j;
  }

  json job_status(const JobRecord& r) {
    json j = r.to_json();
    if (auto live = runner->live(r.id)) {
      std::lock_guard lock(live->mutex);
      j["state"] = live->state;
      j["progress"] = live->progress;
      j["preview_version"] = live->preview_version;
    }
    return j;
  }

  void routes() {
    auto& s = http;
    s.set_payload_max_length(options.max_upload_bytes);
    // cpp-httplib 0.11 listens with a backlog of 5: a burst of new connections (50 pollers) then
    // waits for SYN retransmits, seconds each. Remember the socket to listen again with a
    // larger backlog after bind().
    s.set_socket_options([this](socket_t sock) {
      httplib::default_socket_options(sock);
      listen_socket = sock;
    });
    const int threads = options.threads;
    s.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    // Pollers keep their connection (each holds an HTTP thread while it does); new connections
    // queue in cpp-httplib's accept backlog of 5.
    s.set_keep_alive_max_count(1000);
    s.set_keep_alive_timeout(5);
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      if (options.token.empty()) return httplib::Server::HandlerResponse::Unhandled;
      const std::string bearer = "Bearer " + options.token;
      if (same_token(req.get_header_value("Authorization"), bearer) || same_token(req.get_param_value("token"), options.token))
        return httplib::Server::HandlerResponse::Unhandled;
      send_error(res, 401, "missing or wrong bearer token", "send 'Authorization: Bearer TOKEN' (or ?token=TOKEN)");
      return httplib::Server::HandlerResponse::Handled;
    });
    s.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
      if (!res.body.empty()) return;
      if (res.status == 413) send_error(res, 413, "the request body is too large", "see max_upload_bytes in GET /api/health");
      else if (res.status == 404) send_error(res, 404, "no such endpoint: " + req.method + " " + req.path, "see /api/openapi.json");
      else send_error(res, res.status, "HTTP error " + std::to_string(res.status));
    });
    s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr) {
      send_error(res, 500, "internal error", "this is a bug; please report it");
    });

    // Web UI and API description.
    auto page = [this](const std::string& file) {
      return [this, file](const httplib::Request&, httplib::Response& res) {
        res.set_content(*assets.at("web/" + file), content_type(file));
      };
    };
    s.Get("/", page("index.html"));
    s.Get("/library", page("library.html"));
    s.Get("/morph", page("morph.html"));
    s.Get("/synth", page("synth.html"));
    s.Get(R"(/static/([a-z0-9_\-]+\.(?:js|css|html)))", [this](const httplib::Request& req, httplib::Response& res) {
      auto it = assets.find("web/" + req.matches[1].str());
      if (it == assets.end()) return send_error(res, 404, "no such file", "");
      res.set_content(*it->second, content_type(it->first));
    });
    s.Get("/api/openapi.json", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(*assets.at("server/openapi.json"), "application/json");
    });

    s.Get("/api/health", [this](const httplib::Request&, httplib::Response& res) {
      guarded(res, [&] {
        send_json(res, {{"status", "ok"}, {"version", kVersion}, {"device", ocl::Runtime::instance().device().name},
                        {"catalog", options.catalog.string()}, {"catalog_present", fs::exists(options.catalog)},
                        {"jobs", runner->stats()},
                        {"limits", {{"max_upload_bytes", options.max_upload_bytes},
                                    {"max_upload_dimension", options.max_upload_dimension},
                                    {"max_upload_pixels", options.max_upload_pixels},
                                    {"max_render_size", options.max_render_size},
                                    {"max_synth_size", options.max_synth_size},
                                    {"synth_exemplar_side", {synth::kMinExemplarSide, synth::kMaxExemplarSide}}}},
                        {"retention", retention_json()}});
      });
    });

    s.Get("/api/shaders", [](const httplib::Request&, httplib::Response& res) {
      guarded(res, [&] {
        json out = json::array();
        for (const auto& d : ShaderLibrary::builtin().shaders()) out.push_back(shader_json(d));
        send_json(res, out);
      });
    });
    s.Get(R"(/api/shaders/([A-Za-z0-9_\-]+))", [](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        const ShaderDecl* d = ShaderLibrary::builtin().find(req.matches[1].str());
        if (!d) throw HttpError{404, "no shader '" + req.matches[1].str() + "'", "list them with GET /api/shaders"};
        send_json(res, shader_json(*d));
      });
    });

    s.Post("/api/render", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { render(req, res); });
    });
    s.Post("/api/compare", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { compare(req, res); });
    });
    s.Get("/api/catalog", [this](const httplib::Request&, httplib::Response& res) {
      guarded(res, [&] {
        require_catalog();
        send_json(res, catalog::info(options.catalog));
      });
    });

    // Jobs.
    s.Post("/api/jobs/match", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { create_match(req, res); });
    });
    s.Post("/api/jobs/morph", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { create_morph(req, res); });
    });
    s.Post("/api/jobs/synth", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { create_synth(req, res); });
    });
    s.Get("/api/jobs", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        json out = json::array();
        for (const auto& r : store->list(100)) out.push_back(job_status(r));
        send_json(res, {{"jobs", out}, {"queue", runner->stats()}});
      });
    });
    s.Get(R"(/api/jobs/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { send_json(res, job_status(job_or_404(req.matches[1].str()))); });
    });
    s.Get(R"(/api/jobs/([^/]+)/result)", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        const JobRecord r = job_or_404(req.matches[1].str());
        if (r.result.is_null())
          throw HttpError{409, "job " + r.id + " has no result (state: " + r.state + ")",
                          r.state == "queued" || r.state == "running" ? "wait for it (GET /api/jobs/ID/events)" : "re-run it: POST /api/jobs/ID/retry"};
        send_json(res, r.result);
      });
    });
    s.Get(R"(/api/jobs/([^/]+)/preview)", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        const JobRecord r = job_or_404(req.matches[1].str());
        if (auto live = runner->live(r.id)) {
          std::lock_guard lock(live->mutex);
          if (!live->preview_png.empty()) return res.set_content(live->preview_png, "image/png");
        }
        throw HttpError{404, "no preview yet", "previews appear once the refinement starts"};
      });
    });
    s.Get(R"(/api/jobs/([^/]+)/files/([a-z0-9_]+(?:/[a-z0-9_]+)?\.(?:png|json|gif|jpg|tif|exr)))",
          [this](const httplib::Request& req, httplib::Response& res) {
            guarded(res, [&] {
              const JobRecord r = job_or_404(req.matches[1].str());
              const std::string name = req.matches[2].str();
              const fs::path p = store->job_dir(r.id) / name;  // name: [a-z0-9_] segments only, no '..'
              std::error_code ec;
              if (!fs::is_regular_file(p, ec)) throw HttpError{404, "job " + r.id + " has no file '" + name + "'", "see the result's 'files'"};
              res.set_content(read_file(p), content_type(name));
              if (req.has_param("download"))
                res.set_header("Content-Disposition", "attachment; filename=\"" + r.id.substr(0, 8) + "-" +
                                                          name.substr(name.rfind('/') + 1) + "\"");
            });
          });
    s.Post(R"(/api/jobs/([^/]+)/cancel)", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        const JobRecord r = job_or_404(req.matches[1].str());
        if (!runner->cancel(r.id))
          throw HttpError{409, "job " + r.id + " is " + r.state + ", not queued or running", "nothing to cancel"};
        runner->wait(r.id, 120.0);
        const JobRecord after = job_or_404(r.id);
        json j = job_status(after);
        j["result"] = after.result;
        send_json(res, j);
      });
    });
    s.Post(R"(/api/jobs/([^/]+)/retry)", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] {
        const JobRecord r = job_or_404(req.matches[1].str());
        if (r.state == "queued" || r.state == "running" || r.state == "done")
          throw HttpError{409, "job " + r.id + " is " + r.state, "only interrupted, failed or cancelled jobs are re-run"};
        if (!runner->has_room()) throw QueueFull("the job queue is full");
        store->set_queued(r.id);
        runner->enqueue(r.id);
        send_json(res, job_status(job_or_404(r.id)), 202);
      });
    });
    s.Get(R"(/api/jobs/([^/]+)/events)", [this](const httplib::Request& req, httplib::Response& res) {
      guarded(res, [&] { events(job_or_404(req.matches[1].str()), res); });
    });
  }

  void render(const httplib::Request& req, httplib::Response& res) {
    const json body = parse_body(req);
    if (!body.contains("spec")) throw HttpError{400, "missing 'spec'", "send {\"spec\": {\"shader\": \"bricks\"}, \"size\": 256}"};
    const TextureSpec spec = body["spec"].is_string() ? parse_spec_argument(body["spec"].get<std::string>())
                                                      : TextureSpec::from_json(body["spec"]);
    const ShaderDecl& decl = ShaderLibrary::builtin().get(spec.shader);
    resolve(decl, spec);  // unknown parameters, wrong types, out-of-range values: UsageError
    auto dim = [&](const char* name, int fallback) {
      if (!body.contains(name)) return fallback;
      if (!body[name].is_number_integer()) throw HttpError{400, std::string("'") + name + "' must be a whole number", ""};
      const int64_t v = body[name].get<int64_t>();
      if (v < 1 || v > options.max_render_size)
        throw HttpError{400, fmt::format("'{}' is {}, outside [1, {}]", name, v, options.max_render_size),
                        "render large images with the CLI: proctex render --size"};
      return static_cast<int>(v);
    };
    const int size = dim("size", 256);
    RenderSettings rs;
    rs.width = dim("width", size);
    rs.height = dim("height", size);
    rs.supersample = body.value("supersample", 1);
    if (rs.supersample < 1 || rs.supersample > 4) throw HttpError{400, "'supersample' must be 1-4", ""};
    const std::string format = body.value("format", "png");
    if (format != "png" && format != "exr") throw HttpError{400, "'format' must be png or exr", ""};
    const auto t0 = Clock::now();
    auto t_locked = t0;
    Image img;
    // Counted from here to the encoded image: a running match pauses at its next batch boundary,
    // so this render waits for at most the batch in flight and then has the device and the cores
    // (render, encoding) to itself.
    struct Pending {
      std::atomic<int>& n;
      explicit Pending(std::atomic<int>& c) : n(c) { ++n; }
      ~Pending() { --n; }
    } pending(*ui_renders);
    {
      std::lock_guard lock(render_mutex);
      t_locked = Clock::now();
      img = Renderer().render(spec, rs);
    }
    const auto t_rendered = Clock::now();
    const std::string bytes = encode_png(img, store->data_dir() / "tmp", "." + format);
    const auto ms = [](Clock::time_point a, Clock::time_point b) { return 1000 * std::chrono::duration<double>(b - a).count(); };
    const auto t_end = Clock::now();
    res.set_header("X-Render-Milliseconds", fmt::format("{:.1f}", ms(t0, t_end)));
    // Where the time went (browser dev tools show it): another UI render, the device (the job's
    // batch in flight + this render), the PNG/EXR encoding.
    res.set_header("Server-Timing", fmt::format("lock;dur={:.1f}, render;dur={:.1f}, encode;dur={:.1f}", ms(t0, t_locked),
                                                ms(t_locked, t_rendered), ms(t_rendered, t_end)));
    res.set_content(bytes, format == "png" ? "image/png" : "image/x-exr");
  }

  void compare(const httplib::Request& req, httplib::Response& res) {
    const std::string* a = upload_field(req, "a");
    const std::string* b = upload_field(req, "b");
    if (!a || !b) throw HttpError{400, "compare needs two images, form fields 'a' and 'b'", "curl -F a=@one.png -F b=@two.png"};
    Image ia, ib;
    const fs::path pa = accept_image(*a, "image 'a'", &ia);
    const fs::path pb = accept_image(*b, "image 'b'", &ib);
    std::error_code ec;
    fs::remove(pa, ec);
    fs::remove(pb, ec);
    const metrics::Metric& m = metrics::default_metric();
    const auto fa = m.features(ia, metrics::kDefaultResolution);
    const auto fb = m.features(ib, metrics::kDefaultResolution);
    json j = {{"metric", m.id()}, {"version", m.version()}, {"similarity", m.similarity(fa, fb)}, {"components", json::object()}};
    if (const auto* composite = dynamic_cast<const metrics::CompositeMetric*>(&m))
      for (const auto& [name, value] : composite->breakdown(fa.values, fb.values)) j["components"][name] = value;
    send_json(res, j);
  }

  void create_match(const httplib::Request& req, httplib::Response& res) {
    require_current_catalog();
    json match_opts = json::object();
    const std::string* photo = upload_field(req, "photo");
    std::string raw;
    if (req.is_multipart_form_data()) {
      if (!photo) throw HttpError{400, "no 'photo' field in the form", "curl -F photo=@brick.png"};
      if (req.has_file("options")) {
        match_opts = json::parse(req.get_file_value("options").content, nullptr, false);
        if (match_opts.is_discarded()) throw HttpError{400, "'options' is not valid JSON", "send -F 'options={\"budget\": \"20s\"}'"};
      }
    } else {
      photo = &req.body;  // the image as the body
      if (req.has_param("options")) {
        match_opts = json::parse(req.get_param_value("options"), nullptr, false);
        if (match_opts.is_discarded()) throw HttpError{400, "'options' is not valid JSON", ""};
      }
    }
    match_options_from_json(match_opts);  // rejects bad options before anything is stored
    if (!runner->has_room()) throw QueueFull("the job queue is full");
    const fs::path tmp = accept_image(*photo, "the photo");
    const JobRecord job = store->create("match", {{"options", match_opts}, {"input", "input" + tmp.extension().string()},
                                                  {"upload_bytes", photo->size()},
                                                  {"max_dimension", options.max_upload_dimension},
                                                  {"max_pixels", options.max_upload_pixels}});
    std::error_code ec;
    fs::rename(tmp, store->job_dir(job.id) / ("input" + tmp.extension().string()), ec);
    if (ec) {
      store->finish(job.id, "failed", nullptr, "could not store the upload");
      throw Error("cannot store the upload: " + ec.message(), "check the --data folder");
    }
    try {
      runner->enqueue(job.id);
    } catch (const QueueFull&) {
      store->finish(job.id, "failed", nullptr, "queue full");
      throw;
    }
    res.set_header("Location", "/api/jobs/" + job.id);
    send_json(res, job_status(job_or_404(job.id)), 202);
  }

  void create_morph(const httplib::Request& req, httplib::Response& res) {
    require_catalog();
    json body = parse_body(req);
    if (!body.contains("keys") || !body["keys"].is_array() || body["keys"].size() < 2)
      throw HttpError{400, "a morph needs 'keys': two or more specs", "send {\"keys\": [{\"shader\": \"stripes\"}, ...]}"};
    if (body["keys"].size() > 16) throw HttpError{400, "at most 16 keys", ""};
    json keys = json::array();
    for (const auto& k : body["keys"]) {
      json spec = k;
      if (k.is_object() && k.contains("job")) {  // a match result as a key
        const JobRecord r = job_or_404(k["job"].is_string() ? k["job"].get<std::string>() : "");
        if (r.kind != "match" || r.result.is_null()) throw HttpError{400, "job " + r.id + " has no match result", ""};
        spec = r.result["spec"];
      } else if (k.is_string()) {
        spec = parse_spec_argument(k.get<std::string>()).to_json();
      }
      const TextureSpec ts = TextureSpec::from_json(spec);
      resolve(ShaderLibrary::builtin().get(ts.shader), ts);
      keys.push_back(ts.to_json());
    }
    auto num = [&](const char* name, int fallback, int lo, int hi) {
      if (!body.contains(name)) return fallback;
      if (!body[name].is_number_integer()) throw HttpError{400, std::string("'") + name + "' must be a whole number", ""};
      const int64_t v = body[name].get<int64_t>();
      if (v < lo || v > hi) throw HttpError{400, fmt::format("'{}' is {}, outside [{}, {}]", name, v, lo, hi), ""};
      return static_cast<int>(v);
    };
    json params = {{"keys", keys}, {"frames", num("frames", 24, 2, 480)}, {"size", num("size", 256, 16, 1024)},
                   {"fps", num("fps", 12, 1, 60)}, {"dissolve", num("dissolve", 0, 0, 24)}};
    if (!runner->has_room()) throw QueueFull("the job queue is full");
    const JobRecord job = store->create("morph", params);
    runner->enqueue(job.id);
    res.set_header("Location", "/api/jobs/" + job.id);
    send_json(res, job_status(job_or_404(job.id)), 202);
  }

  json retention_json() {
    std::lock_guard lock(retention_mutex);
    return {{"keep_jobs", options.keep_jobs}, {"max_data_bytes", options.max_data_bytes},
            {"data_bytes", last_prune.bytes}, {"finished_jobs", last_prune.finished_jobs},
            {"jobs_pruned", jobs_pruned}};
  }

  // POST /api/jobs/synth: multipart `exemplar` (+ `options` JSON), or a JSON body of options with
  // "from_job" (reuse an earlier job's uploaded image), or the image as the body (?options=).
  void create_synth(const httplib::Request& req, httplib::Response& res) {
    json opts = json::object();
    const std::string* upload = nullptr;
    auto parse_options = [](const std::string& text) {
      json j = json::parse(text, nullptr, false);
      if (j.is_discarded()) throw HttpError{400, "'options' is not valid JSON", "send -F 'options={\"size\": 512}'"};
      return j;
    };
    if (req.is_multipart_form_data()) {
      upload = upload_field(req, "exemplar");
      if (req.has_file("options")) opts = parse_options(req.get_file_value("options").content);
      if (!upload && !opts.contains("from_job"))
        throw HttpError{400, "no 'exemplar' field in the form", "curl -F exemplar=@rocks.png -F 'options={\"size\": 512}'"};
    } else if (!sniff_image(req.body).empty()) {
      upload = &req.body;  // the image as the body
      if (req.has_param("options")) opts = parse_options(req.get_param_value("options"));
    } else {
      opts = parse_body(req);  // JSON options naming an earlier job's upload
      if (!opts.contains("from_job"))
        throw HttpError{400, "no exemplar: upload one (form field 'exemplar') or name an earlier job's with \"from_job\"",
                        "curl -F exemplar=@rocks.png $URL/api/jobs/synth, or -d '{\"from_job\": \"ID\"}'"};
    }
    const SynthJobOptions so = synth_options_from_json(opts, options.max_synth_size);
    if (upload && !so.from_job.empty())
      throw HttpError{400, "both an uploaded exemplar and \"from_job\"", "send one of them"};
    if (!runner->has_room()) throw QueueFull("the job queue is full");
    fs::path tmp;
    Image image;
    size_t bytes = 0;
    if (upload) {
      tmp = accept_image(*upload, "the exemplar", &image, 1);
      bytes = upload->size();
    } else {
      const JobRecord src = job_or_404(so.from_job);
      const std::string input = src.params.value("input", "");
      std::error_code ec;
      const fs::path from = store->job_dir(src.id) / input;
      if (input.empty() || !fs::is_regular_file(from, ec))
        throw HttpError{400, "job " + src.id + " has no uploaded image", "name a match or synth job (\"from_job\")"};
      tmp = accept_image(read_file(from), "job " + src.id + "'s image", &image, 1);
      bytes = fs::file_size(tmp, ec);
    }
    try {
      const auto size = synth_exemplar_size(so, image.width, image.height);
      resolve_synth_options(so, size[0], size[1]);  // randomness per level, period: as the job will
    } catch (...) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw;
    }
    json params = {{"options", so.to_json()}, {"input", "input" + tmp.extension().string()}, {"upload_bytes", bytes},
                   {"max_dimension", options.max_upload_dimension}, {"max_pixels", options.max_upload_pixels},
                   {"max_size", options.max_synth_size}};
    const JobRecord job = store->create("synth", params);
    std::error_code ec;
    fs::rename(tmp, store->job_dir(job.id) / ("input" + tmp.extension().string()), ec);
    if (ec) {
      fs::remove(tmp, ec);
      store->finish(job.id, "failed", nullptr, "could not store the upload");
      throw Error("cannot store the upload: " + ec.message(), "check the --data folder");
    }
    try {
      runner->enqueue(job.id);
    } catch (const QueueFull&) {
      store->finish(job.id, "failed", nullptr, "queue full");
      throw;
    }
    res.set_header("Location", "/api/jobs/" + job.id);
    send_json(res, job_status(job_or_404(job.id)), 202);
  }

  // Server-Sent Events: "progress" at least 4 times a second while the job runs (with a base64
  // PNG preview whenever the best so far changed), then one "done" event with the final status.
  void events(const JobRecord& job, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    const std::string id = job.id;
    auto live = runner->live(id);
    auto sent_version = std::make_shared<int>(-1);
    auto last_sent = std::make_shared<Clock::time_point>();
    res.set_chunked_content_provider("text/event-stream", [this, id, live, sent_version, last_sent](size_t, httplib::DataSink& sink) {
      auto send = [&](const std::string& event, const json& data) {
        const std::string text = "event: " + event + "\ndata: " + data.dump() + "\n\n";
        return sink.write(text.data(), text.size());
      };
      if (live) {
        json data;
        bool finished;
        // At most 10 events a second (a match reports every render batch), at least 4.
        const auto next = *last_sent + std::chrono::milliseconds(100);
        if (Clock::now() < next) std::this_thread::sleep_until(next);
        {
          std::unique_lock lock(live->mutex);
          live->changed.wait_for(lock, std::chrono::milliseconds(150));
          finished = live->state != "queued" && live->state != "running";
          data = {{"state", live->state}, {"progress", live->progress}};
          if (live->preview_version != *sent_version && !live->preview_png.empty()) {
            data["preview"] = "data:image/png;base64," + base64(live->preview_png);
            *sent_version = live->preview_version;
          }
        }
        *last_sent = Clock::now();
        if (!send("progress", data)) return false;
        if (!finished) return true;
      }
      // Finished (now or before the stream opened): the stored status, result included.
      if (auto r = store->get(id)) {
        json j = job_status(*r);
        j["state"] = r->state;
        j["result"] = r->result;
        send("done", j);
      }
      sink.done();
      return true;
    });
  }
};

Server::Server(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  // Jobs interrupted by the previous process stay "interrupted" until a client re-runs them.
}

Server::~Server() {
  impl_->http.stop();
}

int Server::bind() {
  auto& o = impl_->options;
  if (o.port == 0) impl_->port = impl_->http.bind_to_any_port(o.bind);
  else impl_->port = impl_->http.bind_to_port(o.bind, o.port) ? o.port : -1;
  if (impl_->port < 0)
    throw Error(fmt::format("cannot listen on {}:{}", o.bind, o.port), "the port is taken or the address is not this machine's; try --port 0");
  if (impl_->listen_socket >= 0) ::listen(impl_->listen_socket, SOMAXCONN);  // a larger accept backlog
  return impl_->port;
}

void Server::run() { impl_->http.listen_after_bind(); }
void Server::stop() { impl_->http.stop(); }

std::string Server::url() const {
  const std::string host = impl_->options.bind.find(':') != std::string::npos ? "[" + impl_->options.bind + "]" : impl_->options.bind;
  return fmt::format("http://{}:{}/", host == "0.0.0.0" ? "localhost" : host, impl_->port);
}

}  // namespace proctex::server
