#pragma once
// The catalogue file: SQLite with the conventions of DESIGN.md.
//   - schema version in PRAGMA user_version, forward migrations (kSchemaVersion is the newest);
//     a file from a newer proctex is refused before anything is written;
//   - PRAGMA application_id marks proctex catalogues; other SQLite files are refused;
//   - WAL journal, foreign keys on, statements always parameterised;
//   - every shader is written in one transaction (delete the old rows, insert the new ones), so a
//     reader or a killed build never sees half a shader;
//   - float vectors are little-endian float32 BLOBs.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/sampling.h"

namespace proctex::catalog {

inline constexpr int kSchemaVersion = 3;
// Oldest schema a reader accepts without migrating (v2 only added the jumps table, v3 the
// shader_costs table, so a v1 file is read as a catalogue without jump edges or measured costs;
// opening it for writing migrates it).
inline constexpr int kMinReadableVersion = 1;
inline constexpr int kApplicationId = 0x50545843;  // "PTXC"

namespace sql {
class Connection;
}

// One row of the shaders table without the samples (info, incremental checks).
struct ShaderSummary {
  std::string name, family, source_hash, settings_hash, content_hash, mode, metric, device, built_at,
      proctex_version;
  int metric_version = 0;
  int resolution = 0;
  int samples = 0, pruned = 0;
  uint64_t seed = 0;
  double build_seconds = 0;
  double cpu_seconds = -1;  // measured CPU seconds of the build (schema v3); -1: not recorded
  std::optional<Coverage> coverage;
  nlohmann::json settings, stats;
};

// A jump edge between two shaders (thesis section 5.3): one parameter vector per shader whose
// renders look alike, found by `proctex catalog link` (transform/jumps.h). The features are stored
// so that the joined graph of a morph needs no render; they are tagged like sample features.
struct JumpEdge {
  std::string shader_a, shader_b;  // shader_a < shader_b by name
  std::vector<float> packed_a, packed_b;
  uint32_t seed_a = 0, seed_b = 0;
  metrics::Features features_a, features_b;
  double similarity = 0;  // edge weight: S(p_a(packed_a), p_b(packed_b))
  nlohmann::json info = nlohmann::json::object();  // how it was found (start, rounds, renders)
};

class Store {
 public:
  enum class Access { Read, Write };
  // Write: creates the file (and its folder) if missing, checks it, migrates it to kSchemaVersion,
  // switches to WAL. Read: the file must exist and be a current catalogue; nothing is written.
  // Throws proctex::Error for a missing/unwritable path, a non-SQLite or corrupt file, a file
  // from a newer schema, a non-proctex database.
  Store(const std::filesystem::path& path, Access access);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  const std::filesystem::path& path() const { return path_; }
  int schema_version() const;

  std::vector<ShaderSummary> shaders();
  std::optional<ShaderSummary> summary(const std::string& shader);
  // The complete shader catalogue (samples, features, edges, graphs); throws if absent.
  ShaderCatalogue load(const std::string& shader, bool with_edges = true);

  // Replaces the shader's rows in one transaction. cpu_seconds >= 0 records the measured build
  // cost (shader_costs, schema v3) that balances shards.
  void write(const ShaderCatalogue& cat, const std::string& device, double seconds, double cpu_seconds = -1);
  void remove(const std::string& shader);

  // Jump edges (schema v2). write_jumps replaces every jump edge of the pair {a, b} in one
  // transaction (both shaders must be catalogued). Rebuilding or removing a shader deletes its
  // jump edges (they were found from its old samples). jumps() returns the edges touching
  // `shader` (all when empty), none for a v1 file.
  void write_jumps(const std::string& a, const std::string& b, const std::vector<JumpEdge>& jumps);
  std::vector<JumpEdge> jumps(const std::string& shader = {});

  // Build log: one row per `catalog build` / `catalog merge` run.
  int64_t begin_build(const nlohmann::json& info);
  void finish_build(int64_t id, const nlohmann::json& result);
  nlohmann::json builds();

  // PRAGMA integrity_check + foreign_key_check; empty when healthy, else the problems.
  std::vector<std::string> integrity_problems();
  // Structural checks per shader (edge count, feature lengths, pruned subset, content hash).
  std::vector<std::string> consistency_problems(const std::string& shader);

 private:
  void check_and_migrate(bool writable);
  std::filesystem::path path_;
  std::unique_ptr<sql::Connection> db_;
};

}  // namespace proctex::catalog
