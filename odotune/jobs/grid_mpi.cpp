#include <odotune/jobs/grid_mpi.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include <odotune/core/failure.h>

#if defined(ODOTUNE_WITH_MPI) && ODOTUNE_WITH_MPI
#define ODOTUNE_MPI_ENABLED 1
#include <mpi.h>

#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>

#include <odotune/jobs/run_record_bytes.h>
#else
#define ODOTUNE_MPI_ENABLED 0
#endif

namespace odotune::jobs {

namespace {

// Started by an MPI launcher: Open MPI's mpirun, MPICH's, or Slurm's srun
// with PMI-2 or PMIx.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_RANK", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

}  // namespace

bool mpi_built() { return ODOTUNE_MPI_ENABLED; }

#if !ODOTUNE_MPI_ENABLED

namespace {

long env_long(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::strtol(v, nullptr, 10) : 0;
}

// How many processes the launcher started, as far as its environment tells.
long launched_ranks() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (std::getenv(v)) return env_long(v);
  return std::getenv("PMIX_RANK") ? env_long("SLURM_NTASKS") : 0;
}

}  // namespace

MpiSession::MpiSession() {
  if (launched_by_mpi() && launched_ranks() > 1)
    throw core::Failure(
        fmt::format("started as one of {} MPI ranks, but this odotune was built without MPI (each rank would "
                    "run the whole grid); build with -DODOTUNE_WITH_MPI=ON, or run it without mpirun",
                    launched_ranks()));
}
MpiSession::~MpiSession() = default;

bool MpiSession::agree(const std::function<void()>& step) const {
  step();
  return true;
}

std::optional<GridOutcome> run_grid_mpi(const MpiSession&, const formats::Experiment&, results::Store*,
                                        const std::atomic<bool>*, const std::function<void(long, long)>&) {
  throw std::logic_error("run_grid_mpi: this odotune was built without MPI");
}

#else  // ODOTUNE_MPI_ENABLED

namespace {

// Message tags. Work phase: a rank asks rank 0 for a cell (kRequest), gets its
// index or -1 for "no more" (kCell), sends each finished run (kRun), its first
// failure (kFailure) and finally the number of runs it abandoned (kDone).
// Messages from one rank arrive in the order sent (MPI's non-overtaking rule),
// so kDone comes after that rank's last run.
enum Tag : int { kRequest = 1, kCell, kRun, kFailure, kDone, kSetupFailure };

const MPI_Comm kComm = MPI_COMM_WORLD;

void send_bytes(const std::vector<char>& b, int to, int tag) {
  MPI_Send(b.data(), static_cast<int>(b.size()), MPI_BYTE, to, tag, kComm);
}
void send_text(const std::string& s, int to, int tag) {
  MPI_Send(s.data(), static_cast<int>(s.size()), MPI_BYTE, to, tag, kComm);
}
// Receives the message `st` announced (from MPI_Probe/MPI_Iprobe).
std::vector<char> recv_bytes(const MPI_Status& st) {
  int n = 0;
  MPI_Get_count(&st, MPI_BYTE, &n);
  std::vector<char> b(static_cast<std::size_t>(n));
  MPI_Recv(b.data(), n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, kComm, MPI_STATUS_IGNORE);
  return b;
}
std::vector<char> recv_bytes(int from, int tag) {
  MPI_Status st;
  MPI_Probe(from, tag, kComm, &st);
  return recv_bytes(st);
}

// Rank 0's text, on every rank.
std::string broadcast(std::string s, int rank) {
  long long n = static_cast<long long>(s.size());
  MPI_Bcast(&n, 1, MPI_LONG_LONG, 0, kComm);
  if (rank != 0) s.assign(static_cast<std::size_t>(n), '\0');
  MPI_Bcast(s.data(), static_cast<int>(n), MPI_BYTE, 0, kComm);
  return s;
}

// What a rank must agree on with rank 0 to compute the same runs: the
// experiment file, the cells' keys and the tracks' bytes.
std::string grid_fingerprint(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                             const std::vector<GridCell>& cells) {
  std::string all = e.text;
  for (const auto& c : cells) all += "\n" + results::run_key(cell_record(e, tracks, c));
  std::vector<std::string> files = e.tracks;
  if (e.robot_localization) files.push_back(e.robot_localization->params.string());
  for (const auto& path : files) {
    std::ifstream in(path, std::ios::binary);
    all += "\n";
    all.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return results::experiment_hash(all);
}

[[noreturn]] void abort_job(int rank, const char* what) {
  std::fprintf(stderr, "odotune: rank %d: %s\n", rank, what);
  std::fflush(stderr);
  MPI_Abort(kComm, 1);
  std::abort();  // MPI_Abort does not return
}

// Rank 0's shared state: the cells still to hand out, the runs written and
// the first failure. `mu` guards all of it, the store and progress: the MPI
// server thread and the local workers share them.
struct Coordinator {
  const MpiSession& mpi;
  const std::vector<std::size_t>& pending;
  results::Store& store;
  const std::atomic<bool>* stop;
  const std::function<void(long, long)>& progress;
  long total;
  std::mutex mu{};
  std::size_t next = 0;
  long done = 0, remote_ran = 0, remote_abandoned = 0;
  std::string failure{};

  // The next pending cell; none once failed, stopped or all handed out. Under mu.
  std::optional<std::size_t> take() {
    if (!failure.empty() || (stop && stop->load()) || next == pending.size()) return std::nullopt;
    return pending[next++];
  }
  // Under mu.
  void write(const results::RunRecord& r) {
    store.add(r);
    ++done;
    if (progress) progress(done, total);
  }
  // Keeps the first failure. Under mu.
  void fail(const std::string& line) {
    if (failure.empty()) failure = line;
  }

  // One message of another rank; true when it says that rank is done. Under mu.
  bool handle(const MPI_Status& st, const std::vector<char>& msg) {
    const int from = st.MPI_SOURCE;
    switch (st.MPI_TAG) {
      case kRequest: {
        const auto k = take();
        const long long cell = k ? static_cast<long long>(*k) : -1;
        MPI_Send(&cell, 1, MPI_LONG_LONG, from, kCell, kComm);
        break;
      }
      case kRun:
        try {
          write(run_record_from_bytes(msg));
          ++remote_ran;
        } catch (const std::exception& ex) {
          fail(ex.what());
        }
        break;
      case kFailure: fail(fmt::format("rank {}: {}", from, std::string(msg.begin(), msg.end()))); break;
      case kDone: {
        long long abandoned = 0;
        if (msg.size() == sizeof abandoned) std::memcpy(&abandoned, msg.data(), sizeof abandoned);
        remote_abandoned += static_cast<long>(abandoned);
        return true;
      }
      default: fail(fmt::format("rank {} sent an unknown message (tag {})", from, st.MPI_TAG));
    }
    return false;
  }

  // The server thread, which alone talks MPI on rank 0: answers the other
  // ranks until every one is done.
  void serve() {
    try {
      int working = mpi.size() - 1;
      while (working > 0) {
        MPI_Status st;
        int flag = 0;
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, kComm, &flag, &st);
        if (!flag) {
          std::this_thread::sleep_for(std::chrono::microseconds(500));
          continue;
        }
        const std::vector<char> msg = recv_bytes(st);
        std::lock_guard<std::mutex> lock(mu);
        if (handle(st, msg)) --working;
      }
    } catch (const std::exception& ex) {
      abort_job(0, ex.what());
    }
  }
};

// Rank 0: hands out the pending cells to its own threads and, through a
// second thread that alone talks MPI here, to the other ranks; writes every
// run to the store as it arrives.
GridOutcome coordinate(const MpiSession& mpi, const formats::Experiment& e,
                       const std::vector<PreparedTrack>& tracks, const std::vector<GridCell>& cells,
                       const std::vector<std::size_t>& pending, results::Store& store,
                       const std::atomic<bool>* stop, const std::function<void(long, long)>& progress) {
  GridOutcome out;
  out.total = static_cast<long>(cells.size());
  out.skipped = out.total - static_cast<long>(pending.size());
  if (progress) progress(out.skipped, out.total);

  Coordinator c{mpi, pending, store, stop, progress, out.total};
  c.done = out.skipped;
  std::thread server([&c] { c.serve(); });

  CellSource local;
  local.next = [&c] {
    std::lock_guard<std::mutex> lock(c.mu);
    return c.take();
  };
  local.finished = [&c](results::RunRecord&& r) {
    std::lock_guard<std::mutex> lock(c.mu);
    c.write(r);
  };
  local.failed = [&c](const std::string& line) {  // stop handing out cells at once
    std::lock_guard<std::mutex> lock(c.mu);
    c.fail(line);
  };
  const WorkResult w = work_cells(e, tracks, cells, local, stop);
  server.join();
  if (!c.failure.empty()) throw core::Failure(c.failure);
  out.ran = w.ran + c.remote_ran;
  out.abandoned = w.abandoned + c.remote_abandoned;
  return out;
}

// Any other rank: asks rank 0 for cells until there are none, and sends it
// every finished run. MPI calls come from one OpenMP thread at a time (they
// are made inside work_cells' lock).
void work_for_rank0(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                    const std::vector<GridCell>& cells, const std::atomic<bool>* stop) {
  CellSource remote;
  remote.next = [&]() -> std::optional<std::size_t> {
    MPI_Send(nullptr, 0, MPI_BYTE, 0, kRequest, kComm);
    long long cell = -1;
    MPI_Recv(&cell, 1, MPI_LONG_LONG, 0, kCell, kComm, MPI_STATUS_IGNORE);
    if (cell < 0) return std::nullopt;
    if (static_cast<unsigned long long>(cell) >= cells.size())
      throw std::runtime_error(fmt::format("rank 0 sent cell {} of {}", cell, cells.size()));
    return static_cast<std::size_t>(cell);
  };
  remote.finished = [](results::RunRecord&& r) { send_bytes(to_bytes(r), 0, kRun); };
  remote.failed = [](const std::string& line) { send_text(line, 0, kFailure); };
  const WorkResult w = work_cells(e, tracks, cells, remote, stop);
  const long long abandoned = w.abandoned;
  MPI_Send(&abandoned, static_cast<int>(sizeof abandoned), MPI_BYTE, 0, kDone, kComm);
}

}  // namespace

MpiSession::MpiSession() {
  if (!launched_by_mpi()) return;
  int provided = 0;
  if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS)
    throw core::Failure("MPI could not be started (MPI_Init_thread failed)");
  if (provided < MPI_THREAD_SERIALIZED) {
    MPI_Finalize();
    throw core::Failure("this MPI library does not allow calls from several threads "
                        "(MPI_THREAD_SERIALIZED), which the grid needs");
  }
  initialised_ = true;
  MPI_Comm_rank(kComm, &rank_);
  MPI_Comm_size(kComm, &size_);
}

MpiSession::~MpiSession() {
  if (!initialised_) return;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

bool MpiSession::agree(const std::function<void()>& step) const {
  if (size_ == 1) {
    step();
    return true;
  }
  bool failed = false;
  int code = 1;
  std::string line;
  try {
    step();
  } catch (const core::Failure& f) {
    failed = true;
    code = f.exit_code;
    line = f.what();
  } catch (const std::exception& ex) {
    failed = true;
    line = ex.what();
  }
  int mine = failed ? 1 : 0;
  std::vector<int> flags(rank_ == 0 ? static_cast<std::size_t>(size_) : 0);
  MPI_Gather(&mine, 1, MPI_INT, flags.data(), 1, MPI_INT, 0, kComm);
  if (rank_ != 0) {
    if (failed) send_text(fmt::format("{} {}", code, line), 0, kSetupFailure);
  } else {
    for (int r = 1; r < size_; ++r) {
      if (!flags[static_cast<std::size_t>(r)]) continue;
      const std::vector<char> msg = recv_bytes(r, kSetupFailure);
      if (failed) continue;  // rank 0's own failure, or a lower rank's, is told
      failed = true;
      const std::string text(msg.begin(), msg.end());
      const auto space = text.find(' ');
      code = std::atoi(text.substr(0, space).c_str());
      line = fmt::format("rank {}: {}", r, space == std::string::npos ? "" : text.substr(space + 1));
    }
  }
  int any = failed ? 1 : 0;
  MPI_Bcast(&any, 1, MPI_INT, 0, kComm);
  if (!any) return true;
  if (rank_ == 0) throw core::Failure(line, code);
  return false;
}

std::optional<GridOutcome> run_grid_mpi(const MpiSession& mpi, const formats::Experiment& e,
                                        results::Store* store, const std::atomic<bool>* stop,
                                        const std::function<void(long, long)>& progress) {
  std::vector<PreparedTrack> tracks;
  std::vector<GridCell> cells;
  std::vector<std::size_t> pending;
  std::string fingerprint;
  if (!mpi.agree([&] {
        tracks = prepare_grid_tracks(e);
        cells = grid_cells(e);
        fingerprint = grid_fingerprint(e, tracks, cells);
        if (mpi.rank() == 0) pending = pending_cells(e, tracks, cells, *store);
      }))
    return std::nullopt;
  const std::string rank0_fingerprint = broadcast(fingerprint, mpi.rank());
  if (!mpi.agree([&] {
        if (fingerprint != rank0_fingerprint)
          throw core::Failure(
              "it reads another experiment than rank 0 (the experiment file, the track files or "
              "their contents differ): every rank must see the same files");
      }))
    return std::nullopt;

  try {
    if (mpi.rank() == 0) return coordinate(mpi, e, tracks, cells, pending, *store, stop, progress);
    work_for_rank0(e, tracks, cells, stop);
    return std::nullopt;
  } catch (const core::Failure&) {
    throw;  // rank 0, after every rank has finished: an orderly failure
  } catch (const std::exception& ex) {
    abort_job(mpi.rank(), ex.what());
  }
}

#endif  // ODOTUNE_MPI_ENABLED

std::optional<GridReport> run_grid_job(const GridRequest& request, const GridCallbacks& callbacks) {
  // Under mpirun/srun (MPI build): the ranks share the cells, rank 0 alone
  // writes the store and reports; a failure anywhere is told once, by rank 0.
  const MpiSession mpi;
  formats::Experiment e;
  if (!mpi.agree([&] { e = formats::read_experiment(request.experiment); })) return std::nullopt;
  GridReport report;
  report.store = request.store.empty() ? e.store : std::filesystem::path(request.store);
  report.ranks = mpi.size();
  std::unique_ptr<results::Store> store;
  const bool created = !std::filesystem::exists(report.store);
  if (!mpi.agree([&] {
        if (mpi.rank() == 0)
          store = open_grid_store(e, report.store, request.allow_other, request.code_version);
      }))
    return std::nullopt;
  const std::atomic<bool>* stop = callbacks.started ? callbacks.started(e) : nullptr;
  try {
    if (mpi.size() > 1) {
      const auto ranked = run_grid_mpi(mpi, e, store.get(), stop, callbacks.progress);
      if (!ranked) return std::nullopt;  // not rank 0: rank 0 reports
      report.outcome = *ranked;
    } else {
      report.outcome = run_grid(e, *store, stop, callbacks.progress);
    }
  } catch (const core::Failure&) {
    // A store this command created and left without a run (e.g. a bad track)
    // is not left behind.
    if (store && created && store->finished_keys().empty()) {
      store.reset();
      for (const char* suffix : {"", "-wal", "-shm"}) {
        std::error_code ec;
        std::filesystem::remove(report.store.string() + suffix, ec);
      }
    }
    throw;
  }
  return report;
}

}  // namespace odotune::jobs
