#include <odotune/filters/rl_ekf.h>

#include <odotune/core/why.h>
#include <odotune/filters/rl_filter_base.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

// The filter's arithmetic is written once, as templates over the type of one
// number: double for RlEkf, Pack<W> (kLanes filters side by side, held in
// registers of W doubles) for RlEkfLanes. Every instantiation performs the
// same IEEE operations in the same order for every lane (no FMA contraction:
// -ffp-contract=off, CMakeLists.txt; sums in source order), so a lane gives
// the bits its own RlEkf gives.
//
// The lane kernels exist for x86-64-v4 (AVX-512, W = 8), AVX2 (W = 4) and
// baseline x86-64 (SSE2, W = 2), the CPU picking one at load time (GCC's
// function multiversioning, an ELF ifunc). Each uses registers its CPU has:
// GCC turns comparisons of vectors wider than the target's into scalar code.
#define ODOTUNE_RL_INLINE [[gnu::always_inline]] inline

namespace odotune::filters::rl {
namespace {

using detail::fused_members;
using detail::gather;
using detail::initialise;
using detail::positive_variance;
using detail::symmetric;

constexpr int kN = kStateSize;
// Vectors travel between functions of this file only, all inlined into the
// kernels that use them: the ABI note on passing them by value does not
// concern them.
#pragma GCC diagnostic ignored "-Wpsabi"
using LaneMask = std::int64_t __attribute__((vector_size(kLanes * sizeof(double))));

// W doubles and a W-lane mask (all bits set where true) as GCC vectors
// (spelled out per W: GCC ignores vector_size with a dependent size).
template <int W>
struct Vector;
template <>
struct Vector<2> {
  using V = double __attribute__((vector_size(16), may_alias));
  using M = std::int64_t __attribute__((vector_size(16), may_alias));
};
template <>
struct Vector<4> {
  using V = double __attribute__((vector_size(32), may_alias));
  using M = std::int64_t __attribute__((vector_size(32), may_alias));
};
template <>
struct Vector<8> {
  using V = double __attribute__((vector_size(64), may_alias));
  using M = std::int64_t __attribute__((vector_size(64), may_alias));
};

// kLanes doubles as kLanes / W vectors of W, and a per-lane mask alike; they
// view RlEkfLanes' Lanes arrays.
template <int W>
struct Pack {
  using V = typename Vector<W>::V;
  static constexpr int kParts = kLanes / W;
  V p[kParts];
  double lane(int l) const { return p[l / W][l % W]; }
  static Pack of(const double (&lanes)[kLanes]) {
    Pack r;
    std::memcpy(&r, lanes, sizeof r);
    return r;
  }
};
template <int W>
struct PackMask {
  using M = typename Vector<W>::M;
  M p[Pack<W>::kParts];
};

#define ODOTUNE_RL_PACK_ARITHMETIC(op)                                        \
  template <int W>                                                            \
  ODOTUNE_RL_INLINE Pack<W> operator op(const Pack<W>& a, const Pack<W>& b) { \
    Pack<W> r;                                                                \
    for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a.p[k] op b.p[k];      \
    return r;                                                                 \
  }                                                                           \
  template <int W>                                                            \
  ODOTUNE_RL_INLINE Pack<W> operator op(const Pack<W>& a, double b) {         \
    Pack<W> r;                                                                \
    for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a.p[k] op b;           \
    return r;                                                                 \
  }                                                                           \
  template <int W>                                                            \
  ODOTUNE_RL_INLINE Pack<W> operator op(double a, const Pack<W>& b) {         \
    Pack<W> r;                                                                \
    for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a op b.p[k];           \
    return r;                                                                 \
  }
ODOTUNE_RL_PACK_ARITHMETIC(+)
ODOTUNE_RL_PACK_ARITHMETIC(-)
ODOTUNE_RL_PACK_ARITHMETIC(*)
ODOTUNE_RL_PACK_ARITHMETIC(/)
#undef ODOTUNE_RL_PACK_ARITHMETIC

#define ODOTUNE_RL_PACK_COMPARISON(op)                                            \
  template <int W>                                                                \
  ODOTUNE_RL_INLINE PackMask<W> operator op(const Pack<W>& a, double b) {         \
    PackMask<W> r;                                                                \
    for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a.p[k] op b;               \
    return r;                                                                     \
  }                                                                               \
  template <int W>                                                                \
  ODOTUNE_RL_INLINE PackMask<W> operator op(const Pack<W>& a, const Pack<W>& b) { \
    PackMask<W> r;                                                                \
    for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a.p[k] op b.p[k];          \
    return r;                                                                     \
  }
ODOTUNE_RL_PACK_COMPARISON(<)
ODOTUNE_RL_PACK_COMPARISON(<=)
ODOTUNE_RL_PACK_COMPARISON(>)
ODOTUNE_RL_PACK_COMPARISON(>=)
#undef ODOTUNE_RL_PACK_COMPARISON

template <int W>
ODOTUNE_RL_INLINE Pack<W> operator-(const Pack<W>& a) {
  Pack<W> r;
  for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = -a.p[k];
  return r;
}
template <int W>
ODOTUNE_RL_INLINE PackMask<W> operator!(const PackMask<W>& a) {
  PackMask<W> r;
  for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = a.p[k] == 0;
  return r;
}

// ---------------------------------------------------------------------------
// What differs between one filter and a pack: choosing per lane, |x|, scalar
// library functions applied lane by lane.
ODOTUNE_RL_INLINE double pick(bool c, double a, double b) { return c ? a : b; }
template <int W>
ODOTUNE_RL_INLINE Pack<W> pick(const PackMask<W>& c, const Pack<W>& a, const Pack<W>& b) {
  Pack<W> r;
  for (int k = 0; k < Pack<W>::kParts; ++k) r.p[k] = c.p[k] ? a.p[k] : b.p[k];
  return r;
}
ODOTUNE_RL_INLINE double magnitude(double a) { return std::abs(a); }
template <int W>
ODOTUNE_RL_INLINE Pack<W> magnitude(const Pack<W>& a) {
  using M = typename PackMask<W>::M;
  Pack<W> r;
  for (int k = 0; k < Pack<W>::kParts; ++k) {
    r.p[k] = std::bit_cast<typename Pack<W>::V>(std::bit_cast<M>(a.p[k]) &
                                                std::numeric_limits<std::int64_t>::max());
  }
  return r;
}
ODOTUNE_RL_INLINE bool none(bool c) { return !c; }
template <int W>
ODOTUNE_RL_INLINE bool none(const PackMask<W>& c) {
  for (int l = 0; l < kLanes; ++l) {
    if (c.p[l / W][l % W] != 0) return false;
  }
  return true;
}
template <class T>
ODOTUNE_RL_INLINE T splat(double v) {
  if constexpr (std::is_same_v<T, double>) {
    return v;
  } else {
    double lanes[kLanes];
    std::fill(lanes, lanes + kLanes, v);
    return T::of(lanes);
  }
}
template <class F>
ODOTUNE_RL_INLINE double per_lane(double a, F f) {
  return f(a);
}
template <int W, class F>
ODOTUNE_RL_INLINE Pack<W> per_lane(const Pack<W>& a, F f) {
  double r[kLanes];
  for (int l = 0; l < kLanes; ++l) r[l] = f(a.lane(l));
  return Pack<W>::of(r);
}

// One out-of-line sin and cos for every instantiation (GCC may otherwise
// fuse them into sincos in one and not another).
[[gnu::noinline]] void sin_cos(double a, double* s, double* c) {
  *s = std::sin(a);
  *c = std::cos(a);
}
ODOTUNE_RL_INLINE void sin_cos(double a, double& s, double& c) { sin_cos(a, &s, &c); }
template <int W>
ODOTUNE_RL_INLINE void sin_cos(const Pack<W>& a, Pack<W>& s, Pack<W>& c) {
  double sl[kLanes], cl[kLanes];
  for (int l = 0; l < kLanes; ++l) sin_cos(a.lane(l), &sl[l], &cl[l]);
  s = Pack<W>::of(sl);
  c = Pack<W>::of(cl);
}

bool is_angle(int member) { return member == kRoll || member == kPitch || member == kYaw; }

// angles::normalize_angle: with y = a + π, fmod(y, 2π) is y, y − 2π or y + 2π
// for |y| < 4π, each exact (Sterbenz), so only lanes beyond (or NaN) call the
// library's fmod. The same bits as fmod for every input.
template <class T>
ODOTUNE_RL_INLINE T wrapped(T a) {
  constexpr double kPi = std::numbers::pi, kTwoPi = 2.0 * std::numbers::pi;
  const T y = a + kPi;
  if (!none(!(magnitude(y) < 2.0 * kTwoPi))) {
    return per_lane(a, [](double b) {
      const double r = std::fmod(b + kPi, kTwoPi);
      return r <= 0.0 ? r + kPi : r - kPi;
    });
  }
  T r = pick(y >= kTwoPi, y - kTwoPi, y);
  r = pick(r <= -kTwoPi, r + kTwoPi, r);
  return pick(r <= 0.0, r + kPi, r - kPi);
}

template <class T>
ODOTUNE_RL_INLINE void wrap_angles(T* x) {
  for (int m : {kRoll, kPitch, kYaw}) x[m] = wrapped(x[m]);
}

// ---------------------------------------------------------------------------
// The model's matrices are the identity plus a few terms: A has 28 of them
// and J 13 more, always at the same places. The prediction works on that
// list instead of dense 15 × 15 products.
struct At {
  int row, col;
};
constexpr int kTransferTerms = 28, kTerms = 41;

// Where model_terms puts each term: A − I (first 28), then J − A.
constexpr std::array<At, kTerms> kAt = [] {
  std::array<At, kTerms> at{};
  int k = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      at[k++] = {kX + i, kVx + j};
      at[k++] = {kX + i, kAx + j};
    }
  }
  for (At a : {At{kRoll, kVroll}, At{kRoll, kVpitch}, At{kRoll, kVyaw}, At{kPitch, kVpitch}, At{kPitch, kVyaw},
               At{kYaw, kVpitch}, At{kYaw, kVyaw},    At{kVx, kAx},     At{kVy, kAy},        At{kVz, kAz},
               At{kX, kRoll},     At{kX, kPitch},     At{kX, kYaw},     At{kY, kRoll},       At{kY, kPitch},
               At{kY, kYaw},      At{kZ, kRoll},      At{kZ, kPitch},   At{kRoll, kRoll},    At{kRoll, kPitch},
               At{kPitch, kRoll}, At{kYaw, kRoll},    At{kYaw, kPitch}}) {
    at[k++] = a;
  }
  return at;
}();

// The terms of each row r of J − I, in kAt's order: terms[start[r] … start[r + 1]).
struct RowTerms {
  std::array<int, kN + 1> start{};
  std::array<int, kTerms> terms{};
};
constexpr RowTerms kRows = [] {
  RowTerms rows;
  int n = 0;
  for (int r = 0; r < kN; ++r) {
    rows.start[r] = n;
    for (int k = 0; k < kTerms; ++k) {
      if (kAt[k].row == r) rows.terms[n++] = k;
    }
  }
  rows.start[kN] = n;
  return rows;
}();

template <class T>
ODOTUNE_RL_INLINE T dot3(const T* w, T a, T b, T c) {
  return a * w[0] + b * w[1] + c * w[2];
}

// The values of kAt's terms at x over dt: ekf.cpp's transfer function and
// its analytic Jacobian.
template <class T>
ODOTUNE_RL_INLINE void model_terms(const T* x, double dt, T* v) {
  T sr, cr, sp, cp, sy, cy;
  sin_cos(x[kRoll], sr, cr);
  sin_cos(x[kPitch], sp, cp);
  sin_cos(x[kYaw], sy, cy);
  const T cpi = 1.0 / cp, tp = sp * cpi;
  const double half_dt2 = 0.5 * dt * dt;
  // Body → world rotation R(roll, pitch, yaw), row by row.
  const T rot[3][3] = {{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
                       {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
                       {-sp, cp * sr, cp * cr}};
  int k = 0;
  for (const auto& row : rot) {
    for (const T& r : row) {
      v[k++] = r * dt;
      v[k++] = 0.5 * r * dt * dt;
    }
  }
  const T dts = splat<T>(dt);
  for (T t :
       {dts, sr * tp * dt, cr * tp * dt, cr * dt, -sr * dt, sr * cpi * dt, cr * cpi * dt, dts, dts, dts}) {
    v[k++] = t;
  }
  // ∂(R·(v·dt + a·dt²/2))/∂(roll, pitch, yaw): each is a rotation derivative
  // applied to w = v·dt + a·dt²/2.
  const T w[3] = {x[kVx] * dt + x[kAx] * half_dt2, x[kVy] * dt + x[kAy] * half_dt2,
                  x[kVz] * dt + x[kAz] * half_dt2};
  const T zero = splat<T>(0.0);
  const T vp = x[kVpitch], vy = x[kVyaw];
  for (T t :
       {dot3(w, zero, cy * sp * cr + sy * sr, -cy * sp * sr + sy * cr),
        dot3(w, -cy * sp, cy * cp * sr, cy * cp * cr),
        dot3(w, -sy * cp, -sy * sp * sr - cy * cr, -sy * sp * cr + cy * sr),
        dot3(w, zero, sy * sp * cr - cy * sr, -sy * sp * sr - cy * cr),
        dot3(w, -sy * sp, sy * cp * sr, sy * cp * cr),
        dot3(w, cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr), dot3(w, zero, cp * cr, -cp * sr),
        dot3(w, -cp, -sp * sr, -sp * cr), (cr * tp * vp - sr * tp * vy) * dt,
        (cpi * cpi * sr * vp + cpi * cpi * cr * vy) * dt, (-sr * vp - cr * vy) * dt,
        (cr * cpi * vp - sr * cpi * vy) * dt, (sr * tp * cpi * vp + cr * tp * cpi * vy) * dt}) {
    v[k++] = t;
  }
}

// The two passes of J·P·Jᵀ, row by row of J − I with the rows and terms as
// compile-time constants (unrolled): acc + Σ v[k]·m[col(k)·Stride] over the
// terms k of row R, in kAt's order.
template <int R, int Stride, class T, int... Ts>
ODOTUNE_RL_INLINE T add_row_terms(T acc, const T* v, const T* m, std::integer_sequence<int, Ts...>) {
  constexpr int first = kRows.start[R];
  ((acc = acc + v[kRows.terms[first + Ts]] * m[std::ptrdiff_t{kAt[kRows.terms[first + Ts]].col} * Stride]),
   ...);
  return acc;
}
template <int R, int Stride, class T>
ODOTUNE_RL_INLINE T add_row_terms(T acc, const T* v, const T* m) {
  return add_row_terms<R, Stride>(acc, v, m,
                                  std::make_integer_sequence<int, kRows.start[R + 1] - kRows.start[R]>{});
}
// Column R of B = P·Jᵀ; row R of J·B left of the diagonal.
template <int R, class T>
ODOTUNE_RL_INLINE void b_column(const T* v, const T* P, T* B) {
  for (int i = 0; i < kN; ++i) B[R * kN + i] = add_row_terms<R, kN>(P[R * kN + i], v, P + i);
}
template <int R, class T>
ODOTUNE_RL_INLINE void jb_row(const T* v, const T* B, T* P) {
  for (int j = 0; j <= R; ++j) P[j * kN + R] = add_row_terms<R, 1>(B[j * kN + R], v, B + j * kN);
}
template <class T, int... R>
ODOTUNE_RL_INLINE void project(const T* v, T* P, T* B, std::integer_sequence<int, R...>) {
  (b_column<R>(v, P, B), ...);
  (jb_row<R>(v, B, P), ...);
}

// x ← A·x; P ← J·P·Jᵀ + Δt·Q (Q's pose block scaled by |twist|² when dynamic,
// FilterBase::computeDynamicProcessNoiseCovariance on the state before the
// projection). P is column-major; J = I + D: first B = P·Jᵀ = P + P·Dᵀ (column
// operations; only the first 9 columns differ from P's, as D's rows below 9
// are zero), then the lower triangle of J·B = B + D·B (whose rows from 9 on
// are B's), mirrored.
// `control(x)` applies the control term to x after A, J and the dynamic Q's
// speed are taken (ekf.cpp's order); the lanes pass none.
template <class T, class Flag, class Control>
ODOTUNE_RL_INLINE void predict_kernel(T* x, T* P, const T* Q, Flag dynamic, double dt, Control control) {
  constexpr int kMoved = kVz + 1;  // the rows of J that are not the identity's
  T v[kTerms];
  model_terms(x, dt, v);
  T speed2 = x[kVx] * x[kVx];
  for (int i = kVx + 1; i <= kVyaw; ++i) speed2 = speed2 + x[i] * x[i];
  speed2 = pick(dynamic, speed2, splat<T>(1.0));
  control(x);

  T x_next[kN];
  std::copy(x, x + kN, x_next);
#pragma GCC unroll 28
  for (int k = 0; k < kTransferTerms; ++k) x_next[kAt[k].row] = x_next[kAt[k].row] + v[k] * x[kAt[k].col];
  std::copy(x_next, x_next + kN, x);
  wrap_angles(x);

  T B[kMoved * kN];
  project(v, P, B, std::make_integer_sequence<int, kMoved>{});
  for (int j = 0; j < kMoved; ++j) std::copy(B + j * kN + kMoved, B + j * kN + kN, P + j * kN + kMoved);
  const T dq = dt * speed2, dts = splat<T>(dt);
  for (int j = 0; j < kN; ++j) {
    for (int i = j; i < kN; ++i) {
      P[j * kN + i] = P[j * kN + i] + (i < kVx && j < kVx ? dq : dts) * Q[j * kN + i];
    }
  }
  for (int j = 0; j < kN; ++j) {
    for (int i = j + 1; i < kN; ++i) P[i * kN + j] = P[j * kN + i];
  }
}

// S⁻¹ for the n × n column-major S (destroyed) by Gauss–Jordan elimination
// with partial pivoting: per column, the largest magnitude at or below the
// diagonal (the first of equals) becomes the pivot, lane by lane.
template <class T>
ODOTUNE_RL_INLINE void invert(int n, T* S, T* Si) {
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < n; ++r) Si[c * n + r] = splat<T>(r == c ? 1.0 : 0.0);
  }
  for (int k = 0; k < n; ++k) {
    for (int r = k + 1; r < n; ++r) {
      const auto swap = magnitude(S[k * n + r]) > magnitude(S[k * n + k]);
      if (none(swap)) continue;
      for (int c = 0; c < n; ++c) {
        for (T* M : {S, Si}) {
          const T a = M[c * n + k], b = M[c * n + r];
          M[c * n + k] = pick(swap, b, a);
          M[c * n + r] = pick(swap, a, b);
        }
      }
    }
    const T pivot = S[k * n + k];
    for (int c = 0; c < n; ++c) {
      S[c * n + k] = S[c * n + k] / pivot;
      Si[c * n + k] = Si[c * n + k] / pivot;
    }
    for (int r = 0; r < n; ++r) {
      if (r == k) continue;
      const T f = S[k * n + r];
      for (int c = 0; c < n; ++c) {
        S[c * n + r] = S[c * n + r] - f * S[c * n + k];
        Si[c * n + r] = Si[c * n + r] - f * Si[c * n + k];
      }
    }
  }
}

// Joseph form (I − K·H)·P·(I − K·H)ᵀ + K·R·Kᵀ with H a selection and
// G = I − K·H: G·P = P − K·(H·P), then G·P·Gᵀ + K·R·Kᵀ = G·P − (G·P·Hᵀ − K·R)·Kᵀ
// (one 15 × n × 15 product fewer than three separate terms). The fully
// expanded P − K·H·P − (K·H·P)ᵀ + K·S·Kᵀ is cheaper still but loses the
// covariance on the Husky bag (non-finite within the drive). Only the lower
// triangle is computed, then mirrored; lanes that rejected keep their P.
// N > 0: n = N known at compile time.
template <int N, class T, class Accept>
ODOTUNE_RL_INLINE void joseph(T* P, int n_, const int* idx, const T* PHt, const T* K, const T* R,
                              Accept accept) {
  const int n = N > 0 ? N : n_;
  // W = G·P·Hᵀ − K·R: the columns idx of G·P, less K·R.
  T W[kN * kN];
  for (int m = 0; m < n; ++m) {
    for (int i = 0; i < kN; ++i) {
      T s = K[i] * PHt[m * kN + idx[0]];
      for (int a = 1; a < n; ++a) s = s + K[a * kN + i] * PHt[m * kN + idx[a]];
      T t = K[i] * R[std::ptrdiff_t{m} * n];
      for (int a = 1; a < n; ++a) t = t + K[a * kN + i] * R[m * n + a];
      W[m * kN + i] = (PHt[m * kN + i] - s) - t;
    }
  }
  // Column j of G·P − W·Kᵀ from row j down; (H·P)(a, j) = P(idx[a], j) = PHt(j, a).
  for (int j = 0; j < kN; ++j) {
    for (int i = j; i < kN; ++i) {
      T s = K[i] * PHt[j];
      for (int a = 1; a < n; ++a) s = s + K[a * kN + i] * PHt[a * kN + j];
      T t = W[i] * K[j];
      for (int m = 1; m < n; ++m) t = t + W[m * kN + i] * K[m * kN + j];
      P[j * kN + i] = pick(accept, (P[j * kN + i] - s) - t, P[j * kN + i]);
    }
  }
  for (int j = 0; j < kN; ++j) {
    for (int i = j + 1; i < kN; ++i) P[i * kN + j] = P[j * kN + i];
  }
}

// The correction by the n members idx[0 … n) with values z and covariance R
// (n × n column-major, its diagonal already made positive), gated at the
// squared threshold thr2. Returns where it was accepted (there x and P are
// updated; elsewhere unchanged). P is symmetric, so H·P = (P·Hᵀ)ᵀ.
template <int N, class T>
ODOTUNE_RL_INLINE auto correct_kernel(T* x, T* P, int n_, const int* idx, const T* z, const T* R, T thr2) {
  const int n = N > 0 ? N : n_;
  T PHt[kN * kN], S[kN * kN], Si[kN * kN];
  T nu[kN] = {};
  for (int a = 0; a < n; ++a) {
    std::copy(P + idx[a] * kN, P + idx[a] * kN + kN, PHt + a * kN);
    nu[a] = z[a] - x[idx[a]];
    if (is_angle(idx[a])) nu[a] = wrapped(nu[a]);
  }
  for (int b = 0; b < n; ++b) {
    for (int a = 0; a < n; ++a) S[b * n + a] = PHt[b * kN + idx[a]] + R[b * n + a];
  }
  invert(n, S, Si);
  T d2 = splat<T>(0.0);
  for (int a = 0; a < n; ++a) {
    T t = Si[a] * nu[0];
    for (int b = 1; b < n; ++b) t = t + Si[b * n + a] * nu[b];
    d2 = a == 0 ? nu[a] * t : d2 + nu[a] * t;
  }
  const auto accept = !(d2 >= thr2);
  if (none(accept)) return accept;

  // K = P·Hᵀ·S⁻¹; x ← x + K·ν.
  T K[kN * kN];
  for (int m = 0; m < n; ++m) {
    for (int i = 0; i < kN; ++i) {
      T k = PHt[i] * Si[m * n];
      for (int a = 1; a < n; ++a) k = k + PHt[a * kN + i] * Si[m * n + a];
      K[m * kN + i] = k;
    }
  }
  T x_new[kN];
  for (int i = 0; i < kN; ++i) {
    T dx = K[i] * nu[0];
    for (int m = 1; m < n; ++m) dx = dx + K[m * kN + i] * nu[m];
    x_new[i] = x[i] + dx;
  }
  wrap_angles(x_new);
  for (int i = 0; i < kN; ++i) x[i] = pick(accept, x_new[i], x[i]);
  joseph<N>(P, n, idx, PHt, K, R, accept);
  return accept;
}

// correct_kernel at the measurement's size: compile-time sizes for the usual
// 1 to 6 members.
template <class T>
ODOTUNE_RL_INLINE auto correct_sized(T* x, T* P, int n, const int* idx, const T* z, const T* R, T thr2) {
  switch (n) {
    case 1: return correct_kernel<1>(x, P, n, idx, z, R, thr2);
    case 2: return correct_kernel<2>(x, P, n, idx, z, R, thr2);
    case 3: return correct_kernel<3>(x, P, n, idx, z, R, thr2);
    case 4: return correct_kernel<4>(x, P, n, idx, z, R, thr2);
    case 5: return correct_kernel<5>(x, P, n, idx, z, R, thr2);
    case 6: return correct_kernel<6>(x, P, n, idx, z, R, thr2);
    default: return correct_kernel<0>(x, P, n, idx, z, R, thr2);
  }
}

}  // namespace

namespace {

// The lane kernels, one version per instruction set (see the top of the file).
template <int W>
ODOTUNE_RL_INLINE void predict_pack(Lanes* x, Lanes* P, const Lanes* Q, const LaneMask* dynamic, double dt) {
  predict_kernel(reinterpret_cast<Pack<W>*>(x), reinterpret_cast<Pack<W>*>(P),
                 reinterpret_cast<const Pack<W>*>(Q), *reinterpret_cast<const PackMask<W>*>(dynamic), dt,
                 [](Pack<W>*) {});
}
// Returns the lanes that accepted, lane l as bit l.
template <int W>
ODOTUNE_RL_INLINE std::uint32_t correct_pack(Lanes* x, Lanes* P, int n, const int* idx, const Lanes* z,
                                             const Lanes* R, const Lanes* thr2) {
  const PackMask<W> accepted = correct_sized(reinterpret_cast<Pack<W>*>(x), reinterpret_cast<Pack<W>*>(P), n,
                                             idx, reinterpret_cast<const Pack<W>*>(z),
                                             reinterpret_cast<const Pack<W>*>(R),
                                             *reinterpret_cast<const Pack<W>*>(thr2));
  std::uint32_t bits = 0;
  for (int l = 0; l < kLanes; ++l) bits |= accepted.p[l / W][l % W] != 0 ? 1u << l : 0u;
  return bits;
}

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
[[gnu::target("arch=x86-64-v4")]] void predict_lanes(Lanes* x, Lanes* P, const Lanes* Q,
                                                     const LaneMask* dynamic, double dt) {
  predict_pack<8>(x, P, Q, dynamic, dt);
}
[[gnu::target("avx2")]] void predict_lanes(Lanes* x, Lanes* P, const Lanes* Q, const LaneMask* dynamic,
                                           double dt) {
  predict_pack<4>(x, P, Q, dynamic, dt);
}
[[gnu::target("arch=x86-64-v4")]] std::uint32_t correct_lanes(
    Lanes* x, Lanes* P, int n, const int* idx, const Lanes* z, const Lanes* R, const Lanes* thr2) {
  return correct_pack<8>(x, P, n, idx, z, R, thr2);
}
[[gnu::target("avx2")]] std::uint32_t correct_lanes(Lanes* x, Lanes* P, int n, const int* idx, const Lanes* z,
                                                    const Lanes* R, const Lanes* thr2) {
  return correct_pack<4>(x, P, n, idx, z, R, thr2);
}
#define ODOTUNE_RL_BASELINE [[gnu::target("default")]]
#else
#define ODOTUNE_RL_BASELINE
#endif
ODOTUNE_RL_BASELINE void predict_lanes(Lanes* x, Lanes* P, const Lanes* Q, const LaneMask* dynamic, double dt) {
  predict_pack<2>(x, P, Q, dynamic, dt);
}
ODOTUNE_RL_BASELINE std::uint32_t correct_lanes(Lanes* x, Lanes* P, int n, const int* idx, const Lanes* z,
                                                const Lanes* R, const Lanes* thr2) {
  return correct_pack<2>(x, P, n, idx, z, R, thr2);
}

}  // namespace

double normalize_angle(double a) { return wrapped(a); }

State advance(const State& x, double dt_s) {
  double v[kTerms];
  model_terms(x.data(), dt_s, v);
  State out = x;
  for (int k = 0; k < kTransferTerms; ++k) out[kAt[k].row] += v[k] * x[kAt[k].col];
  return out;
}

Transition transition(const State& x, double dt_s) {
  double v[kTerms];
  model_terms(x.data(), dt_s, v);
  Transition out{Cov::Identity(), Cov::Identity()};
  for (int k = 0; k < kTerms; ++k) {
    if (k < kTransferTerms) out.A(kAt[k].row, kAt[k].col) += v[k];
    out.J(kAt[k].row, kAt[k].col) += v[k];
  }
  return out;
}

bool RlEkfParams::IsValid(std::string* why) const {
  if (!process_noise.allFinite()) return core::invalid(why, "process_noise has a non-finite entry");
  if (!initial_cov.allFinite()) return core::invalid(why, "initial_cov has a non-finite entry");
  if (!initial_state.allFinite()) return core::invalid(why, "initial_state has a non-finite entry");
  for (int i = 0; i < kStateSize; ++i) {
    if (process_noise(i, i) < 0.0)
      return core::invalid(why, fmt::format("process_noise({0},{0}) = {1} < 0", i, process_noise(i, i)));
    if (initial_cov(i, i) < 0.0)
      return core::invalid(why, fmt::format("initial_cov({0},{0}) = {1} < 0", i, initial_cov(i, i)));
  }
  if (control && !control->IsValid(why)) return false;
  return true;
}

RlEkf::RlEkf(const RlEkfParams& params)
    : Q_(symmetric(params.process_noise)),
      dynamic_q_(params.dynamic_process_noise),
      control_(params.control),
      x_(params.initial_state),
      P_(symmetric(params.initial_cov)) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("RlEkfParams: " + why);
}

void RlEkf::predict(double dt_s) {
  predict_at(dt_s, last_time_ns_ + static_cast<std::int64_t>(std::llround(dt_s * 1e9)));
}

void RlEkf::predict_at(double dt_s, std::int64_t reference_ns) {
  if (!control_) {
    predict_kernel(x_.data(), P_.data(), Q_.data(), dynamic_q_, dt_s, [](double*) {});
    return;
  }
  // ekf.cpp's predict, step (1): the rates gain a·Δt, the controlled linear
  // accelerations become a.
  const ControlVector v{x_[kVx], x_[kVy], x_[kVz], x_[kVroll], x_[kVpitch], x_[kVyaw]};
  const ControlVector a = control_accelerations(*control_, command_, v, reference_ns);
  predict_kernel(x_.data(), P_.data(), Q_.data(), dynamic_q_, dt_s, [&](double* x) {
    for (int i = kCVroll; i <= kCVyaw; ++i) x[kVx + i] += a[i] * dt_s;
    for (int i = kCVx; i <= kCVz; ++i) {
      if (control_->update[i]) x[kAx + i] = a[i];
    }
  });
}

bool RlEkf::correct(const Measurement& m) {
  int idx[kN];
  const int n = fused_members(m, idx);
  if (n == 0) return true;
  double z[kN], R[kN * kN];
  gather(m, n, idx, z, R);
  return correct_sized(x_.data(), P_.data(), n, idx, z, R, m.mahalanobis_threshold * m.mahalanobis_threshold);
}

bool RlEkf::process(const Measurement& m) {
  return detail::process_measurement(
      initialized_, last_time_ns_, m.time_ns,
      [&] {
        initialise(m, x_, P_);
        return true;
      },
      [&](double dt) { predict_at(dt, m.time_ns); }, [&] { return correct(m); });
}

void RlEkf::predict_to(std::int64_t time_ns) {
  detail::predict_to(last_time_ns_, time_ns, [&](double dt) { predict_at(dt, time_ns); });
}

// ---------------------------------------------------------------------------
// RlEkfLanes: lanes beyond lanes() repeat lane 0 (their results are unused).

RlEkfLanes::RlEkfLanes(std::span<const RlEkfParams> params) : lanes_(static_cast<int>(params.size())) {
  if (params.empty() || params.size() > static_cast<std::size_t>(kLanes)) {
    throw std::invalid_argument(fmt::format("RlEkfLanes: {} lanes, expected 1 to {}", params.size(), kLanes));
  }
  for (int l = 0; l < kLanes; ++l) {
    const RlEkfParams& p = params[l < lanes_ ? l : 0];
    std::string why;
    if (!p.IsValid(&why)) throw std::invalid_argument(fmt::format("RlEkfParams of lane {}: {}", l, why));
    if (p.control)
      throw std::invalid_argument(fmt::format("RlEkfParams of lane {}: the lanes have no control term", l));
    const Cov Q = symmetric(p.process_noise), P = symmetric(p.initial_cov);
    for (int k = 0; k < kN * kN; ++k) {
      Q_[k][l] = Q.data()[k];
      P_[k][l] = P.data()[k];
    }
    for (int i = 0; i < kN; ++i) x_[i][l] = p.initial_state[i];
    dynamic_q_[l] = p.dynamic_process_noise ? -1 : 0;
  }
}

State RlEkfLanes::state(int lane) const {
  State x;
  for (int i = 0; i < kN; ++i) x[i] = x_[i][lane];
  return x;
}

Cov RlEkfLanes::cov(int lane) const {
  Cov P;
  for (int k = 0; k < kN * kN; ++k) P.data()[k] = P_[k][lane];
  return P;
}

void RlEkfLanes::set_lane(int lane, const State& x, const Cov& P) {
  for (int i = 0; i < kN; ++i) x_[i][lane] = x[i];
  for (int k = 0; k < kN * kN; ++k) P_[k][lane] = P.data()[k];
}

std::uint32_t RlEkfLanes::process(std::span<const Measurement> ms) {
  if (static_cast<int>(ms.size()) != lanes_) {
    throw std::invalid_argument(fmt::format("RlEkfLanes: {} measurements for {} lanes", ms.size(), lanes_));
  }
  assert(std::all_of(ms.begin(), ms.end(),
                     [&](const Measurement& m) { return m.time_ns == ms[0].time_ns && m.mask == ms[0].mask; }));
  const auto init = [&] {
    for (int l = 0; l < kLanes; ++l) {
      State x = state(l);
      Cov P = cov(l);
      initialise(ms[l < lanes_ ? l : 0], x, P);
      set_lane(l, x, P);
    }
    return (1u << lanes_) - 1u;
  };
  return detail::process_measurement(
      initialized_, last_time_ns_, ms[0].time_ns, init,
      [&](double dt) { predict_lanes(x_.data(), P_.data(), Q_.data(), &dynamic_q_, dt); },
      [&] { return correct(ms); });
}

void RlEkfLanes::predict_to(std::int64_t time_ns) {
  detail::predict_to(last_time_ns_, time_ns,
                     [&](double dt) { predict_lanes(x_.data(), P_.data(), Q_.data(), &dynamic_q_, dt); });
}

// The lanes fuse the members of the (common) mask unless a value is
// non-finite in some lane; then each lane is corrected on its own.
std::uint32_t RlEkfLanes::correct(std::span<const Measurement> ms) {
  int idx[kN], n = 0;
  for (int i = 0; i < kN; ++i) {
    if (ms[0].mask[i]) idx[n++] = i;
  }
  if (n == 0) return (1u << lanes_) - 1u;
  Lanes z[kN], R[kN * kN], thr2;
  for (int l = 0; l < kLanes; ++l) {
    const Measurement& m = ms[l < lanes_ ? l : 0];
    for (int a = 0; a < n; ++a) {
      if (!std::isfinite(m.z[idx[a]])) return correct_lane_by_lane(ms);
      z[a][l] = m.z[idx[a]];
    }
    for (int b = 0; b < n; ++b) {
      for (int a = 0; a < n; ++a) R[b * n + a][l] = m.R(idx[a], idx[b]);
    }
    for (int a = 0; a < n; ++a) R[a * n + a][l] = positive_variance(R[a * n + a][l]);
    thr2[l] = m.mahalanobis_threshold * m.mahalanobis_threshold;
  }
  return correct_lanes(x_.data(), P_.data(), n, idx, z, R, &thr2) & ((1u << lanes_) - 1u);
}

std::uint32_t RlEkfLanes::correct_lane_by_lane(std::span<const Measurement> ms) {
  std::uint32_t bits = 0;
  for (int l = 0; l < kLanes; ++l) {
    const Measurement& m = ms[l < lanes_ ? l : 0];
    State x = state(l);
    Cov P = cov(l);
    int idx[kN];
    const int n = fused_members(m, idx);
    bool accepted = true;
    if (n > 0) {
      double z[kN], R[kN * kN];
      gather(m, n, idx, z, R);
      accepted = correct_sized(x.data(), P.data(), n, idx, z, R,
                               m.mahalanobis_threshold * m.mahalanobis_threshold);
    }
    set_lane(l, x, P);
    if (accepted && l < lanes_) bits |= 1u << l;
  }
  return bits;
}

}  // namespace odotune::filters::rl
