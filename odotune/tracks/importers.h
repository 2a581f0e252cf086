// Importers from the third-party datasets in ../shared/data/real to a Track
// (odotune-track/1, ../shared/specs/track-format.md). Each reads the original
// (or, for LITW, the documented derived) files unmodified, and records in the
// track's metadata where the data came from (`source`, `citation`, `licence`
// and `source.*` keys) so that every output cites its origin.
//
// Errors: any reading problem throws TrackError(file, line, reason) naming the
// file (a missing file or directory is named by its path, line 0). Never a
// crash, never a partial result.
#pragma once

#include <filesystem>

#include <odotune/tracks/track.h>

namespace odotune::tracks {

// UTIAS MRCLAM (Leung et al., IJRR 2011), one robot of one dataset folder
// `dir` holding RobotN_Odometry.dat and RobotN_Groundtruth.dat (robot = N,
// 1..5). Odometry.dat holds the COMMANDED body velocities -> v_cmd, w_cmd;
// Groundtruth.dat the Vicon pose -> gt_x, gt_y, gt_theta. Both are on one
// Unix clock at irregular rates: the rows are the union of their time stamps
// (a stamp present in both files shares a row; within one file a repeated
// stamp keeps its last sample, and the count is noted in the metadata).
// t is relative to the earliest stamp; `source.t0_unix` keeps the absolute
// start, computed from the decimal text so millisecond stamps subtract exactly.
Track import_mrclam(const std::filesystem::path& dir, int robot);

// OptiOdom (Sousa et al., JIRS 2022), one synchronised run file
// `<id>_run-NN.csv` (columns time, xgt, ygt, thgt, odoR, odoL: note R before
// L), with `<id>_metadata.csv` beside it (required: robot geometry and encoder).
// Gives ticks_l, ticks_r (cumulative sums of the per-cycle counts, starting
// with the first row's count), gt_x, gt_y, gt_theta (relative to the run start
// pose, as in the file), and robot.ticks_per_rev = ngear * encRes,
// robot.wheel_radius_left/right = Di/2, robot.wheel_base = Li.
// When the robot log `<id>.csv` is beside it and its run NN, trimmed by
// odo_ti/odo_tf, reproduces the run's odoL/odoR sequence exactly, adds the
// velocity commands v_cmd = vlin * (pi D / ticks_per_rev) / 0.05 s and
// w_cmd = omega / 0.05 s on the same cycle rows; otherwise leaves them out and
// says why in `source.cmd_alignment`.
Track import_optiodom(const std::filesystem::path& run_csv);

// UTIAS "Lost in the Woods" (AER1513 dataset2.mat), from its documented CSV
// export litw_series.csv (k,t_s,v_mps,om_radps,x_true_m,y_true_m,th_true_rad,
// true_valid). v, om are the base's odometry (measured, not commanded) ->
// v_cmd, w_cmd; the true pose -> gt_x, gt_y, gt_theta where true_valid == 1,
// empty cells elsewhere. The scalars of litw_scalars.csv beside it (d, v_var,
// om_var, r_var, b_var), when present, become `litw.<name>` metadata keys.
Track import_litw(const std::filesystem::path& series_csv);

}  // namespace odotune::tracks
