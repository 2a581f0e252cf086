#include <odotune/filters/rl_filter.h>

namespace odotune::filters::rl {
namespace {

std::variant<RlEkf, RlUkf> make(RlFilterType type, const RlEkfParams& params, const UkfConstants& c) {
  if (type == RlFilterType::ekf) return RlEkf(params);
  RlUkfParams p;
  p.filter = params;
  p.alpha = c.alpha;
  p.kappa = c.kappa;
  p.beta = c.beta;
  return RlUkf(p);
}

}  // namespace

std::string_view to_string(RlFilterType t) { return t == RlFilterType::ekf ? "ekf" : "ukf"; }
std::string_view display_name(RlFilterType t) { return t == RlFilterType::ekf ? "EKF" : "UKF"; }

std::optional<RlFilterType> parse_rl_filter_type(std::string_view name) {
  if (name == "ekf") return RlFilterType::ekf;
  if (name == "ukf") return RlFilterType::ukf;
  return std::nullopt;
}

RlFilter::RlFilter(RlFilterType type, const RlEkfParams& params, const UkfConstants& ukf)
    : f_(make(type, params, ukf)) {}

bool RlFilter::process(const Measurement& m) {
  return std::visit([&](auto& f) { return f.process(m); }, f_);
}
void RlFilter::predict_to(std::int64_t time_ns) {
  std::visit([&](auto& f) { f.predict_to(time_ns); }, f_);
}
void RlFilter::predict(double dt_s) {
  std::visit([&](auto& f) { f.predict(dt_s); }, f_);
}
void RlFilter::set_command(const Command& c) {
  if (auto* ekf = std::get_if<RlEkf>(&f_)) ekf->set_command(c);
}
void RlFilter::restore(const State& x, const Cov& P, std::int64_t last_ns) {
  std::visit([&](auto& f) { f.restore(x, P, last_ns); }, f_);
}
bool RlFilter::initialized() const {
  return std::visit([](const auto& f) { return f.initialized(); }, f_);
}
std::int64_t RlFilter::last_time_ns() const {
  return std::visit([](const auto& f) { return f.last_time_ns(); }, f_);
}
const State& RlFilter::state() const {
  return std::visit([](const auto& f) -> const State& { return f.state(); }, f_);
}
const Cov& RlFilter::cov() const {
  return std::visit([](const auto& f) -> const Cov& { return f.cov(); }, f_);
}

}  // namespace odotune::filters::rl
