// Verification rung: Tillotson regime continuity and the sound speed of every
// EOS against its thermodynamic definition (issue #3 items 4-5; PHYSICS.md
// §3). For every Tillotson material of the library, on a dense grid
// η = ρ/ρ0 ∈ [0.3, 5] × u ∈ {0} ∪ [1e-6, 100] E_cv (log-spaced in u):
//
//  1. p is continuous across η = 1, u = E_iv and u = E_cv: the one-sided
//     limits at the boundary, each the linear extrapolation from the states
//     at 1e-9 and 2e-9 (relative) on its side, differ by at most 1e-6 of the
//     local pressure scale |p| + A·1e-6. (The plain difference
//     p(b + 1e-9 b) − p(b − 1e-9 b) also holds the slope times 2e-9 b, which
//     alone exceeds that bound near p = 0, e.g. 2e-9 A at η = 1, u = 0; it
//     is recorded for information.)
//  2. c² agrees with ∂p/∂ρ|_u + (p/ρ²) ∂p/∂u|_ρ from fourth-order central
//     differences to 1e-5 relative to |c²| + (A/ρ0)·1e-6 (the c² analogue of
//     the pressure scale) wherever the state is not within 1e-6 (relative)
//     of a regime boundary; steps 1e-4 relative, and next to a boundary a
//     one-sided stencil pointing away from it. Besides the grid, states at
//     2e-6 ... 1e-3 from each boundary, on both sides, are checked.
//  3. c² > 0 everywhere for η ≥ 1; where c² ≤ 0 the documented floor
//     c² = A/ρ0 applies (eos.hpp).
//  4. With the tension cut-off on (rho_limit = 0.9, PHYSICS.md §3's typical
//     value) the only discontinuity is the documented one at η = rho_limit,
//     of size w_c p_c: a search along lines of constant u and of constant η
//     (find_jumps) finds no other, and the jump at rho_limit matches the
//     formula. Without the cut-off the same search finds none at all.
// Plus the same finite-difference check for the ideal gas and for the
// library's Murnaghan material(s) (item 5).
//
// One JSON record per material (docs/report-format.md) with per-material
// maxima, counts, and down-sampled p, c_s maps for report_plots.py. Exit 1
// when a check fails.
//
//   tillotson_continuity_rung --records DIR [--materials a,b,...]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "../common/rung.hpp"
#include "rubble/core/error.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/reference/eos_finite_difference.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene_parser.hpp"

using rubble::verification::Check;
using rubble::verification::Json;
using namespace rubble;

namespace {

// ---- thresholds, each with its source ------------------------------------------
constexpr double kJumpTol = 1e-6;         // issue #3 item 4: jump < 1e-6 of |p| + A·1e-6
constexpr double kJumpDistance = 1e-9;    // issue #3 item 4: sides at 1e-9 (relative) from the boundary
constexpr double kScaleFloor = 1e-6;      // issue #3 item 4: the A·1e-6 in the pressure scale
constexpr double kFdTol = 1e-5;           // issue #3 item 4: c² vs finite differences, 1e-5 relative
constexpr double kBoundaryClear = 1e-6;   // issue #3 item 4: FD check away from boundaries by 1e-6
constexpr double kFdStep = 1e-4;          // FD step (relative); 4th order: truncation ~1e-16
constexpr double kRhoLimit = 0.9;         // PHYSICS.md §3: typical tension cut-off

// ---- grid (issue #3 item 4) -------------------------------------------------------
constexpr int kNEta = 470;   // η ∈ [0.3, 5]
constexpr int kNU = 321;     // u = 0 plus 320 log-spaced points (40 per decade) in [1e-6, 100] E_cv
constexpr int kScanEta = 10;        // the discontinuity search scans along u at every 10th η ...
constexpr int kScanU = 8;           // ... and along η at every 8th u,
constexpr double kScanStep = 2e-4;  // sampling ratio 1 + 2e-4 (curvature leaves ~ h^3 times the third derivative, << 1e-6)
constexpr int kMapEta = 8;   // the maps in the record: every 8th η ...
constexpr int kMapU = 6;     // ... and every 6th u

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return b;
}

std::vector<double> eta_grid() {
  std::vector<double> v(kNEta);
  for (int i = 0; i < kNEta; ++i) v[i] = 0.3 + 4.7 * i / (kNEta - 1);
  return v;
}

std::vector<double> u_grid(double E_cv) {
  std::vector<double> v{0.0};
  for (int i = 0; i < kNU - 1; ++i) v.push_back(E_cv * std::pow(10.0, -6.0 + 8.0 * i / (kNU - 2)));
  return v;
}

// One-sided limits at boundary b of f: linear extrapolation from b ± δ, b ± 2δ.
template <class F>
double one_sided_jump(const F& f, double b, double delta) {
  const double above = 2 * f(b + delta) - f(b + 2 * delta);
  const double below = 2 * f(b - delta) - f(b - 2 * delta);
  return above - below;
}

// Jumps of f along a line x ∈ [lo, hi] (lo > 0), sampled geometrically with
// ratio 1 + step. An interval whose difference f(x_{i+1}) − f(x_i) departs
// from the one its neighbours' mean slope predicts by more than
// tol·(|f| + floor) is a candidate; it is then halved towards the half that
// departs more from that slope, down to adjacent doubles. A kink or
// curvature leaves a departure that shrinks with the width and is dropped; a
// jump J keeps |f(b) − f(a)| ≈ J and is reported at its location.
template <class F>
std::vector<double> find_jumps(const F& f, double lo, double hi, double step, double tol, double floor) {
  std::vector<double> x, y;
  for (double v = lo; v < hi; v *= 1 + step) x.push_back(v);
  x.push_back(hi);
  for (double v : x) y.push_back(f(v));
  std::vector<double> found;
  for (std::size_t i = 1; i + 2 < x.size(); ++i) {
    const double w = x[i + 1] - x[i];
    const double s = 0.5 * ((y[i] - y[i - 1]) / (x[i] - x[i - 1]) + (y[i + 2] - y[i + 1]) / (x[i + 2] - x[i + 1]));
    if (!(std::fabs(y[i + 1] - y[i] - s * w) > tol * (std::fabs(y[i]) + floor))) continue;
    double a = x[i], b = x[i + 1], fa = y[i], fb = y[i + 1];
    for (int it = 0; it < 200; ++it) {
      const double m = 0.5 * (a + b);
      if (!(m > a && m < b)) break;
      const double fm = f(m);
      if (std::fabs(fm - fa - s * (m - a)) >= std::fabs(fb - fm - s * (b - m))) b = m, fb = fm;
      else a = m, fa = fm;
    }
    if (std::fabs(fb - fa) > tol * (0.5 * (std::fabs(fa) + std::fabs(fb)) + floor)) found.push_back(0.5 * (a + b));
  }
  return found;
}

struct Maximum {
  double value = 0;
  std::string where;
  void take(double v, const std::string& at) {
    if (!(v <= value)) value = v, where = at;  // NaN wins, so it is seen
  }
};

std::string at(double eta, double u) {
  char b[80];
  std::snprintf(b, sizeof b, "eta=%.9g u=%.9g", eta, u);
  return b;
}

Json maxima_json(const Maximum& m) { return Json::object({{"max", m.value}, {"at", m.where}}); }

struct Args : rubble::verification::RungArgs {
  std::vector<std::string> materials;
  Args() : RungArgs({.taken = "--records"}) {}
  bool own_option(rubble::verification::ArgReader& r) override { return r.words("--materials", materials); }
};

// ---- one Tillotson material ------------------------------------------------------

struct Outcome {
  std::vector<Check> checks;
  bool passed() const {
    return std::all_of(checks.begin(), checks.end(), [](const Check& c) { return c.passed(); });
  }
};

Outcome tillotson_case(const MaterialConfig& m, const Args& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const EosParams eos = eos_params_from_material(m);
  const TillotsonParams& t = eos.tillotson;
  EosParams cut = eos;
  cut.limits.rho_limit = Real(kRhoLimit);
  const double rho0 = t.rho0, A = t.A, c2_bulk = t.A / t.rho0;
  const std::vector<double> etas = eta_grid(), us = u_grid(t.E_cv);

  auto p_of = [](const EosParams& e) { return [&e](double rho, double u) { return double(eos_evaluate(e, rho, u).p); }; };
  const auto p = p_of(eos);
  const auto p_cut = p_of(cut);
  const auto p_raw = [&](double rho, double u) { return double(eos_evaluate_raw(eos, rho, u).p); };

  // ---- 1. continuity at η = 1, E_iv, E_cv (defaults, and with the cut-off on) ----
  Maximum jump, jump_cut, plain;
  auto boundary_jumps = [&](const auto& pf, Maximum& out, Maximum* plain_out) {
    for (double u : us) {  // across η = 1
      auto f = [&](double rho) { return pf(rho, u); };
      const double scale = std::fabs(f(rho0)) + kScaleFloor * A;
      out.take(std::fabs(one_sided_jump(f, rho0, kJumpDistance * rho0)) / scale, "eta=1 " + at(1.0, u));
      if (plain_out)
        plain_out->take(std::fabs(f(rho0 * (1 + kJumpDistance)) - f(rho0 * (1 - kJumpDistance))) / scale, at(1.0, u));
    }
    for (double eta : etas) {  // across E_iv and E_cv, η < 1
      if (eta >= 1) continue;
      const double rho = eta * rho0;
      auto f = [&](double u) { return pf(rho, u); };
      for (double b : {double(t.E_iv), double(t.E_cv)}) {
        const double scale = std::fabs(f(b)) + kScaleFloor * A;
        out.take(std::fabs(one_sided_jump(f, b, kJumpDistance * b)) / scale,
                 std::string(b == t.E_iv ? "u=E_iv " : "u=E_cv ") + at(eta, b));
        if (plain_out) plain_out->take(std::fabs(f(b * (1 + kJumpDistance)) - f(b * (1 - kJumpDistance))) / scale, at(eta, b));
      }
    }
  };
  boundary_jumps(p, jump, &plain);
  boundary_jumps(p_cut, jump_cut, nullptr);

  // the documented jump at η = rho_limit: w_c p_c there (p above − p below)
  Maximum cut_mismatch;
  double cut_jump_max = 0;
  for (double u : us) {
    const double b = kRhoLimit * rho0;
    auto f = [&](double rho) { return p_cut(rho, u); };
    const double measured = one_sided_jump(f, b, kJumpDistance * b);
    const double documented = tillotson_evaluate(t, b, u).p_cold;
    const double scale = std::fabs(f(b)) + kScaleFloor * A;
    cut_mismatch.take(std::fabs(measured - documented) / scale, at(kRhoLimit, u));
    cut_jump_max = std::max(cut_jump_max, std::fabs(measured) / A);
  }

  // ---- 2-3. the sound speed on the dense grid, and next to the boundaries ---------------
  Maximum fd, fd_regime[4], fd_near, naive, forms, floor_violation;
  long fd_checked = 0, fd_skipped = 0, fd_near_checked = 0, nonpositive = 0, nonpositive_outside = 0, floored = 0;
  long nonpositive_by_regime[4] = {0, 0, 0, 0};
  double min_c2_compressed = std::numeric_limits<double>::infinity();
  auto fd_check = [&](double eta, double u, bool near) {
    const double rho = eta * rho0;
    const EosState raw = eos_evaluate_raw(eos, rho, u);
    const int regime = static_cast<int>(raw.regime) - static_cast<int>(EosRegime::TillotsonCompressed);
    // relative distance to the boundaries along each axis; within 1e-6: not checked
    const double d_rho = std::fabs(rho - rho0) / rho0;
    const double d_iv = eta < 1 ? std::fabs(u - t.E_iv) / t.E_iv : HUGE_VAL;
    const double d_cv = eta < 1 ? std::fabs(u - t.E_cv) / t.E_cv : HUGE_VAL;
    if (d_rho < kBoundaryClear || d_iv < kBoundaryClear || d_cv < kBoundaryClear) {
      ++fd_skipped;
      return;
    }
    // steps 1e-4 relative; a central stencil (±2h) that would reach a
    // boundary becomes a one-sided one (4h) pointing away from it
    const double h_rho = kFdStep * rho, h_u = kFdStep * std::max(u, double(t.E_iv));
    const int side_rho = std::fabs(rho - rho0) < 2.5 * h_rho ? (rho > rho0 ? 1 : -1) : 0;
    int side_u = 0;
    if (eta < 1 && std::fabs(u - t.E_iv) < 2.5 * h_u) side_u = u > t.E_iv ? 1 : -1;
    if (eta < 1 && std::fabs(u - t.E_cv) < 2.5 * h_u) side_u = u > t.E_cv ? 1 : -1;
    const SoundSpeedFd ref = sound_speed2_fd(p_raw, rho, u, h_rho, h_u, side_rho, side_u);
    const double denom = std::fabs(ref.c2) + kScaleFloor * c2_bulk;
    const double err = std::fabs(double(raw.c2) - ref.c2) / denom;
    fd.take(err, at(eta, u));
    fd_regime[regime].take(err, at(eta, u));
    if (near) {
      fd_near.take(err, at(eta, u));
      ++fd_near_checked;
    }
    ++fd_checked;
    // for information: the naive blend w_c c²_c + w_e c²_e, and the two closed forms
    if (raw.regime == EosRegime::TillotsonPartialVaporisation) {
      const double wc = (t.E_cv - u) / (t.E_cv - t.E_iv), we = 1 - wc;
      const TillotsonBranch c = tillotson_compressed(t, rho, u), e = tillotson_expanded(t, rho, u);
      const double nb = wc * (c.dpdrho + c.p / (rho * rho) * c.dpdu) + we * (e.dpdrho + e.p / (rho * rho) * e.dpdu);
      naive.take(std::fabs(nb - ref.c2) / denom, at(eta, u));
    }
    if (regime <= 1) {
      const double pc = tillotson_compressed(t, rho, u).p;
      forms.take(std::fabs(double(tillotson_compressed_c2_form1(t, rho, u, pc)) -
                           double(tillotson_compressed_c2_form2(t, rho, u, pc))) / denom,
                 at(eta, u));
    }
  };
  for (double eta : etas)
    for (double u : us) {
      const double rho = eta * rho0;
      const EosState raw = eos_evaluate_raw(eos, rho, u), full = eos_evaluate(eos, rho, u);
      const int regime = static_cast<int>(raw.regime) - static_cast<int>(EosRegime::TillotsonCompressed);
      if (eta >= 1) min_c2_compressed = std::min(min_c2_compressed, double(raw.c2) / c2_bulk);
      if (full.limited & kEosSoundSpeedFloor) ++floored;
      if (raw.c2 <= 0) {
        ++nonpositive;
        ++nonpositive_by_regime[regime];
        if (eta >= 1) ++nonpositive_outside;
        floor_violation.take(std::fabs(double(full.c2) - c2_bulk) / c2_bulk, at(eta, u));
      }
      fd_check(eta, u, false);
    }
  // states just outside the excluded 1e-6 band, on both sides of each boundary
  for (double d : {2e-6, 1e-5, 1e-4, 1e-3})
    for (int side : {-1, 1}) {
      for (std::size_t j = 0; j < us.size(); j += 4) fd_check(1 + side * d, us[j], true);
      for (std::size_t i = 0; i < etas.size(); i += 4)
        if (etas[i] < 1) {
          fd_check(etas[i], t.E_iv * (1 + side * d), true);
          fd_check(etas[i], t.E_cv * (1 + side * d), true);
        }
    }

  // ---- 4. the discontinuity search, with and without the cut-off ---------------------
  // along u at every kScanEta-th η (u from 1e-6 E_cv to 100 E_cv) and along η
  // at every kScanU-th u
  long found_plain = 0, found_cut_expected = 0, found_cut_unexpected = 0, scan_lines = 0;
  std::string unexpected_where, plain_where;
  auto scan = [&](const auto& pf, bool with_cut) {
    auto record_hit = [&](double eta, double u, bool along_eta) {
      const std::string where = at(eta, u);
      if (!with_cut) {
        ++found_plain;
        plain_where = where;
      } else if (along_eta && std::fabs(eta - kRhoLimit) <= 1e-9 * kRhoLimit && u < t.E_cv) {
        ++found_cut_expected;
      } else {
        ++found_cut_unexpected;
        unexpected_where = where;
      }
    };
    for (std::size_t i = 0; i < etas.size(); i += kScanEta) {
      const double rho = etas[i] * rho0;
      for (double u : find_jumps([&](double uu) { return pf(rho, uu); }, us[1], us.back(), kScanStep, kJumpTol,
                                 kScaleFloor * A))
        record_hit(etas[i], u, false);
      if (!with_cut) ++scan_lines;
    }
    for (std::size_t j = 0; j < us.size(); j += kScanU) {
      const double u = us[j];
      for (double rho : find_jumps([&](double r) { return pf(r, u); }, etas.front() * rho0, etas.back() * rho0,
                                   kScanStep, kJumpTol, kScaleFloor * A))
        record_hit(rho / rho0, u, true);
      if (!with_cut) ++scan_lines;
    }
  };
  scan(p, false);
  scan(p_cut, true);

  // ---- the maps for the report (defaults: what the solver uses) -----------------------
  std::vector<double> map_eta, map_u;
  std::vector<Json> map_p, map_cs, map_regime, map_floored;
  for (std::size_t j = 0; j < us.size(); j += kMapU) map_u.push_back(us[j]);
  for (std::size_t i = 0; i < etas.size(); i += kMapEta) {
    map_eta.push_back(etas[i]);
    std::vector<double> rp, rc, rr, rf;
    for (std::size_t j = 0; j < us.size(); j += kMapU) {
      const EosState s = eos_evaluate(eos, etas[i] * rho0, us[j]);
      rp.push_back(s.p);
      rc.push_back(std::sqrt(std::max(double(s.c2), 0.0)));
      rr.push_back(static_cast<int>(s.regime) - static_cast<int>(EosRegime::TillotsonCompressed));
      rf.push_back((s.limited & kEosSoundSpeedFloor) ? 1.0 : 0.0);
    }
    map_p.push_back(Json(rp));
    map_cs.push_back(Json(rc));
    map_regime.push_back(Json(rr));
    map_floored.push_back(Json(rf));
  }

  // ---- checks and record ------------------------------------------------------------
  Outcome o;
  const std::string issue = "issue #3 item 4";
  o.checks.push_back({"max pressure jump at eta=1, E_iv, E_cv / (|p| + A*1e-6)", jump.value, kJumpTol, "<=", issue});
  o.checks.push_back({"max |c2 - c2_FD| / (|c2_FD| + (A/rho0)*1e-6), off boundaries", fd.value, kFdTol, "<=", issue});
  o.checks.push_back({"min c2 / (A/rho0) over eta >= 1", min_c2_compressed, 0.0, ">", issue + " (c2 > 0 for eta >= 1)"});
  o.checks.push_back({"states with c2 <= 0 where the floor A/rho0 does not apply (rel. deviation)", floor_violation.value,
                      0.0, "<=", issue + "; floor: docs/physics.md (Reinhardt & Stadel 2017; Kegerreis et al. 2019)"});
  o.checks.push_back({"discontinuities found by the line search, defaults", double(found_plain), 0.0, "<=", issue});
  o.checks.push_back({"cut-off on (rho_limit=0.9): pressure jump at eta=1, E_iv, E_cv", jump_cut.value, kJumpTol, "<=",
                      issue});
  o.checks.push_back({"cut-off on: discontinuities other than at eta=rho_limit", double(found_cut_unexpected), 0.0, "<=",
                      issue + " (the only discontinuity is the documented one)"});
  o.checks.push_back({"cut-off on: scan lines finding the jump at eta=rho_limit", double(found_cut_expected), 1.0, ">=",
                      "docs/physics.md: the cut-off jumps by w_c p_c at rho_limit (the search must see it)"});
  o.checks.push_back({"cut-off on: |jump - w_c p_c| at rho_limit / (|p| + A*1e-6)", cut_mismatch.value, kJumpTol, "<=",
                      issue + "; docs/physics.md (documented jump)"});

  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<Json> checks;
  for (const auto& c : o.checks) checks.push_back(c.json());
  const long points = long(etas.size()) * long(us.size());
  const Json record = Json::object({
      {"rung", "tillotson_continuity"},
      {"case", m.name},
      {"resolution", double(points)},
      {"resolution_name", "grid points (eta x u)"},
      {"parameters", Json::object({{"eos", "tillotson"},
                                   {"rho0", double(t.rho0)},
                                   {"A", double(t.A)},
                                   {"B", double(t.B)},
                                   {"E0", double(t.E0)},
                                   {"E_iv", double(t.E_iv)},
                                   {"E_cv", double(t.E_cv)},
                                   {"a", double(t.a)},
                                   {"b", double(t.b)},
                                   {"alpha", double(t.alpha)},
                                   {"beta", double(t.beta)},
                                   {"rho_limit_tested", kRhoLimit},
                                   {"grid", std::to_string(etas.size()) + " eta x " + std::to_string(us.size()) + " u"}})},
      {"errors", Json::object({{"p_jump", Json::object({{"max_rel", jump.value}})},
                               {"c2_fd", Json::object({{"max_rel", fd.value}})},
                               {"cutoff_jump_mismatch", Json::object({{"max_rel", cut_mismatch.value}})}})},
      {"maxima", Json::object({{"p_jump", maxima_json(jump)},
                               {"p_jump_cutoff_on", maxima_json(jump_cut)},
                               {"p_plain_difference", maxima_json(plain)},
                               {"c2_fd", maxima_json(fd)},
                               {"c2_fd_next_to_boundaries", maxima_json(fd_near)},
                               {"c2_fd_compressed", maxima_json(fd_regime[0])},
                               {"c2_fd_expanded_cold", maxima_json(fd_regime[1])},
                               {"c2_fd_partial_vaporisation", maxima_json(fd_regime[2])},
                               {"c2_fd_expanded_hot", maxima_json(fd_regime[3])},
                               {"c2_naive_blend_vs_fd", maxima_json(naive)},
                               {"c2_form1_vs_form2", maxima_json(forms)},
                               {"cutoff_jump_mismatch", maxima_json(cut_mismatch)},
                               {"cutoff_jump_over_A", cut_jump_max},
                               {"min_c2_over_bulk_eta_ge_1", min_c2_compressed}})},
      {"counts", Json::object({{"grid_points", points},
                               {"fd_checked", fd_checked},
                               {"fd_skipped_within_1e-6_of_a_boundary", fd_skipped},
                               {"fd_checked_next_to_boundaries", fd_near_checked},
                               {"c2_nonpositive", nonpositive},
                               {"c2_nonpositive_expanded_cold", nonpositive_by_regime[1]},
                               {"c2_nonpositive_partial_vaporisation", nonpositive_by_regime[2]},
                               {"c2_nonpositive_expanded_hot", nonpositive_by_regime[3]},
                               {"c2_nonpositive_eta_ge_1", nonpositive_outside},
                               {"c2_floored", floored},
                               {"scan_lines", scan_lines},
                               {"jumps_found_defaults", found_plain},
                               {"jumps_found_cutoff_at_rho_limit", found_cut_expected},
                               {"jumps_found_cutoff_elsewhere", found_cut_unexpected}})},
      {"notes", Json::object({{"p_plain_difference",
                               "|p(b(1+1e-9)) - p(b(1-1e-9))| / (|p| + A*1e-6): includes the slope times 2e-9 b, so it "
                               "is not a jump; shown for information"},
                              {"c2_naive_blend_vs_fd",
                               "blending the branch c2 with the pressure weights alone misses "
                               "(p/rho^2)(p_e - p_c)/(E_cv - E_iv); shown for information"},
                              {"unexpected_jump_at", unexpected_where},
                              {"default_jump_at", plain_where}})},
      {"maps", Json::object({{"eta", Json(map_eta)},
                             {"u", Json(map_u)},
                             {"p", Json::array(map_p)},
                             {"cs", Json::array(map_cs)},
                             {"regime", Json::array(map_regime)},
                             {"floored", Json::array(map_floored)},
                             {"regime_names", Json::array({Json("compressed"), Json("expanded_cold"),
                                                           Json("partial_vaporisation"), Json("expanded_hot")})},
                             {"E_iv", double(t.E_iv)},
                             {"E_cv", double(t.E_cv)},
                             {"rho_limit_tested", kRhoLimit}})},
      {"units", Json::object({{"p", "Pa"}, {"cs", "m/s"}, {"u", "J/kg"}, {"eta", "1"}})},
      {"wall_seconds", wall},
      {"timestamp", utc_now()},
      {"checks", Json::array(checks)},
  });
  rubble::verification::write_record(args.records,
                                     "tillotson_continuity-" + m.name + "-" + std::to_string(points) + "-cpu-" +
                                         (sizeof(Real) == 8 ? "double" : "float"),
                                     record, "cpu");
  std::printf("%-10s max jump %.2e (cut-off on %.2e), max |c2-FD| %.2e over %ld states, min c2/(A/rho0) eta>=1 %.3f, "
              "c2<=0 at %ld states (floored), cut-off: %ld lines jump at rho_limit, %ld elsewhere; %.2f s\n",
              m.name.c_str(), jump.value, jump_cut.value, fd.value, fd_checked, min_c2_compressed, nonpositive,
              found_cut_expected, found_cut_unexpected, wall);
  return o;
}

// ---- ideal gas and Murnaghan: the finite-difference sound-speed check (item 5) ----

Outcome fd_case(const std::string& name, const EosParams& eos, const std::vector<double>& rhos,
                const std::vector<double>& us, double c2_scale, double u_scale, const Args& args,
                const std::vector<std::pair<std::string, Json>>& parameters) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto p_raw = [&](double rho, double u) { return double(eos_evaluate_raw(eos, rho, u).p); };
  Maximum fd;
  long checked = 0;
  for (double rho : rhos)
    for (double u : us) {
      const SoundSpeedFd ref = sound_speed2_fd(p_raw, rho, u, kFdStep * rho, kFdStep * std::max(u, u_scale));
      const double c2 = eos_evaluate_raw(eos, rho, u).c2;
      char where[80];
      std::snprintf(where, sizeof where, "rho=%.9g u=%.9g", rho, u);
      fd.take(std::fabs(c2 - ref.c2) / (std::fabs(ref.c2) + kScaleFloor * c2_scale), where);
      ++checked;
    }
  Outcome o;
  o.checks.push_back({"max |c2 - c2_FD| / (|c2_FD| + c2_scale*1e-6)", fd.value, kFdTol, "<=", "issue #3 item 5 (item 4's tolerance)"});
  std::vector<Json> checks;
  for (const auto& c : o.checks) checks.push_back(c.json());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Json record = Json::object({
      {"rung", "tillotson_continuity"},
      {"case", name},
      {"resolution", double(checked)},
      {"resolution_name", "grid points (rho x u)"},
      {"parameters", Json::object(parameters)},
      {"errors", Json::object({{"c2_fd", Json::object({{"max_rel", fd.value}})}})},
      {"maxima", Json::object({{"c2_fd", maxima_json(fd)}})},
      {"wall_seconds", wall},
      {"timestamp", utc_now()},
      {"checks", Json::array(checks)},
  });
  rubble::verification::write_record(args.records,
                                     "tillotson_continuity-" + name + "-" + std::to_string(checked) + "-cpu-" +
                                         (sizeof(Real) == 8 ? "double" : "float"),
                                     record, "cpu");
  std::printf("%-10s max |c2-FD| %.2e over %ld states (%s)\n", name.c_str(), fd.value, checked, fd.where.c_str());
  return o;
}

std::vector<double> geometric(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a * std::pow(b / a, double(i) / (n - 1));
  return v;
}


int run(const Args& args) {
  std::vector<std::string> names = args.materials.empty() ? library_material_names() : args.materials;
  if (names.empty()) throw std::runtime_error("no library materials found in '" + materials_directory() + "'");
  bool ok = true;
  int tillotson = 0;
  for (const auto& name : names) {
    const MaterialConfig m = load_material(name);
    Outcome o;
    if (m.eos == EosKind::Tillotson) {
      o = tillotson_case(m, args);
      ++tillotson;
    } else if (m.eos == EosKind::Murnaghan) {
      const EosParams e = eos_params_from_material(m);
      std::vector<double> rhos;
      for (double eta : eta_grid()) rhos.push_back(eta * m.murnaghan.rho0);
      o = fd_case(m.name, e, rhos, {0.0, m.murnaghan.K0 / m.murnaghan.rho0}, m.murnaghan.K0 / m.murnaghan.rho0,
                  m.murnaghan.K0 / m.murnaghan.rho0, args,
                  {{"eos", "murnaghan"}, {"rho0", m.murnaghan.rho0}, {"K0", m.murnaghan.K0}, {"n", m.murnaghan.n}});
    } else {
      continue;
    }
    for (const auto& c : o.checks)
      if (!c.passed()) std::printf("  FAIL %s: %s: %.3e %s %.3e (%s)\n", name.c_str(), c.name.c_str(), c.value,
                                   c.op.c_str(), c.threshold, c.source.c_str());
    ok = ok && o.passed();
  }
  if (tillotson == 0) throw std::runtime_error("no Tillotson material in the library");
  // the ideal gas, for two adiabatic indices
  for (double gamma : {1.4, 5.0 / 3.0}) {
    EosParams e;
    e.kind = EosKind::IdealGas;
    e.ideal_gas.gamma = Real(gamma);
    const std::string name = gamma == 1.4 ? "ideal_gas_gamma1.4" : "ideal_gas_gamma5_3";
    const Outcome o = fd_case(name, e, geometric(1e-3, 1e3, 61), geometric(1e-3, 1e6, 91), 0.0, 0.0, args,
                              {{"eos", "ideal_gas"}, {"gamma", gamma}});
    for (const auto& c : o.checks)
      if (!c.passed()) std::printf("  FAIL %s: %s\n", name.c_str(), c.name.c_str());
    ok = ok && o.passed();
  }
  std::printf("tillotson_continuity: %s\n", ok ? "all checks passed" : "CHECKS FAILED");
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main<Args>("tillotson_continuity_rung: ", argc, argv, run);
}
