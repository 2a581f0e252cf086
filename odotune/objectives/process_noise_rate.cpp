#include <odotune/objectives/process_noise_rate.h>

#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include <odotune/filters/ekf.h>
#include <odotune/objectives/replay.h>

namespace odotune::objectives {

namespace {

// Times of the first and last odometry step ends of one track, and its number of steps.
struct StepSpan {
  double t_first_s = 0.0, t_last_s = 0.0;
  long steps = 0;
};

StepSpan step_span(const ReplayInput& in) {
  StepSpan s;
  for (const ReplayRow& row : in.rows) {
    if (row.step < 0) continue;
    if (s.steps == 0) s.t_first_s = row.t_s;
    s.t_last_s = row.t_s;
    ++s.steps;
  }
  if (s.steps < 2 || !(s.t_last_s > s.t_first_s))
    throw std::invalid_argument(
        fmt::format("track '{}': {} odometry step(s); at least two are needed for an odometry rate",
                    in.track_name, s.steps));
  return s;
}

void require_inputs(std::span<const ReplayInput> inputs) {
  if (inputs.empty()) throw std::invalid_argument("process noise rate: no tracks given");
}

}  // namespace

double odometry_rate_hz(std::span<const ReplayInput> inputs) {
  require_inputs(inputs);
  long steps = 0;
  double duration = 0.0;
  for (const ReplayInput& in : inputs) {
    const StepSpan s = step_span(in);
    steps += s.steps - 1;
    duration += s.t_last_s - s.t_first_s;
  }
  return static_cast<double>(steps) / duration;
}

ProcessNoiseRate equivalent_process_noise_rate(const filters::NoiseParams& noise,
                                               std::span<const ReplayInput> inputs) {
  require_inputs(inputs);
  std::string why;
  if (!noise.IsValid(&why)) throw std::invalid_argument("process noise rate: invalid noise: " + why);

  ProcessNoiseRate out;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();  // Σ diag(R_k) [m², m², rad²]
  for (const ReplayInput& in : inputs) {
    const StepSpan span = step_span(in);
    out.steps += span.steps - 1;
    out.duration_s += span.t_last_s - span.t_first_s;

    // The replay of replay_ekf, summing the R_k that Ekf::predict adds.
    filters::Ekf ekf(ekf_params_for(in, noise));
    bool first_step = true;
    for (const ReplayRow& row : in.rows) {
      if (row.step >= 0) {
        const auto k = static_cast<std::size_t>(row.step);
        const filters::StateCov R = ekf.predict(in.steps[k], in.abs_yaw_rate_rad_s[k]);
        if (!first_step) sum += R.diagonal();
        first_step = false;
      }
      if (row.fix >= 0) ekf.update(in.fixes[static_cast<std::size_t>(row.fix)]);
      if ((row.step >= 0 || row.fix >= 0) && ekf.check() != filters::Divergence::none)
        throw std::runtime_error(
            fmt::format("track '{}': the filter diverges ({}) at t = {} s with these parameters; no "
                        "process noise rate can be averaged over it",
                        in.track_name, filters::to_string(ekf.divergence()), row.t_s));
    }
  }
  out.odometry_rate_hz = static_cast<double>(out.steps) / out.duration_s;
  out.x_m2_per_s = sum(filters::kX) / out.duration_s;
  out.y_m2_per_s = sum(filters::kY) / out.duration_s;
  out.theta_rad2_per_s = sum(filters::kTheta) / out.duration_s;
  return out;
}

}  // namespace odotune::objectives
