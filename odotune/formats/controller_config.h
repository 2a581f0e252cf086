// A calibrated wheel geometry as the parameters of the controller that drives
// the robot, so that `calibrate` and `diagnose` results go straight into its
// configuration (`--controller-out`):
//
//  * ros2_control's diff_drive_controller (ROS 2), a parameter file
//        NAME:
//          ros__parameters:
//            wheel_separation: …   wheel_radius: …
//            wheel_separation_multiplier: …
//            left_wheel_radius_multiplier: …   right_wheel_radius_multiplier: …
//  * ROS 1's diff_drive_controller (ros_controllers), the same keys under
//        NAME:
//          type: diff_drive_controller/DiffDriveController
//  * Gazebo Sim's DiffDrive system (gz::sim::systems::DiffDrive), an SDF
//    <plugin> element with <wheel_separation> and <wheel_radius>.
//
// Semantics, checked against the packages' sources (docs/calibration/README.md,
// "Into the robot's controller", gives the files and lines):
//  * ros2_controllers, diff_drive_controller/src/diff_drive_controller_parameter.yaml
//    (the five names, doubles, multipliers default 1.0) and
//    diff_drive_controller/src/diff_drive_controller.cpp (the controller uses
//    wheel_separation_multiplier × wheel_separation as the separation and
//    left/right_wheel_radius_multiplier × wheel_radius as each wheel's
//    radius, for its odometry and its wheel commands alike);
//  * ros_controllers (noetic-devel), diff_drive_controller/src/diff_drive_controller.cpp:
//    the same names and products, read from the controller's namespace;
//    a `wheel_radius_multiplier` parameter, when present, replaces both
//    left and right multipliers (the file says not to set it);
//  * gz-sim, src/systems/diff_drive/DiffDrive.hh and DiffDrive.cc: one
//    <wheel_radius> for the left and right wheels, <wheel_separation>, no
//    multipliers. A left/right radius difference cannot be represented: the
//    mean radius is written and a comment gives the difference's size.
// These controllers' kinematics are odotune's (odotune/filters/odometry_params.h):
// V = (ω_r R_R + ω_l R_L)/2, W = (ω_r R_R − ω_l R_L)/D.
//
// Forms (ROS controllers; Gazebo always gets the absolute geometry):
//  * multipliers (default): wheel_radius = R_nom, wheel_separation = D_nom
//    (the geometry the user's configuration already states), multipliers
//    R_L/R_nom, R_R/R_nom and D/D_nom. R_nom is the mean of the nominal left
//    and right radii (the track's robot.* metadata gives them per wheel; a
//    controller has one wheel_radius), so wheel_radius × multiplier is R_L
//    and R_R exactly, whatever the nominal.
//  * absolute: wheel_radius = R̄ = (R_L + R_R)/2, wheel_separation = D,
//    multipliers R_L/R̄, R_R/R̄ and 1.
// Both describe the same effective geometry; the file writes one form as
// parameters and the other in its comments.
//
// Numbers: metres with 7 decimals (0.1 µm), multipliers with 6 decimals
// (6 significant digits near 1; 0.5e-6 × a 0.3 m wheel is 0.15 µm). Every
// number is written with a decimal point: ROS 2 reads `1` as an integer,
// which a double parameter refuses.
//
// The file opens with comments: what wrote it, the provenance lines, the
// held-out figures, the calibrated and nominal geometry, the other form and
// how the controller applies the values. Nothing here reads the files back.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/filters/odometry_params.h>

namespace odotune::formats {

enum class ControllerKind { ros2_control, ros1, gazebo };
// "ros2_control", "ros1", "gazebo".
std::string_view to_string(ControllerKind kind);
// The keys of to_string; false (out untouched) for anything else.
bool parse_controller_kind(std::string_view text, ControllerKind* out);

enum class ControllerForm { multipliers, absolute };
// "multipliers", "absolute".
std::string_view to_string(ControllerForm form);
bool parse_controller_form(std::string_view text, ControllerForm* out);

struct ControllerOptions {
  ControllerKind kind = ControllerKind::ros2_control;
  // ROS controllers only (gazebo writes the absolute geometry and no
  // controller name: the <plugin> element's name is the system's class).
  ControllerForm form = ControllerForm::multipliers;
  // The controller's name in the controller manager's configuration: a ROS
  // name, letters, digits, '_' and '/', not starting with a digit.
  std::string controller_name = "diff_drive_controller";

  // False, with *why (when not null) naming the field and its value, for an
  // empty or malformed controller_name.
  bool IsValid(std::string* why) const;
};

// What to write. Provenance and held-out lines are free text, one comment
// line each (no line breaks inside), e.g. "calibrated by odotune calibrate:
// method batch-pose", "tracks: a.csv, b.csv", "held-out position error
// 0.412 m → 0.031 m".
struct ControllerGeometry {
  filters::OdometryParams calibrated;  // R_L, R_R, D [m]: the geometry the controller should use
  filters::OdometryParams nominal;     // the geometry the user's configuration states [m]
  std::string nominal_source;          // where the nominal came from, e.g. "the track's robot.* metadata"
  std::vector<std::string> provenance;
  std::vector<std::string> heldout;  // held-out figures, if any

  // False, with *why naming the first bad value ("calibrated wheel_base_m =
  // -1 must be a finite number > 0"), unless both geometries are positive and
  // finite (a nominal of zeros is one not given) and no line holds a line break.
  bool IsValid(std::string* why) const;
};

// The five parameters of one form (ROS controllers' names, SI units).
struct ControllerValues {
  double wheel_radius_m = 0.0;
  double wheel_separation_m = 0.0;
  double wheel_separation_multiplier = 1.0;
  double left_wheel_radius_multiplier = 1.0;
  double right_wheel_radius_multiplier = 1.0;
};

// The values of `form` (file comment). Precondition: geometry.IsValid().
ControllerValues controller_values(const ControllerGeometry& geometry, ControllerForm form);

// The file's text (ROS: YAML; gazebo: an SDF <plugin> element after XML
// comments, whose "--" sequences are written as "- -"). Throws
// core::Failure ("controller file: why") when geometry or options are
// invalid.
std::string controller_config_text(const ControllerGeometry& geometry, const ControllerOptions& options);

// Writes controller_config_text atomically (odotune/core/atomic_file.h). Throws
// core::Failure ("PATH: not written: why", or the writer's
// "cannot write controller parameters 'PATH': reason").
void write_controller_config(const ControllerGeometry& geometry, const ControllerOptions& options,
                             const std::filesystem::path& path);

}  // namespace odotune::formats
