// Finds and loads the OpenImageIO module (proctex_image_oiio.so) on first use.
// Search order: $PROCTEX_IMAGE_BACKEND (a file), beside the executable, ../lib/proctex/ from the
// executable (the install layout), the install prefix configured at build time, the build tree.
#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <system_error>

#include "core/error.h"
#include "image/backend.h"

namespace proctex {
namespace fs = std::filesystem;
namespace {

constexpr const char* kModuleName = "proctex_image_oiio.so";

fs::path executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

std::vector<fs::path> candidates() {
  std::vector<fs::path> list;
  if (const char* env = std::getenv("PROCTEX_IMAGE_BACKEND"); env && *env) {
    list.emplace_back(env);
    return list;  // an explicit choice is not second-guessed
  }
  if (const fs::path dir = executable_dir(); !dir.empty()) {
    list.push_back(dir / kModuleName);
    list.push_back(dir.parent_path() / "lib" / "proctex" / kModuleName);
  }
#ifdef PROCTEX_IMAGE_BACKEND_INSTALL_PATH
  list.emplace_back(PROCTEX_IMAGE_BACKEND_INSTALL_PATH);
#endif
#ifdef PROCTEX_IMAGE_BACKEND_BUILD_PATH
  list.emplace_back(PROCTEX_IMAGE_BACKEND_BUILD_PATH);
#endif
  return list;
}

struct Loaded {
  backend::Backend* backend = nullptr;
  fs::path path;
  std::string problem;  // why loading failed (when backend is null)
};

std::atomic<bool> g_loaded{false};

Loaded load_module() {
  Loaded result;
  std::string tried;
  for (const fs::path& p : candidates()) {
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) {
      tried += (tried.empty() ? "" : ", ") + p.string();
      continue;
    }
    // RTLD_NOW: a missing dependency shows here, not as a crash later. RTLD_LOCAL: OpenImageIO's
    // libraries do not join the global symbol scope of the process.
    void* handle = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = ::dlerror();
      result.problem = "cannot load " + p.string() + ": " + (why ? why : "unknown dlopen error");
      return result;
    }
    using Factory = backend::Backend* (*)();
    auto factory = reinterpret_cast<Factory>(::dlsym(handle, "proctex_image_backend_create"));
    backend::Backend* b = factory ? factory() : nullptr;
    if (!b || b->interface_version() != backend::kInterfaceVersion) {
      result.problem = p.string() + " is not a proctex image module of this version";
      return result;
    }
    result.backend = b;
    result.path = p;
    g_loaded = true;
    return result;  // never unloaded: OpenImageIO keeps threads and caches until exit
  }
  result.problem = "proctex_image_oiio.so not found (looked in " + tried + ")";
  return result;
}

const Loaded& loaded() {
  static const Loaded once = load_module();  // thread-safe initialisation
  return once;
}

}  // namespace

namespace backend {
Backend& get(const std::string& purpose) {
  const Loaded& l = loaded();
  if (!l.backend) {
    throw Error(purpose + ": the OpenImageIO module is unavailable: " + l.problem,
                "EXR, TIFF, GIF and JPEG output need proctex_image_oiio.so beside the proctex binary, in "
                "../lib/proctex/, or named by PROCTEX_IMAGE_BACKEND; rebuild or reinstall proctex");
  }
  return *l.backend;
}
}  // namespace backend

bool image_backend_loaded() { return g_loaded; }

fs::path image_backend_path() {
  for (const fs::path& p : candidates()) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p;
  }
  return {};
}

}  // namespace proctex
