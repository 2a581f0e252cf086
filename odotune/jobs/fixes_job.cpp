#include <odotune/jobs/fixes_job.h>

#include <stdexcept>

#include <odotune/core/failure.h>
#include <odotune/tracks/track_io.h>

namespace odotune {

std::string run_fixes(const FixesRequest& r) {
  std::string why;
  if (!r.options.IsValid(&why)) throw Failure(why);
  const Track in = load_tracks({r.track}).front();
  const Track out = [&] {
    try {
      return with_synthetic_fixes(in, r.options);
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
  }();
  try {
    write_track(out, r.output);
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
  return out.meta().get("fixes.synthetic").value_or("");
}

}  // namespace odotune
