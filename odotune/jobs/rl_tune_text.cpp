// What a robot_localization tune writes besides the parameter values
// (odotune/jobs/rl_job.h): the written file's header comment and tune --json.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <odotune/core/atomic_file.h>
#include <odotune/jobs/rl_job.h>

namespace odotune::jobs {
namespace {

std::string score_text(const objectives::FixScore& s) {
  return s.finite ? fmt::format("{:.3f} m", s.rmse_m) : "diverged";
}

std::string percent(double before, double after) {
  return std::isfinite(before) && std::isfinite(after) && before > 0.0
             ? fmt::format("{:+.0f} %", 100.0 * (after / before - 1.0))
             : "n/a";
}

std::string change(const objectives::FixScore& a, const objectives::FixScore& b) {
  return fmt::format("{} -> {} ({})", score_text(a), score_text(b), percent(a.rmse_m, b.rmse_m));
}

std::string span_text(const RlTuneOutcome& o) {
  if (!o.tracks.empty())
    return fmt::format("the whole of {} track(s), {:.1f} s", o.tracks.size(), o.duration_s);
  return fmt::format("{:.1f}-{:.1f} s of {:.1f} s", o.span_from_s, o.span_until_s, o.duration_s);
}

std::string search_text(const RlTuneRequest& r, const RlTuneOutcome& o) {
  std::string s = r.search.grid_levels.empty()
                      ? std::string("no grid")
                      : fmt::format("a grid of block factors 10^({}) ({} combinations)",
                                    fmt::join(r.search.grid_levels, ", "), o.grid.points);
  if (r.search.refine_decades > 0.0) {
    s += fmt::format(", then {} within {:g} decade(s) of the determined factors", r.solver.name(),
                     r.search.refine_decades);
  } else {
    s += "; no seeded stage, so every seed gives this file";
  }
  if (r.search.profile)
    s += fmt::format(", then each factor profiled (range within {:g} % of the best)",
                     100.0 * r.search.tolerance);
  return s;
}

// "q_x ×12.3 (3.1–40)" for each determined parameter; the others by name.
std::pair<std::string, std::string> determined_lists(const RlTuneOutcome& o, const RlStartOutcome& st) {
  std::string yes, no;
  for (std::size_t i = 0; i < o.param_names.size(); ++i) {
    if (st.profiles.empty()) break;
    const RlParamProfile& p = st.profiles[i];
    if (p.determined) {
      yes += fmt::format("{}{} x{:.3g} ({:.3g}-{:.3g})", yes.empty() ? "" : ", ", o.param_names[i],
                         st.factors[i], p.lo, p.hi);
    } else {
      no += fmt::format("{}{} ({:.3g}-{:.3g})", no.empty() ? "" : ", ", o.param_names[i], p.lo, p.hi);
    }
  }
  return {yes, no};
}

nlohmann::json tune_json_of(const objectives::FixScore& s) {
  return {{"rmse_m", s.rmse_m}, {"fixes", s.fixes}, {"finite", s.finite}};
}

nlohmann::json tune_json_of(const RlProtocolScores& p) {
  return {{"outage", tune_json_of(p.outage)}, {"every_fifth_fix", tune_json_of(p.every_fifth)}};
}

nlohmann::json tune_json_of(const RlTuneOutcome& o, const RlStartOutcome& st) {
  nlohmann::json params = nlohmann::json::object();
  for (std::size_t i = 0; i < o.param_names.size(); ++i) {
    nlohmann::json p = {{"factor", st.factors[i]}};
    if (!st.profiles.empty()) {
      p["range"] = {st.profiles[i].lo, st.profiles[i].hi};
      p["determined"] = st.profiles[i].determined;
    }
    params[o.param_names[i]] = p;
  }
  nlohmann::json j = {
      {"seed", st.seed},
      {"tuning_fitness", st.fitness},
      {"evaluations", st.evaluations},
      {"seconds", st.seconds},
      {"parameters", params},
      {"tuning_span", {{"heldout_fixes", tune_json_of(st.heldout)}, {"outage", tune_json_of(st.outage)}}}};
  if (st.judged) j["judged"] = tune_json_of(*st.judged);
  return j;
}

}  // namespace

std::string rl_tune_header(const RlTuneRequest& r, const RlTuneOutcome& o, std::size_t k) {
  const RlStartOutcome& st = o.starts[k];
  const auto [lo, hi] = std::minmax_element(o.starts.begin(), o.starts.end(),
                                            [](const auto& a, const auto& b) { return a.fitness < b.fitness; });
  std::vector<std::string> tracks;
  for (const auto& t : o.tracks) tracks.push_back(t.string());
  const std::string source = tracks.empty() ? fmt::format("Bag: {}", o.bag.string())
                                            : fmt::format("Tracks: {}", fmt::join(tracks, ", "));
  std::string c = fmt::format(
      "Tuned by odotune (robot_localization's EKF replayed from the robot's {}).\n"
      "Command: {}\n"
      "{}; parameter file: {}\n"
      "Tuned on {}: fitness {}{}, {} process noise{}; GPS outages of {} s ({} windows, one every {:g} s).\n"
      "Search: {}.\n",
      tracks.empty() ? "bag" : "recordings, as tracks",
      r.command_line.empty() ? "odotune tune --rl-params ..." : r.command_line, source, o.params_file.string(),
      span_text(o), objectives::to_string(r.options.fitness),
      r.options.subtract_fix_variance ? " (the fixes' own variance taken out)" : "",
      objectives::to_string(r.options.space), r.options.input_covariances ? " and input covariances" : "",
      fmt::join(r.options.outage_s, ", "), o.outage_windows, r.options.outage_stride_s, search_text(r, o));
  c += fmt::format(
      "This file is seed {}'s ({} replays){}; tuning fitness {:.4f} (the file's own values: {:.4f}).\n",
      st.seed, st.evaluations + o.grid.evaluations,
      o.starts.size() > 1
          ? fmt::format(" of {} starts, seeds {}-{}, whose tuning fitness spans "
                        "{:.4f}-{:.4f}",
                        o.starts.size(), o.starts.front().seed, o.starts.back().seed, lo->fitness, hi->fitness)
          : "",
      st.fitness, o.baseline_fitness);
  c += fmt::format("On the tuning span: held-out fixes {}; outages {}.\n",
                   change(o.baseline_heldout, st.heldout), change(o.baseline_outage, st.outage));
  if (o.baseline_judged && st.judged) {
    c += fmt::format("Judged on {:.1f}-{:.1f} s, never seen by the tune, file's values -> tuned:\n"
                     "  GPS outage: RMSE {}; every 5th fix held out: {}.\n",
                     o.judged_from_s, o.judged_until_s, change(o.baseline_judged->outage, st.judged->outage),
                     change(o.baseline_judged->every_fifth, st.judged->every_fifth));
  }
  const auto [yes, no] = determined_lists(o, st);
  if (!no.empty()) {
    c += fmt::format("Not determined by this recording, so kept at the file's values (the tuning fitness stays "
                     "within {:g} % of its best over these factors): {}.\n",
                     100.0 * r.search.tolerance, no);
  }
  if (!yes.empty())
    c += fmt::format("Determined (tuned factor, and its range within {:g} %): {}.\n",
                     100.0 * r.search.tolerance, yes);
  return c;
}

void write_rl_tune_json(const std::filesystem::path& path, const RlTuneRequest& r, const RlTuneOutcome& o) {
  nlohmann::json starts = nlohmann::json::array();
  for (const RlStartOutcome& st : o.starts) starts.push_back(tune_json_of(o, st));
  const RlStartOutcome& w = o.starts[o.written];
  nlohmann::json factors = nlohmann::json::object();
  for (std::size_t i = 0; i < o.param_names.size(); ++i) factors[o.param_names[i]] = o.factors[i];
  nlohmann::json j = {
      {"bag", o.bag.string()},
      {"params", o.params_file.string()},
      {"fitness", std::string(objectives::to_string(r.options.fitness))},
      {"space", std::string(objectives::to_string(r.options.space))},
      {"subtract_fix_variance", r.options.subtract_fix_variance},
      {"span_s", {o.span_from_s, o.span_until_s}},
      {"outage_s", r.options.outage_s},
      {"outage_windows", o.outage_windows},
      {"solver", r.solver.name()},
      {"seed", w.seed},
      {"grid",
       {{"levels", r.search.grid_levels},
        {"points", o.grid.points},
        {"evaluations", o.grid.evaluations},
        {"fitness", o.grid.fitness}}},
      {"evaluations", o.summary.evaluations},
      {"termination", o.summary.termination_text()},
      {"seconds", o.summary.seconds},
      {"factors", factors},
      {"parameters", tune_json_of(o, w)["parameters"]},
      {"baseline_fitness", o.baseline_fitness},
      {"tuned_fitness", o.tuned_fitness},
      {"starts", starts},
      {"tuning_span",
       {{"baseline",
         {{"heldout_fixes", tune_json_of(o.baseline_heldout)}, {"outage", tune_json_of(o.baseline_outage)}}},
        {"tuned",
         {{"heldout_fixes", tune_json_of(o.tuned_heldout)}, {"outage", tune_json_of(o.tuned_outage)}}}}}};
  if (o.baseline_judged && o.tuned_judged) {
    j["held_out"] = {{"span_s", {o.judged_from_s, o.judged_until_s}},
                     {"baseline", tune_json_of(*o.baseline_judged)},
                     {"tuned", tune_json_of(*o.tuned_judged)}};
  }
  std::vector<double> diag(o.tuned.process_noise.diagonal().data(),
                           o.tuned.process_noise.diagonal().data() + 15);
  j["process_noise_diagonal"] = diag;
  core::write_atomically(path, "JSON", j.dump(2) + "\n");
}

}  // namespace odotune::jobs
