#include <odotune/jobs/calibration_trace.h>

#include <stdexcept>

#include <fmt/format.h>

namespace odotune::jobs {

namespace {

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

CalibrationTraceTable build_trace_table(const calibration::CalibrationResult& result,
                                        const std::vector<const calibration::CalibrationInput*>& inputs) {
  const calibration::CalibrationTrace& tr = result.trace;
  if (tr.track.size() != tr.t.size() || tr.estimate.size() != tr.t.size())
    throw std::invalid_argument(
        fmt::format("calibration trace: t has {} rows, track {}, estimate {} (expected equal lengths)",
                    tr.t.size(), tr.track.size(), tr.estimate.size()));
  CalibrationTraceTable table;
  double offset = 0.0;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const calibration::CalibrationInput& in = *inputs[k];
    table.track_names.push_back(in.track_name);
    const double first = in.t.empty() ? 0.0 : in.t.front();
    const double duration = in.t.empty() ? 0.0 : in.t.back() - first;
    table.track_start_elapsed_s.push_back(offset);
    table.track_end_elapsed_s.push_back(offset + duration);
    if (in.truth) {
      const double last = first + duration;
      double from = first;
      for (double c : in.truth->change_times()) {
        table.change_elapsed_s.push_back(offset + (c - first));
        table.change_track.push_back(static_cast<int>(k));
        if (c <= from || c >= last) continue;
        table.truth_pieces.push_back({static_cast<int>(k), offset + (from - first), offset + (c - first),
                                      in.truth->at(from)});
        from = c;
      }
      table.truth_pieces.push_back({static_cast<int>(k), offset + (from - first), offset + duration,
                                    in.truth->at(from)});
    }
    offset += duration;
  }
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const int k = tr.track[i];
    if (k < 0 || static_cast<std::size_t>(k) >= inputs.size())
      throw std::invalid_argument(fmt::format("calibration trace: row {} refers to track {} of {}", i, k,
                                              inputs.size()));
    const calibration::CalibrationInput& in = *inputs[static_cast<std::size_t>(k)];
    const double first = in.t.empty() ? 0.0 : in.t.front();
    table.t_s.push_back(tr.t[i]);
    table.elapsed_s.push_back(table.track_start_elapsed_s[static_cast<std::size_t>(k)] + (tr.t[i] - first));
    table.track.push_back(k);
    table.estimate.push_back(tr.estimate[i]);
    if (in.truth) {
      table.truth.emplace_back(in.truth->at(tr.t[i]));
      table.any_truth = true;
    } else {
      table.truth.emplace_back(std::nullopt);
    }
  }
  const bool fixed = calibration::is_offline(result.method) ||
                     result.method == calibration::CalibrationMethod::none;
  if (fixed || tr.t.empty())
    for (std::size_t k = 0; k < inputs.size(); ++k)
      table.fixed_params.push_back(k < result.tracks.size() ? result.tracks[k].final_params
                                                            : result.final_params);
  return table;
}

std::string trace_csv(const CalibrationTraceTable& table) {
  std::string out =
      "t_s,elapsed_s,track,r_right_m,r_left_m,wheel_base_m,sd_r_right_m,sd_r_left_m,sd_wheel_base_m,"
      "particles,n_eff";
  if (table.any_truth) out += ",true_r_right_m,true_r_left_m,true_wheel_base_m";
  out += "\n";
  for (std::size_t i = 0; i < table.t_s.size(); ++i) {
    const filters::CalibEstimate& e = table.estimate[i];
    const filters::OdometryParams& p = e.params;
    out += fmt::format("{},{},{},{},{},{},{},{},{},{},{}", table.t_s[i], table.elapsed_s[i],
                       csv_cell(table.track_names[static_cast<std::size_t>(table.track[i])]),
                       p.wheel_radius_right_m, p.wheel_radius_left_m, p.wheel_base_m, e.sd_radius_right_m,
                       e.sd_radius_left_m, e.sd_wheel_base_m, e.particles, e.n_eff);
    if (table.any_truth) {
      if (table.truth[i]) {
        const filters::OdometryParams& t = *table.truth[i];
        out += fmt::format(",{},{},{}", t.wheel_radius_right_m, t.wheel_radius_left_m, t.wheel_base_m);
      } else {
        out += ",,,";
      }
    }
    out += "\n";
  }
  return out;
}

}  // namespace odotune::jobs
