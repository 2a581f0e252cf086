#include <odotune/cli/controller_options.h>

namespace odotune::cli {

void add_controller_options(CLI::App* sub, jobs::ControllerRequest& r, bool nominal_flags) {
  sub->add_option("--controller-out", r.out,
                  "write the calibrated wheel geometry as the robot controller's parameters to this file "
                  "(with --controller)");
  sub->add_option(
      "--controller", r.kind,
      "controller for --controller-out: ros2_control (diff_drive_controller, ROS 2 parameter file) | "
      "ros1 (diff_drive_controller) | gazebo (gz-sim DiffDrive <plugin> element)");
  sub->add_option("--controller-form", r.form,
                  "ROS controllers: multipliers (nominal wheel_radius and wheel_separation, calibrated "
                  "multipliers; default) | absolute (calibrated wheel_radius and wheel_separation)");
  sub->add_option("--controller-name", r.name,
                  "ROS controllers: the controller's name in the file (default diff_drive_controller)");
  if (!nominal_flags) return;
  sub->add_option("--nominal-wheel-radius-m", r.nominal_wheel_radius_m,
                  "the wheel_radius your controller configuration states [m], which the multipliers refer to "
                  "(default: the first track's robot.* radii, their mean when they differ)");
  sub->add_option("--nominal-wheel-base-m", r.nominal_wheel_base_m,
                  "the wheel_separation your controller configuration states [m] (default: the first track's "
                  "robot.wheel_base)");
}

}  // namespace odotune::cli
