#include <glog/logging.h>

#include <odotune/cli/commands.h>

int main(int argc, char** argv) {
  // Ceres logs through glog (e.g. a rank-deficient covariance, which odotune
  // reports itself as not determined); its lines on stderr would break the
  // one-line message of a refusal. Only a fatal log is let through.
  FLAGS_minloglevel = google::GLOG_FATAL;
  return odotune::cli::run(argc, argv);
}
