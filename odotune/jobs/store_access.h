// Reading a finished (or running) grid's results store from the commands
// that come after it (report, export): opening it read-only with one-line
// errors, finding its experiment's track files again, and turning a stored
// run back into filter noise.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <odotune/filters/ekf_noise.h>
#include <odotune/formats/ukf_config_yaml.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/results/run_record.h>
#include <odotune/results/store.h>
#include <odotune/tracks/track.h>

namespace odotune::jobs {

// Opens `path` read-only; throws core::Failure (one line) when it
// does not exist or is not a results store.
std::unique_ptr<results::Store> open_store_for_reading(const std::filesystem::path& path);

// The experiment's tracks by name, loaded from the files its stored text
// names (resolved against the experiment file recorded in the store), then
// from `extra_files` (--track), which take precedence for the same name.
// A track file that no longer exists is skipped; a file that exists but is
// bad is a Failure line. Returns an empty map when nothing can be found.
std::map<std::string, tracks::Track> experiment_tracks(const results::ExperimentInfo& info,
                                                       const std::vector<std::string>& extra_files);

// The model of a stored run, and a model name of the store: the store keeps
// the names `grid` wrote (data, results/run_record.h), parsed here where a
// command reads them back, so that no command compares them as text. Throw
// core::Failure (naming the run) for a name that is no model.
objectives::TunedModel run_model(const results::RunRecord& run);
objectives::TunedModel stored_model(const std::string& name);

// A stored run's physical parameter `name` (e.g. "r1_mm2"). Throws
// core::Failure naming the run when it has no such parameter.
double run_param(const results::RunRecord& run, const std::string& name);

// The filter noise of a stored run (its model and physical parameters, by
// name). Throws core::Failure naming the run when the model or a
// parameter is unknown, the run is a calibrator's (pf-calib,
// adaptive-pf-calib: no EKF noise) or the UKF's, or the values are invalid.
filters::NoiseParams run_noise(const results::RunRecord& run);

// The tuned UKF noise of a stored ukf run (ukf_space() values by name, at the
// grid's fusion rate, 10 Hz). Throws core::Failure naming the run
// when it is not a ukf run, a parameter is missing or the values are invalid.
formats::UkfConfig run_ukf_config(const results::RunRecord& run);

}  // namespace odotune::jobs
