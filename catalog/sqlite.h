#pragma once
// A thin RAII layer over the SQLite C API: one connection, prepared statements with bound
// parameters (never string-built SQL), errors as proctex::Error naming the file.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace proctex::catalog::sql {

class Statement;

class Connection {
 public:
  enum class Mode { ReadOnly, ReadWrite, Create };
  // Opens `path`; throws proctex::Error (with a hint) when SQLite cannot open it.
  Connection(const std::filesystem::path& path, Mode mode);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Runs SQL without parameters (schema, pragmas, BEGIN/COMMIT).
  void exec(const std::string& sql);
  Statement prepare(const std::string& sql);
  // First column of the first row of a parameterless query as integer/text.
  int64_t scalar_int(const std::string& sql);
  std::string scalar_text(const std::string& sql);

  const std::filesystem::path& path() const { return path_; }
  sqlite3* handle() { return db_; }
  [[noreturn]] void fail(int code, const std::string& what);

 private:
  sqlite3* db_ = nullptr;
  std::filesystem::path path_;
};

// A prepared statement; bind parameters 1-based, step() until it returns false.
class Statement {
 public:
  Statement(Connection& db, sqlite3_stmt* stmt) : db_(&db), stmt_(stmt) {}
  ~Statement();
  Statement(Statement&& o) noexcept : db_(o.db_), stmt_(o.stmt_) { o.stmt_ = nullptr; }
  Statement(const Statement&) = delete;

  Statement& bind(int i, int64_t v);
  Statement& bind(int i, int v) { return bind(i, static_cast<int64_t>(v)); }
  Statement& bind(int i, double v);
  Statement& bind(int i, const std::string& v);
  Statement& bind(int i, const char* v) { return bind(i, std::string(v)); }
  Statement& bind_blob(int i, std::span<const unsigned char> bytes);
  Statement& bind_null(int i);

  bool step();  // true while a row is available
  void run() { while (step()) {} reset(); }
  void reset();

  bool is_null(int col) const;
  int64_t column_int(int col) const;
  double column_double(int col) const;
  std::string column_text(int col) const;
  std::vector<unsigned char> column_blob(int col) const;

 private:
  Connection* db_;
  sqlite3_stmt* stmt_;
};

// BEGIN IMMEDIATE ... COMMIT; rolls back when destroyed without commit() (an exception).
class Transaction {
 public:
  explicit Transaction(Connection& db);
  ~Transaction();
  void commit();

 private:
  Connection& db_;
  bool done_ = false;
};

// Float vectors as little-endian float32 BLOBs (DESIGN.md catalogue convention).
std::vector<unsigned char> floats_to_blob(std::span<const float> v);
std::vector<float> blob_to_floats(std::span<const unsigned char> blob);

}  // namespace proctex::catalog::sql
