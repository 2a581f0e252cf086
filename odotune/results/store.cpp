#include <odotune/results/store.h>

#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace odotune::results {

namespace {

// 1: the first layout; 2: runs.param_ranges added (a store of version 1 is
// upgraded when opened for writing and read as is, with empty ranges).
constexpr int kSchemaVersion = 2;

// A prepared statement that finalizes itself.
class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& path, const char* sql) : path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK)
      throw std::runtime_error(fmt::format("{}: {}", path, sqlite3_errmsg(db)));
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;
  sqlite3_stmt* get() { return s_; }
  void text(int i, const std::string& v) { sqlite3_bind_text(s_, i, v.c_str(), -1, SQLITE_TRANSIENT); }
  void real(int i, double v) { sqlite3_bind_double(s_, i, v); }
  void integer(int i, long long v) { sqlite3_bind_int64(s_, i, v); }
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw std::runtime_error(fmt::format("{}: {}", path_, sqlite3_errmsg(sqlite3_db_handle(s_))));
  }
  std::string col_text(int i) {
    const auto* p = sqlite3_column_text(s_, i);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  // SQLite stores a bound NaN as NULL: it reads back as NaN, not 0 (a
  // diverged run's metrics).
  double col_real(int i) {
    return sqlite3_column_type(s_, i) == SQLITE_NULL ? std::nan("") : sqlite3_column_double(s_, i);
  }
  long long col_int(int i) { return sqlite3_column_int64(s_, i); }

 private:
  std::string path_;
  sqlite3_stmt* s_ = nullptr;
};

nlohmann::json convergence_json(const RunRecord& r) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& p : r.convergence) a.push_back({p.evaluations, p.best_fitness});
  return a;
}

// A double as JSON: finite values as numbers, exactly (nlohmann writes the
// shortest text that reads back to the same double), the others as the
// strings "inf", "-inf" and "nan" (JSON has no such numbers; a NaN's payload
// is not kept).
nlohmann::json exact_json(double v) {
  if (std::isfinite(v)) return v;
  if (std::isnan(v)) return "nan";
  return v > 0 ? "inf" : "-inf";
}
double exact_double(const nlohmann::json& j) {
  if (j.is_number()) return j.get<double>();
  const std::string s = j.get<std::string>();
  if (s == "inf") return HUGE_VAL;
  if (s == "-inf") return -HUGE_VAL;
  if (s == "nan") return std::nan("");
  throw std::runtime_error("not a number: " + s);
}

// [[lo, hi, determined], …] in param_names' order; "[]" when not profiled.
std::string ranges_json(const RunRecord& r) {
  nlohmann::json a = nlohmann::json::array();
  for (const ParamRange& p : r.param_ranges) a.push_back({exact_json(p.lo), exact_json(p.hi), p.determined});
  return a.dump();
}
std::vector<ParamRange> ranges_of(const std::string& text) {
  std::vector<ParamRange> out;
  if (text.empty()) return out;  // NULL: a run stored before the column existed
  for (const auto& p : nlohmann::json::parse(text))
    out.push_back({exact_double(p.at(0)), exact_double(p.at(1)), p.at(2).get<bool>()});
  return out;
}

// Whether table `runs` has the column `name` (stores of schema 1 lack param_ranges).
bool has_column(sqlite3* db, const std::string& path, const char* name) {
  Stmt s(db, path, "SELECT name FROM pragma_table_info('runs')");
  while (s.step())
    if (s.col_text(0) == name) return true;
  return false;
}

}  // namespace

std::string experiment_hash(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a 64 offset basis
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;  // FNV prime
  }
  return fmt::format("{:016x}", h);
}

std::string run_key(const RunRecord& r) {
  return fmt::format("{}|{}|{}|{}|{}|{}", r.model, r.track, r.heldout_track, r.mode, r.seed, r.solver);
}

void Store::exec(const std::string& sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw std::runtime_error(fmt::format("{}: {}", path_, msg));
  }
}

Store::Store(const std::filesystem::path& path, const ExperimentInfo& info, bool allow_other_experiment)
    : path_(path.string()) {
  if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot open the results store: {}", path_, msg));
  }
  try {
    sqlite3_busy_timeout(db_, 10000);
    exec("PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;");
    exec(fmt::format("CREATE TABLE IF NOT EXISTS experiment (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
                     "CREATE TABLE IF NOT EXISTS runs ("
                     " id INTEGER PRIMARY KEY AUTOINCREMENT, key TEXT UNIQUE NOT NULL,"
                     " model TEXT, track TEXT, heldout_track TEXT, mode INTEGER, seed INTEGER, solver TEXT,"
                     " params TEXT, best_fitness REAL,"
                     " baseline_rmse_m REAL, baseline_mae_m REAL, baseline_maxe_m REAL,"
                     " tuned_rmse_m REAL, tuned_mae_m REAL, tuned_maxe_m REAL,"
                     " evaluations INTEGER, seconds REAL, diverged INTEGER, termination TEXT,"
                     " convergence TEXT, param_ranges TEXT);"
                     "INSERT OR IGNORE INTO experiment VALUES ('schema_version', '{}');",
                     kSchemaVersion));
    // A store of schema 1 gets the column (NULL in its rows: empty ranges)
    // in one transaction, so a crash leaves it either upgraded or as it was.
    if (!has_column(db_, path_, "param_ranges")) {
      exec("BEGIN IMMEDIATE");
      try {
        if (!has_column(db_, path_, "param_ranges")) exec("ALTER TABLE runs ADD COLUMN param_ranges TEXT");
        exec(fmt::format("UPDATE experiment SET value = '{}' WHERE key = 'schema_version'", kSchemaVersion));
      } catch (...) {
        exec("ROLLBACK");
        throw;
      }
      exec("COMMIT");
    }
    has_ranges_ = true;
    const ExperimentInfo have = experiment();
    if (have.hash.empty()) {
      exec("BEGIN IMMEDIATE");
      Stmt s(db_, path_, "INSERT OR REPLACE INTO experiment VALUES (?, ?)");
      for (const auto& [k, v] : {std::pair<std::string, std::string>{"name", info.name},
                                 {"text", info.text},
                                 {"hash", info.hash},
                                 {"code_version", info.code_version},
                                 {"file", info.file}}) {
        s.text(1, k);
        s.text(2, v);
        s.step();
        sqlite3_reset(s.get());
      }
      exec("COMMIT");
    } else if (have.hash != info.hash && !allow_other_experiment) {
      throw std::runtime_error(
          fmt::format("{}: this store belongs to another experiment ('{}', hash {}; this file has hash {}); "
                      "use another --store, or --allow-other-experiment to continue into it",
                      path_, have.name, have.hash, info.hash));
    }
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

Store::Store(const std::filesystem::path& path) : path_(path.string()) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(fmt::format("{}: no such results store", path_));
  if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot open the results store: {}", path_, msg));
  }
  sqlite3_busy_timeout(db_, 10000);
  try {
    has_ranges_ = has_column(db_, path_, "param_ranges");
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

Store::~Store() { sqlite3_close(db_); }

ExperimentInfo Store::experiment() const {
  ExperimentInfo info;
  Stmt s(db_, path_, "SELECT key, value FROM experiment");
  while (s.step()) {
    const std::string k = s.col_text(0);
    if (k == "name") info.name = s.col_text(1);
    if (k == "text") info.text = s.col_text(1);
    if (k == "hash") info.hash = s.col_text(1);
    if (k == "code_version") info.code_version = s.col_text(1);
    if (k == "file") info.file = s.col_text(1);
  }
  return info;
}

std::set<std::string> Store::finished_keys() const {
  std::set<std::string> keys;
  Stmt s(db_, path_, "SELECT key FROM runs");
  while (s.step()) keys.insert(s.col_text(0));
  return keys;
}

void Store::add(const RunRecord& r) {
  if (!r.param_ranges.empty() && r.param_ranges.size() != r.param_names.size())
    throw std::invalid_argument(fmt::format("run {}: {} parameter ranges for {} parameters", run_key(r),
                                            r.param_ranges.size(), r.param_names.size()));
  nlohmann::json params = nlohmann::json::array();
  for (std::size_t i = 0; i < r.params.size(); ++i) params.push_back({r.param_names[i], r.params[i]});
  exec("BEGIN IMMEDIATE");
  try {
    Stmt s(db_, path_,
           "INSERT INTO runs (key, model, track, heldout_track, mode, seed, solver, params,"
           " best_fitness, baseline_rmse_m, baseline_mae_m, baseline_maxe_m, tuned_rmse_m,"
           " tuned_mae_m, tuned_maxe_m, evaluations, seconds, diverged, termination, convergence,"
           " param_ranges) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
    int i = 1;
    s.text(i++, run_key(r));
    s.text(i++, r.model);
    s.text(i++, r.track);
    s.text(i++, r.heldout_track);
    s.integer(i++, r.mode);
    s.integer(i++, static_cast<long long>(r.seed));
    s.text(i++, r.solver);
    s.text(i++, params.dump());
    s.real(i++, r.best_fitness);
    s.real(i++, r.baseline.rmse_m);
    s.real(i++, r.baseline.mae_m);
    s.real(i++, r.baseline.maxe_m);
    s.real(i++, r.tuned.rmse_m);
    s.real(i++, r.tuned.mae_m);
    s.real(i++, r.tuned.maxe_m);
    s.integer(i++, r.evaluations);
    s.real(i++, r.seconds);
    s.integer(i++, r.diverged);
    s.text(i++, r.termination);
    s.text(i++, convergence_json(r).dump());
    s.text(i++, ranges_json(r));
    s.step();
  } catch (...) {
    exec("ROLLBACK");
    throw;
  }
  exec("COMMIT");
}

std::vector<RunRecord> Store::runs() const {
  std::vector<RunRecord> out;
  Stmt s(db_, path_,
         has_ranges_ ? "SELECT model, track, heldout_track, mode, seed, solver, params, best_fitness,"
                       " baseline_rmse_m, baseline_mae_m, baseline_maxe_m, tuned_rmse_m, tuned_mae_m,"
                       " tuned_maxe_m, evaluations, seconds, diverged, termination, convergence, param_ranges"
                       " FROM runs ORDER BY id"
                     : "SELECT model, track, heldout_track, mode, seed, solver, params, best_fitness,"
                       " baseline_rmse_m, baseline_mae_m, baseline_maxe_m, tuned_rmse_m, tuned_mae_m,"
                       " tuned_maxe_m, evaluations, seconds, diverged, termination, convergence, NULL"
                       " FROM runs ORDER BY id");
  while (s.step()) {
    RunRecord r;
    int i = 0;
    r.model = s.col_text(i++);
    r.track = s.col_text(i++);
    r.heldout_track = s.col_text(i++);
    r.mode = static_cast<int>(s.col_int(i++));
    r.seed = static_cast<std::uint64_t>(s.col_int(i++));
    r.solver = s.col_text(i++);
    for (const auto& p : nlohmann::json::parse(s.col_text(i++))) {
      r.param_names.push_back(p[0].get<std::string>());
      r.params.push_back(p[1].get<double>());
    }
    r.best_fitness = s.col_real(i++);
    r.baseline = {s.col_real(i), s.col_real(i + 1), s.col_real(i + 2)};
    i += 3;
    r.tuned = {s.col_real(i), s.col_real(i + 1), s.col_real(i + 2)};
    i += 3;
    r.evaluations = static_cast<long>(s.col_int(i++));
    r.seconds = s.col_real(i++);
    r.diverged = static_cast<long>(s.col_int(i++));
    r.termination = s.col_text(i++);
    for (const auto& p : nlohmann::json::parse(s.col_text(i++)))
      r.convergence.push_back({p[0].get<long>(), p[1].get<double>()});
    r.param_ranges = ranges_of(s.col_text(i++));
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace odotune::results
