#include <odotune/jobs/run_record_bytes.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace odotune::jobs {

namespace {

// Appends trivially copyable values and length-prefixed strings.
class Writer {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put(const std::string& s) {
    put(static_cast<std::uint64_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<char> take() { return std::move(bytes_); }

 private:
  std::vector<char> bytes_;
};

// Reads what Writer wrote; throws on running past the end.
class Reader {
 public:
  explicit Reader(const std::vector<char>& bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string text() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s(bytes_.data() + at_, static_cast<std::size_t>(n));
    at_ += static_cast<std::size_t>(n);
    return s;
  }
  // A count of elements of at least `min_size` bytes each that must still fit.
  std::size_t count(std::size_t min_size) {
    const auto n = get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / min_size) fail();
    return static_cast<std::size_t>(n);
  }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  void need(std::uint64_t n) const {
    if (n > bytes_.size() - at_) fail();
  }
  [[noreturn]] static void fail() { throw std::runtime_error("a run sent between MPI ranks is truncated"); }
  const std::vector<char>& bytes_;
  std::size_t at_ = 0;
};

constexpr std::uint32_t kMagic = 0x6f647232;  // "odr2": this layout (odr1 had no param_ranges)

}  // namespace

std::vector<char> to_bytes(const results::RunRecord& r) {
  Writer w;
  w.put(kMagic);
  w.put(r.model);
  w.put(r.track);
  w.put(r.heldout_track);
  w.put(static_cast<std::int64_t>(r.mode));
  w.put(r.seed);
  w.put(r.solver);
  w.put(static_cast<std::uint64_t>(r.param_names.size()));
  for (const auto& n : r.param_names) w.put(n);
  w.put(static_cast<std::uint64_t>(r.params.size()));
  for (double p : r.params) w.put(p);
  w.put(static_cast<std::uint64_t>(r.param_ranges.size()));
  for (const auto& g : r.param_ranges) {
    w.put(g.lo);
    w.put(g.hi);
    w.put(static_cast<std::uint8_t>(g.determined ? 1 : 0));
  }
  w.put(r.best_fitness);
  for (const auto* m : {&r.baseline, &r.tuned}) {
    w.put(m->rmse_m);
    w.put(m->mae_m);
    w.put(m->maxe_m);
  }
  w.put(static_cast<std::int64_t>(r.evaluations));
  w.put(r.seconds);
  w.put(static_cast<std::int64_t>(r.diverged));
  w.put(r.termination);
  w.put(static_cast<std::uint64_t>(r.convergence.size()));
  for (const auto& c : r.convergence) {
    w.put(static_cast<std::int64_t>(c.evaluations));
    w.put(c.best_fitness);
  }
  return w.take();
}

results::RunRecord run_record_from_bytes(const std::vector<char>& bytes) {
  Reader in(bytes);
  if (in.get<std::uint32_t>() != kMagic)
    throw std::runtime_error("a run sent between MPI ranks has an unknown layout (different odotune builds?)");
  results::RunRecord r;
  r.model = in.text();
  r.track = in.text();
  r.heldout_track = in.text();
  r.mode = static_cast<int>(in.get<std::int64_t>());
  r.seed = in.get<std::uint64_t>();
  r.solver = in.text();
  r.param_names.resize(in.count(sizeof(std::uint64_t)));
  for (auto& n : r.param_names) n = in.text();
  r.params.resize(in.count(sizeof(double)));
  for (auto& p : r.params) p = in.get<double>();
  r.param_ranges.resize(in.count(2 * sizeof(double) + sizeof(std::uint8_t)));
  for (auto& g : r.param_ranges) {
    g.lo = in.get<double>();
    g.hi = in.get<double>();
    const auto d = in.get<std::uint8_t>();
    if (d > 1) throw std::runtime_error("a run sent between MPI ranks has a malformed parameter range");
    g.determined = d == 1;
  }
  r.best_fitness = in.get<double>();
  for (auto* m : {&r.baseline, &r.tuned}) {
    m->rmse_m = in.get<double>();
    m->mae_m = in.get<double>();
    m->maxe_m = in.get<double>();
  }
  r.evaluations = static_cast<long>(in.get<std::int64_t>());
  r.seconds = in.get<double>();
  r.diverged = static_cast<long>(in.get<std::int64_t>());
  r.termination = in.text();
  r.convergence.resize(in.count(sizeof(std::int64_t) + sizeof(double)));
  for (auto& c : r.convergence) {
    c.evaluations = static_cast<long>(in.get<std::int64_t>());
    c.best_fitness = in.get<double>();
  }
  if (!in.at_end()) throw std::runtime_error("a run sent between MPI ranks has trailing bytes");
  return r;
}

}  // namespace odotune::jobs
