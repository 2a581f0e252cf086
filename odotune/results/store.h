// The results store of an experiment grid: one SQLite file (Debian's
// libsqlite3) holding the experiment file and its hash, the code version, and
// every finished run.
//
// Crash safety: the database runs in WAL mode with synchronous=FULL and each
// run is written in its own transaction, so a process killed at any moment
// (SIGKILL, power loss) leaves every committed run intact and no partial one.
// A restarted grid asks finished_keys() and skips those cells: it never repeats
// a finished run and never loses one. A store is bound to one experiment
// (by the hash of its file); opening it for another is refused unless asked.
//
// Each run's parameter ranges (RunRecord::param_ranges) are kept since schema
// 2; a store of schema 1 (made before) is upgraded in one transaction when
// opened for writing and read as it is otherwise, its runs with empty ranges.
//
// Not thread-safe: one Store per thread (the grid writes from one thread).
#pragma once

#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <odotune/results/run_record.h>

struct sqlite3;

namespace odotune::results {

struct ExperimentInfo {
  std::string name;
  std::string text;          // the experiment file, verbatim
  std::string hash;          // of `text` (see experiment_hash)
  std::string code_version;  // odotune version that made the runs
  // Absolute path of the experiment file when the store was made, so report
  // and export can find the experiment's tracks again (its relative track
  // paths resolve against this file's folder). Empty if unknown.
  std::string file;
};

// FNV-1a 64 of the text, as 16 hex digits: identifies an experiment file.
// (Not cryptographic; it tells files apart, it does not defend against forgery.)
std::string experiment_hash(const std::string& text);

// The identity of a run's cell, e.g. "rq|track1||7|3|pso".
std::string run_key(const RunRecord& r);

class Store {
 public:
  // Opens or creates the store at `path`. A new store records `info`. An
  // existing one must hold the same experiment hash, else std::runtime_error
  // names both hashes (unless allow_other_experiment). Throws
  // std::runtime_error naming the path on any SQLite failure.
  Store(const std::filesystem::path& path, const ExperimentInfo& info, bool allow_other_experiment = false);
  // Opens an existing store read-only (for report and export).
  explicit Store(const std::filesystem::path& path);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  ExperimentInfo experiment() const;
  std::set<std::string> finished_keys() const;
  // Writes one run in its own durable transaction. A run whose key is
  // already stored is an error (the grid never repeats a run); so are
  // param_ranges that are neither empty nor one per parameter
  // (std::invalid_argument, nothing written).
  void add(const RunRecord& run);
  // All runs, in the order they were written.
  std::vector<RunRecord> runs() const;

 private:
  void exec(const std::string& sql) const;
  std::string path_;
  sqlite3* db_ = nullptr;
  bool has_ranges_ = false;  // runs has the param_ranges column (schema 2)
};

}  // namespace odotune::results
