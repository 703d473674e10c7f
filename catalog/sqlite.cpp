#include "catalog/sqlite.h"

#include <sqlite3.h>

#include <bit>
#include <cstring>

#include "core/error.h"

namespace proctex::catalog::sql {

Connection::Connection(const std::filesystem::path& path, Mode mode) : path_(path) {
  int flags = SQLITE_OPEN_NOMUTEX;
  switch (mode) {
    case Mode::ReadOnly: flags |= SQLITE_OPEN_READONLY; break;
    case Mode::ReadWrite: flags |= SQLITE_OPEN_READWRITE; break;
    case Mode::Create: flags |= SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE; break;
  }
  const int rc = sqlite3_open_v2(path.string().c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw Error("cannot open catalogue '" + path.string() + "': " + msg,
                mode == Mode::ReadOnly ? "check that the file exists and is readable"
                                       : "check that the folder exists and is writable, or pass another --db");
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, 10000);
}

Connection::~Connection() {
  if (db_) sqlite3_close_v2(db_);
}

void Connection::fail(int code, const std::string& what) {
  const int primary = code & 0xff;
  std::string msg = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(code);
  std::string hint = "the catalogue file may be damaged; rebuild it with 'proctex catalog build'";
  if (primary == SQLITE_NOTADB)
    hint = "the file is not a SQLite database; pass another --db or remove it";
  else if (primary == SQLITE_CORRUPT)
    hint = "the file is corrupt; keep a copy for diagnosis and rebuild it with 'proctex catalog build' into a new file";
  else if (primary == SQLITE_READONLY || primary == SQLITE_CANTOPEN || primary == SQLITE_IOERR ||
           primary == SQLITE_PERM)
    hint = "check that the file and its folder are writable";
  else if (primary == SQLITE_FULL)
    hint = "the disk is full; free space and rerun (the catalogue was not changed)";
  else if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED)
    hint = "another process is writing this catalogue; wait for it or use another --db";
  throw Error("catalogue '" + path_.string() + "': " + what + ": " + msg, hint);
}

void Connection::exec(const std::string& sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err);
  if (err) sqlite3_free(err);
  if (rc != SQLITE_OK) fail(rc, "SQL failed");
}

Statement Connection::prepare(const std::string& sql) {
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &stmt, nullptr);
  if (rc != SQLITE_OK) fail(rc, "preparing a statement failed");
  return Statement(*this, stmt);
}

int64_t Connection::scalar_int(const std::string& sql) {
  Statement s = prepare(sql);
  return s.step() ? s.column_int(0) : 0;
}

std::string Connection::scalar_text(const std::string& sql) {
  Statement s = prepare(sql);
  return s.step() ? s.column_text(0) : std::string();
}

Statement::~Statement() {
  if (stmt_) sqlite3_finalize(stmt_);
}

Statement& Statement::bind(int i, int64_t v) {
  if (int rc = sqlite3_bind_int64(stmt_, i, v); rc != SQLITE_OK) db_->fail(rc, "bind");
  return *this;
}
Statement& Statement::bind(int i, double v) {
  if (int rc = sqlite3_bind_double(stmt_, i, v); rc != SQLITE_OK) db_->fail(rc, "bind");
  return *this;
}
Statement& Statement::bind(int i, const std::string& v) {
  if (int rc = sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT); rc != SQLITE_OK)
    db_->fail(rc, "bind");
  return *this;
}
Statement& Statement::bind_blob(int i, std::span<const unsigned char> b) {
  // A zero-length blob must still be a BLOB, not NULL: pass a non-null pointer.
  static const unsigned char empty = 0;
  if (int rc = sqlite3_bind_blob(stmt_, i, b.empty() ? &empty : b.data(), static_cast<int>(b.size()), SQLITE_TRANSIENT);
      rc != SQLITE_OK)
    db_->fail(rc, "bind");
  return *this;
}
Statement& Statement::bind_null(int i) {
  if (int rc = sqlite3_bind_null(stmt_, i); rc != SQLITE_OK) db_->fail(rc, "bind");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  sqlite3_reset(stmt_);
  db_->fail(rc, "query failed");
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

bool Statement::is_null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
int64_t Statement::column_int(int col) const { return sqlite3_column_int64(stmt_, col); }
double Statement::column_double(int col) const { return sqlite3_column_double(stmt_, col); }
std::string Statement::column_text(int col) const {
  const auto* p = sqlite3_column_text(stmt_, col);
  return p ? std::string(reinterpret_cast<const char*>(p), sqlite3_column_bytes(stmt_, col)) : std::string();
}
std::vector<unsigned char> Statement::column_blob(int col) const {
  const auto* p = static_cast<const unsigned char*>(sqlite3_column_blob(stmt_, col));
  const int n = sqlite3_column_bytes(stmt_, col);
  return p ? std::vector<unsigned char>(p, p + n) : std::vector<unsigned char>();
}

Transaction::Transaction(Connection& db) : db_(db) { db_.exec("BEGIN IMMEDIATE"); }
Transaction::~Transaction() {
  if (!done_) {
    char* err = nullptr;
    sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, &err);
    if (err) sqlite3_free(err);
  }
}
void Transaction::commit() {
  db_.exec("COMMIT");
  done_ = true;
}

std::vector<unsigned char> floats_to_blob(std::span<const float> v) {
  std::vector<unsigned char> out(v.size() * 4);
  for (size_t i = 0; i < v.size(); ++i) {
    uint32_t bits = std::bit_cast<uint32_t>(v[i]);
    for (int b = 0; b < 4; ++b) out[4 * i + b] = static_cast<unsigned char>(bits >> (8 * b));
  }
  return out;
}

std::vector<float> blob_to_floats(std::span<const unsigned char> blob) {
  if (blob.size() % 4 != 0) throw Error("catalogue holds a float vector of " + std::to_string(blob.size()) + " bytes (not a multiple of 4)",
                                        "the file is damaged; rebuild it");
  std::vector<float> out(blob.size() / 4);
  for (size_t i = 0; i < out.size(); ++i) {
    uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits |= uint32_t(blob[4 * i + b]) << (8 * b);
    out[i] = std::bit_cast<float>(bits);
  }
  return out;
}

}  // namespace proctex::catalog::sql
