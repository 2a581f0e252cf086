// Model terms: corrections of a wheel's ground speed that are NOT physics
// effects of ../shared/specs/physics-effects.md (docs/diagnosis-design.md,
// "Physics outside the list: term search"). One vocabulary for the simulator (odotune/sim/simulator.h,
// Scenario::terms), the scenario YAML (`terms:`, odotune/formats/scenario_yaml.h) and
// the diagnosis's term search (odotune/diagnose/term_search.h), which finds such
// terms in a recording and reports them as a formula.
//
// A term is coef x basis(state) added to ONE wheel's ground speed (the
// target, v_l or v_r) [m/s]:
//
//     v_l,true = v_l + sum over terms on v_l of coef * basis(state),
//
// where v_l is the wheel's ground speed as the rest of the model gives it (in
// the simulator: after every effect; in the diagnosis: the chosen model's;
// the nominal rim speed R_l*omega_l when neither has an effect). An
// out-of-round left wheel, radius R*(1 + a*sin(phi_l + p)), is
//     v_l,true = v_l*(1 + a*sin(phi_l + p)) = v_l + c1*v_l*sin(phi_l) + c2*v_l*cos(phi_l),
// c1 = a*cos(p), c2 = a*sin(p): the two terms "v_l·sin(φ_l)", "v_l·cos(φ_l)".
//
// Bases for the target wheel X (l or r), with their names (display form as in
// ../shared/specs/diagnosis-output.md; the ASCII form, `*` for `·` and `phi`
// for `φ`, is what scenarios use; both parse) and the coefficient's unit:
//   speed         v_X               coef [1]     (a radius scale)
//   sin_k, cos_k  v_X·sin(kφ_X), v_X·cos(kφ_X), k = 1, 2, 3   [1]
//   constant      1                 [m/s]
//   accel         dv_X/dt           [s]          (the wheel's acceleration)
//   turn_speed    |v·w|             [s]          (body speed times yaw rate)
//   speed_turn    v_X·|w|           [s]
//   speed_sq      v_X·|v_X|         [s/m]
//   speed_time    v_X·t             [1/s]        (t: time since the start)
//   speed_x       v_X·x             [1/m]        (x, y: the robot's position in
//   speed_y       v_X·y             [1/m]         the track's frame)
// State: v_X the target wheel's ground speed before the terms [m/s]; v, w
// the body velocities those ground speeds give [m/s, rad/s]; dv_X/dt its
// rim acceleration [m/s^2]; φ_X the wheel's rotation angle since the start
// (what its encoder counts) [rad]; x, y, t.
//
// Errors are one line (std::invalid_argument, or bool + message).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace odotune::sim {

enum class TermTarget { v_l, v_r };

enum class TermBasis {
  speed,
  sin_1,
  cos_1,
  sin_2,
  cos_2,
  sin_3,
  cos_3,
  constant,
  accel,
  turn_speed,
  speed_turn,
  speed_sq,
  speed_time,
  speed_x,
  speed_y
};
inline constexpr int kNumTermBases = 15;
inline constexpr std::size_t kMaxModelTerms = 64;  // per scenario

struct ModelTerm {
  TermTarget target = TermTarget::v_l;
  TermBasis basis = TermBasis::speed;
  double coef = 0.0;  // unit: see the file comment
};

// The state a basis is evaluated on (file comment).
struct TermState {
  double v_l = 0, v_r = 0;      // wheel ground speeds before the terms [m/s]
  double a_l = 0, a_r = 0;      // wheel (rim) accelerations [m/s^2]
  double v = 0, w = 0;          // body velocities [m/s, rad/s]
  double phi_l = 0, phi_r = 0;  // wheel rotation angles since the start [rad]
  double x = 0, y = 0;          // position [m]
  double t = 0;                 // time since the start [s]
};

// All bases in enum order.
const std::vector<TermBasis>& all_term_bases();
// "v_l" / "v_r".
std::string_view target_name(TermTarget t);
// The basis's name for target t: display form ("v_l·sin(2φ_l)") or ASCII
// ("v_l*sin(2*phi_l)").
std::string term_name(TermTarget t, TermBasis b, bool ascii = false);
// "1", "m/s", "s", "s/m", "1/s", "1/m".
std::string_view coef_unit(TermBasis b);
// basis(state) for target t [m/s per unit of coef].
double basis_value(TermTarget t, TermBasis b, const TermState& s);
// Sum of coef*basis over the terms whose target is t [m/s].
double term_correction(const std::vector<ModelTerm>& terms, TermTarget t, const TermState& s);

// "v_l" / "v_r" -> target; throws std::invalid_argument naming the valid ones.
TermTarget parse_target(std::string_view name);
// A basis name of target t in either form (spaces ignored); throws
// std::invalid_argument naming the valid names for t.
TermBasis parse_basis(TermTarget t, std::string_view name);

// Finite coefficients, at most kMaxModelTerms, no (target, basis) twice.
bool validate_terms(const std::vector<ModelTerm>& terms, std::string* why);

// One line for track metadata (sim.terms): "v_l += 0.01*v_l*sin(phi_l); ..."
// (ASCII names, shortest round-trip numbers).
std::string format_terms(const std::vector<ModelTerm>& terms);

// The terms as formulas, one clause per target in target order, e.g.
// "v_l,true = v_l·(1 + 0.012·sin(φ_l + 0.4))": terms with the factor v_X
// inside v_X·(1 + ...), a sin/cos pair of one harmonic as one amplitude and
// phase, the others added after; clauses joined by "; ". "" for no term.
std::string term_formula(const std::vector<ModelTerm>& terms);

}  // namespace odotune::sim
