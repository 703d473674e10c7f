#pragma once
// A catalogue shared by the tests of one build tree: ctest runs every test in its own process, so
// a per-process fixture would rebuild it for each test; instead every process runs the incremental
// build under a file lock, which builds it the first time and skips every unchanged shader
// afterwards (a shader source or metric change rebuilds just what changed).
#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "catalog/catalog.h"
#include "catalog/store.h"

namespace proctex::testing {

struct CatalogueGroup {
  std::vector<std::string> shaders;
  int samples = 0;
};

// Builds (first time) or checks <build>/tests/<name> with each group's shaders at its sample count.
inline std::filesystem::path locked_catalogue(const std::filesystem::path& binary, const std::string& name,
                                              const std::vector<CatalogueGroup>& groups, uint64_t seed) {
  // `binary` is <build>/cli/proctex: keep the catalogue in <build>/tests.
  const std::filesystem::path dir = binary.parent_path().parent_path() / "tests";
  std::filesystem::create_directories(dir);
  const std::filesystem::path db = dir / name;
  const std::string lock_path = db.string() + ".lock";
  const int fd = ::open(lock_path.c_str(), O_CREAT | O_RDWR, 0644);
  if (fd < 0 || ::flock(fd, LOCK_EX) != 0) throw std::runtime_error("cannot lock " + lock_path);
  try {
    for (const auto& group : groups) {
      catalog::BuildOptions o;
      o.db = db;
      o.shaders = group.shaders;
      o.settings.samples = group.samples;
      o.settings.probes = 0;
      o.seed = seed;
      o.jobs = 2;
      catalog::build(o);
    }
    catalog::Store(db, catalog::Store::Access::Write);  // checkpoint the WAL into the main file
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);  // releases the lock
  return db;
}

}  // namespace proctex::testing
