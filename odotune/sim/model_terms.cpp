#include <odotune/sim/model_terms.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::sim {

namespace {

// Harmonic of a sin/cos basis (0 for the others) and whether it is a sine.
int harmonic(TermBasis b) {
  switch (b) {
    case TermBasis::sin_1:
    case TermBasis::cos_1: return 1;
    case TermBasis::sin_2:
    case TermBasis::cos_2: return 2;
    case TermBasis::sin_3:
    case TermBasis::cos_3: return 3;
    default: return 0;
  }
}
bool is_sine(TermBasis b) { return b == TermBasis::sin_1 || b == TermBasis::sin_2 || b == TermBasis::sin_3; }

// Bases with the factor v_X (written inside v_X·(1 + ...) by term_formula).
bool has_speed_factor(TermBasis b) {
  return b != TermBasis::constant && b != TermBasis::accel && b != TermBasis::turn_speed;
}

// The part after "v_X·" for bases with the speed factor, in display or ASCII
// form; x is "l" or "r".
std::string factor_name(TermBasis b, std::string_view x, bool ascii) {
  const std::string phi = ascii ? fmt::format("phi_{}", x) : fmt::format("φ_{}", x);
  const int k = harmonic(b);
  if (k > 0) {
    const std::string arg = k == 1 ? phi : fmt::format("{}{}{}", k, ascii ? "*" : "", phi);
    return fmt::format("{}({})", is_sine(b) ? "sin" : "cos", arg);
  }
  switch (b) {
    case TermBasis::speed_turn: return "|w|";
    case TermBasis::speed_sq: return fmt::format("|v_{}|", x);
    case TermBasis::speed_time: return "t";
    case TermBasis::speed_x: return "x";
    case TermBasis::speed_y: return "y";
    default: return "";
  }
}

// Names compare without spaces and products (· or *; no two names differ
// only there), with φ as phi: "v_l·sin(2φ_l)" = "v_l*sin(2*phi_l)".
std::string normalised(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == ' ' || s[i] == '\t' || s[i] == '*') continue;
    if (s.substr(i, 2) == "·") {
      ++i;
    } else if (s.substr(i, 2) == "φ") {
      out += "phi", ++i;
    } else {
      out += s[i];
    }
  }
  return out;
}

std::string number(double v) { return fmt::format("{:.3g}", v); }

}  // namespace

const std::vector<TermBasis>& all_term_bases() {
  static const std::vector<TermBasis> all = [] {
    std::vector<TermBasis> v;
    v.reserve(kNumTermBases);
    for (int i = 0; i < kNumTermBases; ++i) v.push_back(static_cast<TermBasis>(i));
    return v;
  }();
  return all;
}

std::string_view target_name(TermTarget t) { return t == TermTarget::v_l ? "v_l" : "v_r"; }

std::string term_name(TermTarget t, TermBasis b, bool ascii) {
  const std::string_view x = t == TermTarget::v_l ? "l" : "r";
  const std::string_view dot = ascii ? "*" : "·";
  switch (b) {
    case TermBasis::speed: return fmt::format("v_{}", x);
    case TermBasis::constant: return "1";
    case TermBasis::accel: return fmt::format("dv_{}/dt", x);
    case TermBasis::turn_speed: return fmt::format("|v{}w|", dot);
    default: return fmt::format("v_{}{}{}", x, dot, factor_name(b, x, ascii));
  }
}

std::string_view coef_unit(TermBasis b) {
  switch (b) {
    case TermBasis::constant: return "m/s";
    case TermBasis::accel:
    case TermBasis::turn_speed:
    case TermBasis::speed_turn: return "s";
    case TermBasis::speed_sq: return "s/m";
    case TermBasis::speed_time: return "1/s";
    case TermBasis::speed_x:
    case TermBasis::speed_y: return "1/m";
    default: return "1";
  }
}

double basis_value(TermTarget t, TermBasis b, const TermState& s) {
  const bool left = t == TermTarget::v_l;
  const double vx = left ? s.v_l : s.v_r, phi = left ? s.phi_l : s.phi_r;
  const int k = harmonic(b);
  if (k > 0) return vx * (is_sine(b) ? std::sin(k * phi) : std::cos(k * phi));
  switch (b) {
    case TermBasis::speed: return vx;
    case TermBasis::constant: return 1.0;
    case TermBasis::accel: return left ? s.a_l : s.a_r;
    case TermBasis::turn_speed: return std::abs(s.v * s.w);
    case TermBasis::speed_turn: return vx * std::abs(s.w);
    case TermBasis::speed_sq: return vx * std::abs(vx);
    case TermBasis::speed_time: return vx * s.t;
    case TermBasis::speed_x: return vx * s.x;
    case TermBasis::speed_y: return vx * s.y;
    default: return 0.0;
  }
}

double term_correction(const std::vector<ModelTerm>& terms, TermTarget t, const TermState& s) {
  double sum = 0.0;
  for (const ModelTerm& m : terms)
    if (m.target == t) sum += m.coef * basis_value(t, m.basis, s);
  return sum;
}

TermTarget parse_target(std::string_view name) {
  const std::string n = normalised(name);
  if (n == "v_l") return TermTarget::v_l;
  if (n == "v_r") return TermTarget::v_r;
  throw std::invalid_argument(fmt::format("unknown term target '{}'; expected v_l or v_r", name));
}

TermBasis parse_basis(TermTarget t, std::string_view name) {
  const std::string n = normalised(name);
  std::string valid;
  for (TermBasis b : all_term_bases()) {
    if (normalised(term_name(t, b, true)) == n) return b;
    valid += (valid.empty() ? "" : ", ") + term_name(t, b, true);
  }
  throw std::invalid_argument(fmt::format("unknown term '{}' for target {}; expected one of {}", name,
                                          target_name(t), valid));
}

bool validate_terms(const std::vector<ModelTerm>& terms, std::string* why) {
  if (terms.size() > kMaxModelTerms)
    return core::invalid(why, fmt::format("{} terms; expected at most {}", terms.size(), kMaxModelTerms));
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const ModelTerm& m = terms[i];
    const std::string name = term_name(m.target, m.basis, true);
    if (!std::isfinite(m.coef))
      return core::invalid(why, fmt::format("term {} ({} on {}): coef = {}; expected a finite number", i + 1,
                                            name, target_name(m.target), m.coef));
    for (std::size_t j = 0; j < i; ++j)
      if (terms[j].target == m.target && terms[j].basis == m.basis)
        return core::invalid(
            why, fmt::format("term {} ({} on {}) is given twice (also term {}); expected each term once", i + 1,
                             name, target_name(m.target), j + 1));
  }
  return true;
}

std::string format_terms(const std::vector<ModelTerm>& terms) {
  std::string out;
  for (const ModelTerm& m : terms)
    out += fmt::format("{}{} += {}*{}", out.empty() ? "" : "; ", target_name(m.target), m.coef,
                       term_name(m.target, m.basis, true));
  return out.empty() ? "none" : out;
}

std::string term_formula(const std::vector<ModelTerm>& terms) {
  std::string out;
  for (TermTarget t : {TermTarget::v_l, TermTarget::v_r}) {
    const std::string_view x = t == TermTarget::v_l ? "l" : "r";
    auto coef_of = [&](TermBasis b, bool* present) {
      for (const ModelTerm& m : terms)
        if (m.target == t && m.basis == b) return *present = true, m.coef;
      return *present = false, 0.0;
    };
    std::string inside, outside;  // "+ 0.012·sin(φ_l + 0.4)" parts
    auto add = [](std::string& s, double c, const std::string& what) {
      s += fmt::format(" {} {}{}", c < 0 ? "−" : "+", number(std::abs(c)), what.empty() ? "" : "·" + what);
    };
    bool any = false;
    for (TermBasis b : all_term_bases()) {
      bool here = false;
      const double c = coef_of(b, &here);
      if (!here) continue;
      any = true;
      const int k = harmonic(b);
      if (k > 0) {
        const TermBasis sine = static_cast<TermBasis>(static_cast<int>(TermBasis::sin_1) + 2 * (k - 1));
        const TermBasis cosine = static_cast<TermBasis>(static_cast<int>(sine) + 1);
        bool has_s = false, has_c = false;
        const double cs = coef_of(sine, &has_s), cc = coef_of(cosine, &has_c);
        if (has_s && has_c) {
          if (b == cosine) continue;  // written with its sine
          const double amp = std::hypot(cs, cc), phase = std::atan2(cc, cs);
          const std::string arg = fmt::format("{}φ_{} {} {:.2f}", k == 1 ? "" : fmt::format("{}", k), x,
                                              phase < 0 ? "−" : "+", std::abs(phase));
          add(inside, amp, fmt::format("sin({})", arg));
          continue;
        }
      }
      if (b == TermBasis::speed)
        add(inside, c, "");
      else if (has_speed_factor(b))
        add(inside, c, factor_name(b, x, false));
      else
        add(outside, c, term_name(t, b, false));
    }
    if (!any) continue;
    std::string clause = fmt::format("v_{},true = v_{}", x, x);
    if (!inside.empty()) clause += fmt::format("·(1{})", inside);
    clause += outside;
    out += (out.empty() ? "" : "; ") + clause;
  }
  return out;
}

}  // namespace odotune::sim
