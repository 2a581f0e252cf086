#include <odotune/rlnode/prepared_recording.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/rlnode/replay.h>

namespace odotune::rlnode {

PreparedRecording prepare_recording(const std::filesystem::path& bag, const RlParams& params,
                                    const RecordingOptions& options, double gps_heading_fit_s) {
  PreparedRecording out{load_recording(bag, params, options), std::nullopt};
  if (gps_heading_fit_s > 0.0) {
    ReplaySettings reference = settings_of(params);
    reference.process_noise = default_process_noise();
    reference.initial_cov = default_initial_estimate_covariance();
    out.alignment = fit_gps_alignment(out.rec, reference, gps_heading_fit_s);
    out.rec.gps_transform = out.alignment->transform;
  }
  const Recording& rec = out.rec;
  if (rec.gps_sensor >= 0 && !rec.gps_transform.fixed && rec.navsat_headings.empty() &&
      !rec.params.navsat.use_odometry_yaw) {
    throw std::invalid_argument(
        fmt::format("{}: navsat_transform_node needs the IMU's heading for its datum, and the bag has "
                    "no IMU orientation; expected --gps-heading-fit SECONDS",
                    bag.string()));
  }
  return out;
}

}  // namespace odotune::rlnode
