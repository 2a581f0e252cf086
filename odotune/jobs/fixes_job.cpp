#include <odotune/jobs/fixes_job.h>

#include <stdexcept>

#include <odotune/core/failure.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

std::string run_fixes(const FixesRequest& r) {
  std::string why;
  if (!r.options.IsValid(&why)) throw core::Failure(why);
  const tracks::Track in = tracks::load_tracks({r.track}).front();
  const tracks::Track out = [&] {
    try {
      return sim::with_synthetic_fixes(in, r.options);
    } catch (const std::invalid_argument& e) {
      throw core::Failure(e.what());
    }
  }();
  try {
    tracks::write_track(out, r.output);
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
  return out.meta().get("fixes.synthetic").value_or("");
}

}  // namespace odotune::jobs
