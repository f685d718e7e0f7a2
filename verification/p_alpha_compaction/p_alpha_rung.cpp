// Verification rung: the p–α porosity model (issue #11; PHYSICS.md §4,
// reference tests (a) and (b); Jutzi, Benz & Michel 2008, Icarus 198:242 —
// "J08"; Jutzi et al. 2009, Icarus 201:802 — "J09").
//
//   p_alpha_rung --part forced --case quadratic_aluminium|steep_pumice|quadratic_basalt
//                --records DIR [--levels 7] [--checks]
//   p_alpha_rung --part piston --scene FILE --records DIR --resolutions 250,500,...
//                [--label NAME] [--set key=value ...] [--checks]
//
// (a) forced evolution (0-D, no SPH; after Spheral's
//     PalphaAnalyticEvolutionTest, which forces one node with
//     drho/dt = sin(2 pi t), du/dt = 2 sin(2 pi t)). One element of porous
//     material, with prescribed
//       drho/dt = A [sin(2 pi t) + s],   du/dt = k drho/dt,   s = 0.3, t in [0, 1.75]
//     so rho(t) = rho0 + A[(1 − cos 2 pi t)/(2 pi) + s t] exactly and
//     u = k (rho − rho0). The drift s makes the cycle load (to t1 = 0.5 +
//     asin(s)/2 pi), unload (to t1 + 1 − 2 t1 + ... = 1 − asin(s)/2 pi),
//     reload past the first maximum (to t1 + 1) and unload again. A is set so
//     that the second maximum reaches p_e + 0.85 (p_s − p_e) on the loading
//     envelope (the first one about halfway), k = 0.5 p_s/rho0². alpha is
//     integrated, with rho and u, by Heun's method — the accepted solution of
//     the solver's rk2_adaptive (integrate/rk2_adaptive.hpp), with its clamp
//     alpha >= 1 (integrated_alpha) and its end of step (the return to the
//     loading envelope from the step's start value, porosity_end_step_particle)
//     — at fixed steps dt = 1/(100·2^l), l = 0..levels−1, using
//     porosity_dalpha_dt (physics/porosity.hpp) for the stages, with the
//     prescribed rates at the stage times. Since u is a function of rho
//     along the path, the exact alpha(t) is the state on the loading envelope
//     (porous_alpha_on_loading_curve) at the running maximum of rho.
//     Checks (issue #11; thresholds of the issue):
//       - on virgin loading beyond p_e, where the envelope is the crush curve,
//         |alpha − crush_curve_alpha(p)|/crush_curve_alpha(p) <= 1e-3 at the
//         finest step (p from the numerical alpha); the elastic stretch of the
//         envelope between p_e and its meeting with the crush curve is judged
//         the same way against the virgin elastic curve;
//       - on unloading steps (drho/dt < 0 at both stage times) alpha does not
//         change at all (== 0: dalpha/dt is clamped to <= 0 and vanishes when
//         unloading);
//       - observed order of the global error max_n |alpha_n − alpha(t_n)|:
//         least-squares slope of log error over log dt over all levels,
//         >= 1.8 (Heun is second order).
//
// (b) planar piston compaction (J08 §5.1): the 1-D scene (piston_1d.toml)
//     through run_scene at each resolution N (particles per 20 mm rod),
//     against the analytic two-wave solution
//     (reference/porous_piston.hpp) in the wall frame (x > 0 of the mirror
//     setup). Measured: the elastic front (where p crosses p_e/2, first
//     crossing from the undisturbed side, interpolated linearly between
//     particles), the compaction front (where alpha crosses (alpha_E +
//     alpha_S)/2), the plateau means of rho, p, alpha, v over the middle half
//     of each analytic plateau, L1 errors (mean over the particles in
//     [0, 1.25 x_e]) of rho, alpha, v, p, and the same L1 in Spheral's
//     definition (grid-weighted mean over [10 dx, x_free − 10 dx]).
//     Checks at the finest resolution given with --checks (issue #11; J08):
//       - each plateau value within 1 % (rho, p, alpha relative to the exact
//         plateau value; v relative to the drive speed 458 m/s, the velocity
//         scale, since the compacted plateau has v = 0);
//       - each front within 2 smoothing lengths of the analytic position,
//         the smoothing length being the solver's h (kernel support radius,
//         2 dx here; docs/scene.md hfact) of the particle nearest the front;
//       - L1 of rho, alpha, v, p falls at every refinement (ratio >= 1).
//     Also recorded, not gated: the equal-area position in rho of each
//     front (equal_area_front), where a sharp jump holding the same mass
//     would sit.
//     The elastic front check fails (2.18 h at N = 2000, a known failure in
//     CMakeLists.txt). Diagnosis (numbers from this rung, --set to vary):
//       - not the measurement: the precursor profile is nearly symmetric, its
//         equal-area position in rho (+2.34 h at N = 2000) lies even further
//         ahead than the half-amplitude point (+2.18 h), so half-amplitude
//         and the mass-conserving position agree to 0.16 h; no lag at the
//         kink (the SPH front is ahead, not behind);
//       - not the analytic speed: the SPH half-amplitude point moves at
//         3630.3 m/s between t = 0.4 and 3.5 us (N = 2000), the reference at
//         U_e − V = 3630.5 m/s (U_e = 4088.5 m/s from the solver's own EOS and
//         elastic branch; nominal c_e = 4110 m/s would give 3652 m/s);
//       - a start-up offset, set by the impulsive collision at t = 0 and
//         artificial viscosity: at N = 2000 it is 2.03 h already at t = 25 ns
//         (the front 9 dx from the wall) and 2.18–2.21 h from 0.2 to 3.5 us,
//         i.e. constant in metres (0.040–0.044 mm) once formed; it scales
//         with the viscosity (t = 0.4 us: 1.31 h at alpha = 0.5, beta = 1;
//         2.21 h at 1, 2; 4.05 h at 2, 4) and persists with the elastic
//         branch made negligible (c_e = 5349.9: 1.77 h at N = 250, 1.74 h at
//         500). With an impulsive start the only length is h (the problem is
//         self-similar: N = 250 at 3.5 us and N = 500 at 1.75 us give the
//         same profile in units of h), so the offset is c h, first order in
//         metres (0.354, 0.180, 0.0892, 0.0436 mm at N = 250 ... 2000,
//         orders 0.98, 1.01, 1.03) with c = 2.21, 2.25, 2.23, 2.18 at every N;
//       - why this front only: the precursor is weak. Its lead holds
//         (rho_E − rho0)·2.34 h = 2.3e-4 kg/m² of extra mass at N = 2000,
//         1.1 % of one particle's mass, matched by a deficit of the same size
//         in the compacted material near the collision plane; the same mass
//         moves the compaction front (jump 128 times larger) by 0.018 h.
//     So the front converges at first order but its constant exceeds the
//     issue's 2 h, with the scene's standard viscosity (alpha = 1, beta = 2).
//     Spheral's regression references for the same setup (LLNL/spheral,
//     tests/functional/Porosity/PlanarCompaction/PlanarCompaction-1d.py,
//     LnormRef["SPH"], nx = 500 over 2 cm — the same dx as our N = 500) are
//     recorded beside ours, converted from (g/cc, cm/us, Mbar) to SI. They
//     are a regression baseline of that code (tolerance 1e-5 on itself), not
//     a published convergence study; no published L1 errors for this test
//     were found.
//
// One JSON record per run (docs/report-format.md); exit 1 when a gating
// check fails.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "../common/rung.hpp"
#include "rubble/core/error.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/porosity.hpp"
#include "rubble/reference/porous_piston.hpp"
#include "rubble/run.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene_parser.hpp"

using rubble::verification::Check;
using rubble::verification::Json;
using namespace rubble;

namespace {

// The rods' artificial viscosity, for the record.
std::string viscosity_label(const rubble::ArtificialViscosity& v) {
  std::ostringstream o;
  o << "alpha " << v.alpha << ", beta " << v.beta;
  if (v.switch_on) o << ", Morris-Monaghan switch (alpha_min " << v.alpha_min << ", decay " << v.decay << ")";
  return o.str();
}


struct Args : rubble::verification::RungArgs {
  std::string part, which_case;
  int levels = 7;
  Args() : RungArgs({.taken = "--scene --records --label --set --checks --known-failure --resolutions"}) {}
  bool own_option(rubble::verification::ArgReader& r) override {
    return r.value("--part", part) || r.value("--case", which_case) || r.value("--levels", levels);
  }
  void validate() override {
    if (part != "forced" && part != "piston") throw std::runtime_error("--part forced|piston");
    if (part == "forced" && which_case.empty()) throw std::runtime_error("--part forced needs --case");
    if (part == "piston" && (scene.empty() || resolutions.empty()))
      throw std::runtime_error("--part piston needs --scene and --resolutions");
    if (levels < 5) throw std::runtime_error("--levels must be >= 5 (the step is halved at least 4 times)");
  }
};

void print_checks(const std::vector<Check>& checks) {
  for (const auto& c : checks)
    std::printf("  [%s] %s = %.6g (%s %.6g; %s)\n", c.passed() ? "PASS" : "FAIL", c.name.c_str(), c.value, c.op.c_str(),
                c.threshold, c.source.c_str());
  std::fflush(stdout);
}

Json checks_json(const std::vector<Check>& checks, bool& all_passed) {
  std::vector<Json> out;
  for (const auto& c : checks) {
    out.push_back(c.json());
    all_passed = all_passed && c.passed();
  }
  return Json::array(out);
}

// =========================== (a) forced evolution ===========================

struct ForcedCase {
  std::string name, description;
  EosParams matrix;
  PorosityParams por;
  double rho_s0;
};

PorosityParams make_quadratic(double alpha0, double p_e, double p_s, double c_e, double c_s0) {
  PorosityParams q;
  q.enabled = true;
  q.curve = CrushCurve::Quadratic;
  q.alpha_e = Real(alpha0);
  q.p_e = Real(p_e);
  q.p_s = Real(p_s);
  q.n2 = 2;
  q.c_e = Real(c_e);
  q.c_s0 = Real(c_s0);
  return q;
}

ForcedCase forced_case(const std::string& name) {
  ForcedCase c;
  c.name = name;
  if (name == "quadratic_aluminium") {
    // J08 §5.1 porous aluminium (PHYSICS.md §4) on the library's Tillotson
    // aluminium (Melosh 1989)
    c.matrix = eos_params_from_material(load_material("aluminium"));
    c.por = make_quadratic(1.275, 8e7, 7e8, 4110, 5350);
    c.description = "J08 §5.1 porous aluminium, quadratic crush curve, Tillotson aluminium matrix (Melosh 1989)";
  } else if (name == "steep_pumice") {
    // J09 pumice (PHYSICS.md §4): alpha0 = 4.64, alpha_t = 1.90, p_e = 1 MPa,
    // p_t = 68 MPa, p_s = 213 MPa, n1 = 12, n2 = 3. Matrix: the library's
    // Tillotson basalt (Benz & Asphaug 1999), our choice, not J09's. c_s0 is
    // that matrix's sound speed at rest, sqrt(A/rho0); c_e = c_s0/2 is our
    // choice (the fraction of Spheral's analytic-evolution test), not J09's.
    c.matrix = eos_params_from_material(load_material("basalt"));
    const double cs0 = std::sqrt(double(c.matrix.tillotson.A / c.matrix.tillotson.rho0));
    PorosityParams q;
    q.enabled = true;
    q.curve = CrushCurve::Steep;
    q.alpha_e = Real(4.64);
    q.alpha_t = Real(1.90);
    q.p_e = Real(1e6);
    q.p_t = Real(6.8e7);
    q.p_s = Real(2.13e8);
    q.n1 = 12;
    q.n2 = 3;
    q.c_s0 = Real(cs0);
    q.c_e = Real(0.5 * cs0);
    c.por = q;
    c.description = "J09 pumice, steep crush curve, Tillotson basalt matrix (Benz & Asphaug 1999; our choice), c_e = c_s0/2 (our choice)";
  } else if (name == "quadratic_basalt") {
    // PHYSICS.md §4 "porous basalt (impact example)": alpha0 = 1.25, p_e =
    // 0.2 GPa, p_s = 2 GPa, c_e = 1.5 km/s, on the library's Tillotson basalt;
    // c_s0 = sqrt(A/rho0) of that matrix
    c.matrix = eos_params_from_material(load_material("basalt"));
    const double cs0 = std::sqrt(double(c.matrix.tillotson.A / c.matrix.tillotson.rho0));
    c.por = make_quadratic(1.25, 2e8, 2e9, 1500, cs0);
    c.description = "PHYSICS.md §4 porous basalt, quadratic crush curve, Tillotson basalt matrix (Benz & Asphaug 1999)";
  } else {
    throw std::runtime_error("unknown --case " + name + " (quadratic_aluminium, steep_pumice, quadratic_basalt)");
  }
  if (c.matrix.kind == EosKind::Tillotson) c.rho_s0 = c.matrix.tillotson.rho0;
  else c.rho_s0 = c.matrix.murnaghan.rho0;
  return c;
}

constexpr double kPi = 3.14159265358979323846;
constexpr double kDrift = 0.3;     // s
constexpr double kEndTime = 1.75;  // load, unload, reload past the first maximum, unload

struct Forcing {
  double rho0, A, k;
  double g(double t) const { return (1 - std::cos(2 * kPi * t)) / (2 * kPi) + kDrift * t; }
  double rho(double t) const { return rho0 + A * g(t); }
  double drho(double t) const { return A * (std::sin(2 * kPi * t) + kDrift); }
  double u(double t) const { return k * (rho(t) - rho0); }
  double du(double t) const { return k * drho(t); }
};

// alpha on the loading envelope at bulk density rho (u = k (rho − rho0)).
double envelope_alpha(const ForcedCase& c, const Forcing& f, double rho) {
  return double(porous_alpha_on_loading_curve(c.matrix, c.por, Real(rho), Real(f.k * (rho - f.rho0)), c.por.alpha_e));
}
double porous_p(const ForcedCase& c, double rho, double u, double alpha) {
  return double(porous_eos_evaluate(c.matrix, c.por, Real(rho), Real(u), Real(alpha)).p);
}
// alpha on the virgin elastic curve at pressure p (p_el decreases with alpha).
double elastic_curve_alpha(const ForcedCase& c, double p) {
  double lo = 1, hi = c.por.alpha_e;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    if (double(porosity_elastic_curve_pressure(c.matrix, c.por, Real(mid))) > p) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

struct ForcedRun {
  double dt;
  int steps;
  double err_global = 0;           // max |alpha_n − alpha_exact(t_n)|
  double err_final = 0;            // |alpha_N − alpha_exact(T)|
  double dev_plastic = 0;          // virgin loading, crush-curve stretch: max rel. deviation
  double dev_elastic = 0;          // virgin loading, elastic stretch: max rel. deviation from the elastic curve
  double unload_change = 0;        // max |alpha_{n+1} − alpha_n| on unloading steps
  double reload_change = 0;        // ... on reloading steps well below the previous maximum
  long plastic_points = 0, elastic_points = 0, unload_steps = 0, reload_steps = 0;
  double max_step_fraction = 0;    // max |alpha_{n+1} − alpha_n|/alpha_n (the solver limits it to 1e-2)
  long stalled_k1 = 0;             // steps with k1 = 0 but k2 != 0 (state just below the envelope)
  std::vector<double> t, p, alpha, alpha_exact;
};

ForcedRun forced_run(const ForcedCase& c, const Forcing& f, double dt) {
  ForcedRun r;
  r.dt = dt;
  r.steps = static_cast<int>(std::lround(kEndTime / dt));
  const PorosityParams& q = c.por;
  // the rate at the numerical state (rho_n, u_n) with the prescribed rates at time t
  auto rate = [&](double t, double rho_n, double u_n, double alpha) {
    return double(porosity_dalpha_dt(c.matrix, q, Real(rho_n), Real(u_n), Real(alpha), Real(f.drho(t)), Real(f.du(t))));
  };
  double alpha = q.alpha_e, rho_max = f.rho0;
  double rho_num = f.rho0, u_num = f.u(0);  // rho and u integrated by Heun like alpha
  const int stride = std::max(1, r.steps / 4000);
  const double t_min1 = 1 - std::asin(kDrift) / (2 * kPi);                 // end of the first unloading
  const double rho_valley = f.rho(t_min1), rho_peak1 = f.rho(0.5 + std::asin(kDrift) / (2 * kPi));
  for (int n = 0; n <= r.steps; ++n) {
    const double t = n * dt, rho = rho_num, u = u_num;
    const bool virgin = f.rho(t) >= rho_max;
    rho_max = std::max(rho_max, f.rho(t));  // of the exact path: the reference
    const double exact = envelope_alpha(c, f, rho_max);
    r.err_global = std::max(r.err_global, std::fabs(alpha - exact));
    if (n == r.steps) r.err_final = std::fabs(alpha - exact);
    const double p = porous_p(c, rho, u, alpha);
    if (virgin && n > 0 && p > double(q.p_e)) {
      const double ac = double(crush_curve_alpha(q, Real(p))), ae = elastic_curve_alpha(c, p);
      if (ac <= ae) {
        r.dev_plastic = std::max(r.dev_plastic, std::fabs(alpha - ac) / ac);
        ++r.plastic_points;
      } else {
        r.dev_elastic = std::max(r.dev_elastic, std::fabs(alpha - ae) / ae);
        ++r.elastic_points;
      }
    } else if (virgin && n > 0 && p >= 0) {
      const double ae = elastic_curve_alpha(c, p);
      r.dev_elastic = std::max(r.dev_elastic, std::fabs(alpha - ae) / ae);
      ++r.elastic_points;
    }
    if (n % stride == 0 || n == r.steps) {
      r.t.push_back(t);
      r.p.push_back(p);
      r.alpha.push_back(alpha);
      r.alpha_exact.push_back(exact);
    }
    if (n == r.steps) break;
    // Heun (rk2_adaptive's accepted combination) on (rho, u, alpha), alpha
    // kept >= 1, then the solver's end of step (porosity_end_step_particle):
    // the state returned to the loading envelope from the step's start value
    // (porosity_return_bound: alpha_e while the state is virgin elastic)
    const double k1 = rate(t, rho_num, u_num, alpha);
    const double a1 = double(integrated_alpha(Real(alpha), Real(dt), Real(k1)));
    const double rho1 = rho_num + dt * f.drho(t), u1 = u_num + dt * f.du(t);
    const double k2 = rate(t + dt, rho1, u1, a1);
    double next = double(integrated_alpha(Real(alpha), Real(0.5 * dt), Real(k1 + k2)));
    rho_num += 0.5 * dt * (f.drho(t) + f.drho(t + dt));
    u_num += 0.5 * dt * (f.du(t) + f.du(t + dt));
    next = double(porous_alpha_on_loading_curve(c.matrix, q, Real(rho_num), Real(u_num),
                                                porosity_return_bound(c.matrix, q, Real(alpha))));
    r.max_step_fraction = std::max(r.max_step_fraction, std::fabs(next - alpha) / alpha);
    if (k1 == 0 && k2 != 0) ++r.stalled_k1;
    if (f.drho(t) < 0 && f.drho(t + dt) < 0) {
      r.unload_change = std::max(r.unload_change, std::fabs(next - alpha));
      ++r.unload_steps;
    } else if (t > t_min1 && f.rho(t + dt) < rho_peak1 - 0.05 * (rho_peak1 - rho_valley)) {
      // reloading, still 5 % of the unloading amplitude below the first maximum
      r.reload_change = std::max(r.reload_change, std::fabs(next - alpha));
      ++r.reload_steps;
    }
    alpha = next;
  }
  return r;
}

int run_forced(const Args& args) {
  const ForcedCase c = forced_case(args.which_case);
  const PorosityParams& q = c.por;
  Forcing f;
  f.rho0 = c.rho_s0 / double(q.alpha_e);
  f.k = 0.5 * double(q.p_s) / (f.rho0 * f.rho0);
  f.A = 0;
  // A: the second maximum (t2 = 1.5 + asin(s)/2 pi) reaches p_target on the
  // envelope; bisection on its density
  const double t1 = 0.5 + std::asin(kDrift) / (2 * kPi), t2 = t1 + 1;
  const double p_target = double(q.p_e) + 0.85 * double(q.p_s - q.p_e);
  auto p_env = [&](double rho) { return porous_p(c, rho, f.k * (rho - f.rho0), envelope_alpha(c, f, rho)); };
  double lo = f.rho0, hi = f.rho0 * double(q.alpha_e);
  while (p_env(hi) < p_target) hi *= 1.2;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    (p_env(mid) < p_target ? lo : hi) = mid;
  }
  f.A = (0.5 * (lo + hi) - f.rho0) / f.g(t2);
  const double p_peak1 = p_env(f.rho(t1)), p_peak2 = p_env(f.rho(t2));
  std::printf("%s: rho0 %.6g, A %.6g kg/m^3/s, k %.6g J/kg per kg/m^3; peaks p %.4g, %.4g Pa (p_e %.4g, p_s %.4g)\n",
              c.name.c_str(), f.rho0, f.A, f.k, p_peak1, p_peak2, double(q.p_e), double(q.p_s));

  std::vector<ForcedRun> runs;
  std::vector<double> res, errs;
  for (int l = 0; l < args.levels; ++l) {
    runs.push_back(forced_run(c, f, 1.0 / (100.0 * std::pow(2.0, l))));
    res.push_back(1 / runs.back().dt);
    errs.push_back(runs.back().err_global);
  }
  const double order = rubble::verification::observed_order(res, errs);
  bool all_passed = true;
  // crush and elastic curves for the plot
  std::vector<double> cp, ca, cel;
  const double p_hi = 1.1 * double(q.p_s);
  for (int i = 0; i <= 600; ++i) {
    const double p = p_hi * i / 600.0;
    cp.push_back(p);
    ca.push_back(double(crush_curve_alpha(q, Real(p))));
    cel.push_back(std::min(elastic_curve_alpha(c, p), double(q.alpha_e)));
  }
  for (std::size_t l = 0; l < runs.size(); ++l) {
    const ForcedRun& r = runs[l];
    const bool finest = l + 1 == runs.size();
    std::vector<Check> checks;
    Json orders = Json::object({});
    if (l > 0) {
      const double pair = std::log(runs[l - 1].err_global / r.err_global) / std::log(2.0);
      orders = Json::object({{"alpha_Linf_pairwise", pair}});
    }
    if (finest) {
      orders = Json::object({{"alpha", order}});
      if (args.checks) {
        checks.push_back({"virgin loading beyond p_e: max |alpha - crush_curve_alpha(p)|/crush_curve_alpha(p), finest dt",
                          r.dev_plastic, 1e-3, "<=", "issue #11: alpha follows the crush curve on loading (1e-3 relative)"});
        checks.push_back({"virgin elastic loading: max |alpha - alpha_el(p)|/alpha_el(p), finest dt", r.dev_elastic, 1e-3,
                          "<=", "issue #11 (same 1e-3) applied to the elastic stretch of the loading envelope (porosity.hpp)"});
        checks.push_back({"unloading steps: max |alpha_{n+1} - alpha_n|, finest dt", r.unload_change, 0.0, "<=",
                          "PHYSICS.md §4 / issue #11: alpha constant on unloading (dalpha/dt clamped, exactly 0)"});
        checks.push_back({"observed order of max_n |alpha_n - alpha(t_n)| (least squares over all dt levels)", order, 1.8,
                          ">=", "issue #11: Heun (rk2_adaptive's accepted solution) is second order"});
      }
    }
    print_checks(checks);
    Json profile;
    if (finest)
      profile = Json::object({{"x_label", "p"}, {"x", r.p}, {"alpha", r.alpha},
                              {"exact", Json::object({{"x", cp}, {"alpha", ca}, {"alpha_elastic", cel}})}});
    Json trajectory = Json::object({});
    if (finest) trajectory = Json::object({{"t", r.t}, {"p", r.p}, {"alpha", r.alpha}, {"alpha_exact", r.alpha_exact}});
    std::vector<std::pair<std::string, Json>> kv = {
        {"rung", "p_alpha_compaction"},
        {"case", "forced_" + c.name + std::string()},
        {"parameters", Json::object({{"alpha0", double(q.alpha_e)}, {"p_e", double(q.p_e)}, {"p_s", double(q.p_s)},
                                     {"p_t", double(q.p_t)}, {"alpha_t", double(q.alpha_t)}, {"n1", double(q.n1)},
                                     {"n2", double(q.n2)}, {"c_e", double(q.c_e)}, {"c_s0", double(q.c_s0)},
                                     {"rho0_bulk", f.rho0}, {"forcing_A", f.A}, {"forcing_s", kDrift}, {"forcing_k", f.k},
                                     {"end_time", kEndTime}, {"integrator", "heun (rk2_adaptive accepted solution), fixed dt"}})},
        {"description", c.description},
        {"resolution", res[l]},
        {"resolution_name", "1/dt (steps per forcing period)"},
        {"n_particles", 1},
        {"steps", r.steps},
        {"errors", Json::object({{"alpha", Json::object({{"Linf", r.err_global}, {"final", r.err_final}})},
                                 {"alpha_vs_crush_curve", Json::object({{"rel_max", r.dev_plastic}})},
                                 {"alpha_vs_elastic_curve", Json::object({{"rel_max", r.dev_elastic}})}})},
        {"observed_order", orders},
        {"diagnostics", Json::object({{"plastic_points", r.plastic_points}, {"elastic_points", r.elastic_points},
                                      {"unload_steps", r.unload_steps}, {"unload_max_change", r.unload_change},
                                      {"reload_steps_below_previous_max", r.reload_steps},
                                      {"reload_max_change", r.reload_change}, {"p_peak1", p_peak1}, {"p_peak2", p_peak2},
                                      {"max_step_fraction", r.max_step_fraction}, {"stalled_k1_steps", r.stalled_k1}})},
        {"wall_seconds", 0.0},
        {"units", Json::object({{"x", "Pa"}, {"p", "Pa"}})},
        {"checks", checks_json(checks, all_passed)},
    };
    if (finest) kv.push_back({"profile", profile}), kv.push_back({"trajectory", trajectory});
    const Json record = Json::object(kv);
    char stem[160];
    std::snprintf(stem, sizeof stem, "p_alpha_forced_%s%s_%07d", c.name.c_str(), "",
                  static_cast<int>(res[l]));
    rubble::verification::write_record(args.records, stem, record, "cpu");
    std::printf("  dt 1/%-6g steps %6d  max|alpha-exact| %.3e  final %.3e  crush dev %.3e (%ld pts)  elastic dev %.3e (%ld)"
                "  unload dalpha %.3g (%ld)  reload dalpha %.3g (%ld)  max step dalpha/alpha %.3g  k1-stalls %ld\n",
                res[l], r.steps, r.err_global, r.err_final, r.dev_plastic, r.plastic_points, r.dev_elastic,
                r.elastic_points, r.unload_change, r.unload_steps, r.reload_change, r.reload_steps, r.max_step_fraction,
                r.stalled_k1);
  }
  std::printf("  observed order (least squares, all levels) %.3f\n", order);
  // the variant is for comparison: its checks are recorded, the exit status stays 0
  return all_passed ? 0 : 1;
}

// ============================ (b) piston compaction ============================

constexpr double kRod = 0.02;        // rod length [m] (each of the two; J08's 20 mm)
constexpr double kDrive = 458.0;     // J08 §5.1 [m/s]

// Spheral's LnormRef["SPH"] L1 (PlanarCompaction-1d.py), converted to SI.
constexpr double kSpheralL1Rho = 0.06784186300927694 * 1e3;       // g/cc -> kg/m^3
constexpr double kSpheralL1V = 0.004921931042558655 * 1e4;        // cm/us -> m/s
constexpr double kSpheralL1P = 0.0022217375280911347 * 1e11;      // Mbar -> Pa
constexpr double kSpheralL1Alpha = 0.0590391542763204;

struct Particle {
  double x, rho, p, alpha, v, u, h;
};

// Where field q crosses level, scanning from the undisturbed (far) side
// towards the wall; linear interpolation between the two particles.
template <class F>
double crossing(const std::vector<Particle>& P, double level, F q) {
  for (std::size_t i = P.size() - 1; i > 0; --i) {
    const double a = q(P[i - 1]), b = q(P[i]);
    if ((a - level) * (b - level) <= 0 && a != b) {
      const double w = (level - b) / (a - b);
      return P[i].x + w * (P[i - 1].x - P[i].x);
    }
  }
  return std::nan("");
}

// The equal-area (conservation) position of a smeared jump of field q from
// the plateau value qa (x <= a) to qb (x >= b): a + integral_a^b (q − qb)/(qa −
// qb) dx (trapezoid over the particles). It is where a sharp jump with the
// same content of q would sit, the position that the Rankine–Hugoniot front
// of the analytic solution corresponds to; for a symmetric profile it is the
// half-amplitude point. A diagnostic beside the gated half-amplitude front.
template <class F>
double equal_area_front(const std::vector<Particle>& P, double a, double b, double qa, double qb, F q) {
  double x0 = std::nan(""), xp = 0, sp = 0, integral = 0;
  for (const auto& p : P) {
    if (p.x < a || p.x > b) continue;
    const double s = (q(p) - qb) / (qa - qb);
    if (std::isnan(x0)) x0 = p.x;
    else integral += 0.5 * (s + sp) * (p.x - xp);
    xp = p.x, sp = s;
  }
  return x0 + integral;
}

double h_near(const std::vector<Particle>& P, double x) {
  double best = 1e300, h = std::nan("");
  for (const auto& p : P)
    if (std::fabs(p.x - x) < best) best = std::fabs(p.x - x), h = p.h;
  return h;
}

struct Plateau {
  double rho = 0, p = 0, alpha = 0, v = 0;
  long count = 0;
};

Plateau plateau_mean(const std::vector<Particle>& P, double a, double b) {
  Plateau m;
  for (const auto& q : P)
    if (q.x >= a && q.x <= b) m.rho += q.rho, m.p += q.p, m.alpha += q.alpha, m.v += q.v, ++m.count;
  if (m.count) m.rho /= m.count, m.p /= m.count, m.alpha /= m.count, m.v /= m.count;
  else m.rho = m.p = m.alpha = m.v = std::nan("");
  return m;
}

int run_piston(const Args& args) {
  std::vector<double> res_done, e_rho, e_alpha, e_v, e_p;
  bool all_passed = true;
  std::vector<Check> all_checks;  // of every resolution, for the exit status
  const double finest = *std::max_element(args.resolutions.begin(), args.resolutions.end());
  for (double N : args.resolutions) {
    std::vector<std::string> sets = args.sets;
    sets.push_back("bodies.0.spacing=" + rubble::verification::exact_number(kRod / N));
    sets.push_back("bodies.1.spacing=" + rubble::verification::exact_number(kRod / N));
    sets.push_back("bodies.2.spacing=" + rubble::verification::exact_number(kRod / N));  // the pistons
    sets.push_back("bodies.3.spacing=" + rubble::verification::exact_number(kRod / N));
    const Scene scene = load_scene_file(args.scene, sets);
    const MaterialConfig& mc = scene.materials.at(0);
    if (!mc.porosity.enabled) throw std::runtime_error("the scene's material is not porous");
    const EosParams matrix = eos_params_from_material(mc);
    const PorosityParams& por = mc.porosity;
    const double rho0 = scene.bodies.at(1).density;
    const PorousPiston exact(matrix, por, rho0, 0.0, kDrive);
    const PorousPistonSolution& S = exact.solution();

    const FinalState fs = rubble::verification::run_in_memory(scene);
    const double t = fs.time;
    if (fs.alpha.size() != fs.rho.size()) throw std::runtime_error("the run returned no alpha field");
    std::vector<Particle> P;
    auto piston = [&](std::size_t i) { return !fs.boundary.empty() && fs.boundary[i] != 0; };
    for (std::size_t i = 0; i < fs.rho.size(); ++i)
      if (fs.x[i] > 0 && !piston(i)) P.push_back({fs.x[i], fs.rho[i], fs.p[i], fs.alpha[i], fs.v[i], fs.u[i], fs.h[i]});
    std::sort(P.begin(), P.end(), [](const Particle& a, const Particle& b) { return a.x < b.x; });
    // mirror symmetry: the left rod, reflected, should be the right one
    double asym = 0;
    {
      std::vector<std::pair<double, double>> L;
      for (std::size_t i = 0; i < fs.rho.size(); ++i)
        if (fs.x[i] < 0 && !piston(i)) L.push_back({-fs.x[i], fs.p[i]});
      std::sort(L.begin(), L.end());
      for (std::size_t i = 0; i < std::min(L.size(), P.size()); ++i) asym = std::max(asym, std::fabs(L[i].second - P[i].p));
      asym /= S.compacted.p;
    }

    const double xs = exact.compaction_front(t), xe = exact.elastic_front(t);
    const PorousPistonState Sw = exact.wall_frame(S.compacted), Ew = exact.wall_frame(S.elastic),
                            Iw = exact.wall_frame(S.initial);
    const double xs_sph = crossing(P, 0.5 * (S.elastic.alpha + S.compacted.alpha), [](const Particle& q) { return q.alpha; });
    const double xe_sph = crossing(P, 0.5 * (S.elastic.p + S.initial.p), [](const Particle& q) { return q.p; });
    const double hs = h_near(P, xs), he = h_near(P, xe);
    // equal-area positions in rho (diagnostic; mass is what the jump
    // conditions conserve): compaction front between the middles of the
    // compacted and elastic plateaus, elastic front from the middle of the
    // elastic plateau to as far ahead of x_e
    auto rho_of = [](const Particle& q) { return q.rho; };
    const double xs_ea = equal_area_front(P, 0.5 * xs, 0.5 * (xs + xe), Sw.rho, Ew.rho, rho_of);
    const double xe_ea = equal_area_front(P, 0.5 * (xs + xe), std::min(xe + 0.5 * (xe - xs), P.back().x - 0.1 * kRod),
                                          Ew.rho, Iw.rho, rho_of);
    const Plateau ps = plateau_mean(P, 0.25 * xs, 0.75 * xs);
    const Plateau pe = plateau_mean(P, xs + 0.25 * (xe - xs), xs + 0.75 * (xe - xs));

    // L1 over [0, 1.25 xe]: particle mean, and Spheral's grid-weighted mean
    // over [10 dx, x_free - 10 dx]
    double l_rho = 0, l_alpha = 0, l_v = 0, l_p = 0;
    long cnt = 0;
    double g_rho = 0, g_alpha = 0, g_v = 0, g_p = 0, g_w = 0;
    const double dx = kRod / N, gmin = 10 * dx, gmax = std::min(P.back().x, kRod) - 10 * dx;
    for (std::size_t i = 0; i < P.size(); ++i) {
      const Particle& q = P[i];
      const PorousPistonState e = exact.sample_wall_frame(q.x, t);
      const double dr = std::fabs(q.rho - e.rho), da = std::fabs(q.alpha - e.alpha), dv = std::fabs(q.v - e.v),
                   dp = std::fabs(q.p - e.p);
      if (q.x <= 1.25 * xe) l_rho += dr, l_alpha += da, l_v += dv, l_p += dp, ++cnt;
      const double r0 = std::clamp(i ? 0.5 * (P[i - 1].x + q.x) : q.x, gmin, gmax);
      const double r1 = std::clamp(i + 1 < P.size() ? 0.5 * (q.x + P[i + 1].x) : q.x, gmin, gmax);
      const double w = r1 - r0;
      g_rho += w * dr, g_alpha += w * da, g_v += w * dv, g_p += w * dp, g_w += w;
    }
    l_rho /= cnt, l_alpha /= cnt, l_v /= cnt, l_p /= cnt;
    g_rho /= g_w, g_alpha /= g_w, g_v /= g_w, g_p /= g_w;
    res_done.push_back(N);
    e_rho.push_back(l_rho), e_alpha.push_back(l_alpha), e_v.push_back(l_v), e_p.push_back(l_p);

    const bool last = N == finest;
    std::vector<Check> checks;
    const std::string src_plateau = "issue #11 / Jutzi et al. 2008 §5.1: plateaus within 1 %";
    const std::string src_front = "issue #11 / Jutzi et al. 2008 §5.1: fronts within 2 smoothing lengths";
    auto rel = [](double a, double b) { return std::fabs(a - b) / std::fabs(b); };
    if (args.checks && last) {
      const std::string at = " at N=" + rubble::verification::exact_number(N);
      checks.push_back({"compacted plateau rho rel. error" + at, rel(ps.rho, Sw.rho), 0.01, "<=", src_plateau});
      checks.push_back({"compacted plateau p rel. error" + at, rel(ps.p, Sw.p), 0.01, "<=", src_plateau});
      checks.push_back({"compacted plateau alpha rel. error" + at, rel(ps.alpha, Sw.alpha), 0.01, "<=", src_plateau});
      checks.push_back({"compacted plateau |v - v_exact|/458 m/s" + at, std::fabs(ps.v - Sw.v) / kDrive, 0.01, "<=", src_plateau});
      checks.push_back({"elastic plateau rho rel. error" + at, rel(pe.rho, Ew.rho), 0.01, "<=", src_plateau});
      checks.push_back({"elastic plateau p rel. error" + at, rel(pe.p, Ew.p), 0.01, "<=", src_plateau});
      checks.push_back({"elastic plateau alpha rel. error" + at, rel(pe.alpha, Ew.alpha), 0.01, "<=", src_plateau});
      checks.push_back({"elastic plateau |v - v_exact|/458 m/s" + at, std::fabs(pe.v - Ew.v) / kDrive, 0.01, "<=", src_plateau});
      checks.push_back({"compaction front |x - x_exact|/h" + at, std::fabs(xs_sph - xs) / hs, 2.0, "<=", src_front});
      checks.push_back({"elastic front |x - x_exact|/h" + at, std::fabs(xe_sph - xe) / he, 2.0, "<=", src_front});
      for (std::size_t k = 1; k < res_done.size(); ++k) {
        const std::string step = " ratio coarse/fine, N " + rubble::verification::exact_number(res_done[k - 1]) + " -> " + rubble::verification::exact_number(res_done[k]);
        const std::string src = "issue #11: L1 errors fall with resolution";
        checks.push_back({"L1(rho)" + step, e_rho[k - 1] / e_rho[k], 1.0, ">=", src});
        checks.push_back({"L1(alpha)" + step, e_alpha[k - 1] / e_alpha[k], 1.0, ">=", src});
        checks.push_back({"L1(v)" + step, e_v[k - 1] / e_v[k], 1.0, ">=", src});
        checks.push_back({"L1(p)" + step, e_p[k - 1] / e_p[k], 1.0, ">=", src});
      }
    }
    Json orders = Json::object({});
    if (last && res_done.size() >= 2)
      orders = Json::object({{"rho", rubble::verification::observed_order(res_done, e_rho)},
                             {"alpha", rubble::verification::observed_order(res_done, e_alpha)},
                             {"v", rubble::verification::observed_order(res_done, e_v)},
                             {"p", rubble::verification::observed_order(res_done, e_p)}});
    // profiles (right rod) and the exact solution
    std::vector<double> px, prho, pp, pa, pv, pu;
    const std::size_t stride = std::max<std::size_t>(1, P.size() / 4000);
    for (std::size_t i = 0; i < P.size(); i += stride)
      px.push_back(P[i].x), prho.push_back(P[i].rho), pp.push_back(P[i].p), pa.push_back(P[i].alpha), pv.push_back(P[i].v),
          pu.push_back(P[i].u);
    std::vector<double> ex, erho, ep, ea, ev, eu;
    auto add = [&](double x, const PorousPistonState& s) {
      ex.push_back(x), erho.push_back(s.rho), ep.push_back(s.p), ea.push_back(s.alpha), ev.push_back(s.v), eu.push_back(s.u);
    };
    add(0, Sw), add(xs, Sw), add(xs, Ew), add(xe, Ew), add(xe, Iw), add(P.back().x, Iw);

    auto plateau_json = [](const Plateau& m, const PorousPistonState& e) {
      return Json::object({{"rho", m.rho}, {"p", m.p}, {"alpha", m.alpha}, {"v", m.v}, {"particles", m.count},
                           {"exact", Json::object({{"rho", e.rho}, {"p", e.p}, {"alpha", e.alpha}, {"v", e.v}, {"u", e.u}})}});
    };
    auto L1 = [](double v) { return Json::object({{"L1", v}}); };
    const Json record = Json::object({
        {"rung", "p_alpha_compaction"},
        {"case", args.label.empty() ? std::string("piston_1d") : args.label},
        {"parameters", Json::object({{"scene", args.scene.substr(args.scene.find_last_of('/') + 1)},
                                     {"drive_speed", kDrive}, {"t", t}, {"rod_length", kRod},
                                     {"integrator", scene.simulation.integrator == Integrator::Leapfrog ? "leapfrog" : "rk2_adaptive"},
                                     {"wall", "mirror (two rods colliding at x = 0)"},
                                     {"viscosity", viscosity_label(scene.materials[0].viscosity)},
                                     {"overrides", rubble::verification::joined(args.sets)}})},
        {"resolution", N},
        {"resolution_name", "N (particles per 20 mm rod)"},
        {"n_particles", fs.rho.size()},
        {"dimension", fs.dimension},
        {"steps", static_cast<long long>(fs.steps)},
        {"errors", Json::object({{"rho", L1(l_rho)}, {"alpha", L1(l_alpha)}, {"v", L1(l_v)}, {"p", L1(l_p)}})},
        {"errors_spheral_definition", Json::object({{"rho", g_rho}, {"alpha", g_alpha}, {"v", g_v}, {"p", g_p}})},
        {"spheral_reference_L1",
         Json::object({{"rho", kSpheralL1Rho}, {"alpha", kSpheralL1Alpha}, {"v", kSpheralL1V}, {"p", kSpheralL1P},
                       {"resolution", 500},
                       {"source", "LLNL/spheral tests/functional/Porosity/PlanarCompaction/PlanarCompaction-1d.py, "
                                  "LnormRef['SPH'] (regression baseline, nx=500 over 2 cm, WendlandC4, grid-weighted L1 "
                                  "over the rod less 10 dx at each end; converted to SI). No published L1 errors found."}})},
        {"observed_order", orders},
        {"fronts", Json::object({{"compaction", Json::object({{"sph", xs_sph}, {"sph_equal_area", xs_ea}, {"exact", xs}, {"h", hs}})},
                                 {"elastic", Json::object({{"sph", xe_sph}, {"sph_equal_area", xe_ea}, {"exact", xe}, {"h", he}})}})},
        {"plateaus", Json::object({{"compacted", plateau_json(ps, Sw)}, {"elastic", plateau_json(pe, Ew)}})},
        {"analytic", Json::object({{"elastic_speed", S.elastic_speed}, {"compaction_speed", S.compaction_speed},
                                   {"c_path_initial", S.c_path_initial}, {"c_path_elastic", S.c_path_elastic},
                                   {"frame", "speeds relative to the undisturbed material; plateaus in the wall frame"}})},
        {"mirror_asymmetry_p_rel", asym},
        {"wall_seconds", fs.wall_seconds},
        {"units", Json::object({{"x", "m"}, {"rho", "kg/m^3"}, {"p", "Pa"}, {"v", "m/s"}, {"u", "J/kg"}})},
        {"checks", checks_json(checks, all_passed)},
        {"profile", Json::object({{"x", px}, {"rho", prho}, {"p", pp}, {"alpha", pa}, {"v", pv}, {"u", pu},
                                  {"exact", Json::object({{"x", ex}, {"rho", erho}, {"p", ep}, {"alpha", ea}, {"v", ev}, {"u", eu}})}})},
    });
    char stem[160];
    std::snprintf(stem, sizeof stem, "p_alpha_%s_%06d", args.label.empty() ? "piston_1d" : args.label.c_str(),
                  static_cast<int>(N));
    rubble::verification::write_record(args.records, stem, record, fs.backend);
    std::printf("piston N %6g  particles %zu  steps %lld  wall %.1f s  t %.4g\n", N, fs.rho.size(),
                static_cast<long long>(fs.steps), fs.wall_seconds, t);
    std::printf("  fronts: compaction %.5g mm (exact %.5g, |d|/h %.3g)  elastic %.5g mm (exact %.5g, |d|/h %.3g)\n",
                xs_sph * 1e3, xs * 1e3, std::fabs(xs_sph - xs) / hs, xe_sph * 1e3, xe * 1e3, std::fabs(xe_sph - xe) / he);
    std::printf("  fronts, equal-area (diagnostic): compaction (x - x_exact)/h %+.3g  elastic (x - x_exact)/h %+.3g\n",
                (xs_ea - xs) / hs, (xe_ea - xe) / he);
    std::printf("  compacted plateau rho %.6g (%.6g) p %.6g (%.6g) alpha %.6g (%.6g) v %.4g (%.4g)\n", ps.rho, Sw.rho, ps.p,
                Sw.p, ps.alpha, Sw.alpha, ps.v, Sw.v);
    std::printf("  elastic plateau   rho %.6g (%.6g) p %.6g (%.6g) alpha %.6g (%.6g) v %.4g (%.4g)\n", pe.rho, Ew.rho, pe.p,
                Ew.p, pe.alpha, Ew.alpha, pe.v, Ew.v);
    std::printf("  L1 rho %.4g alpha %.4g v %.4g p %.4g | Spheral-def rho %.4g alpha %.4g v %.4g p %.4g | asym %.2g\n", l_rho,
                l_alpha, l_v, l_p, g_rho, g_alpha, g_v, g_p, asym);
    print_checks(checks);
    all_checks.insert(all_checks.end(), checks.begin(), checks.end());
  }
  (void)all_passed;  // the record's own flag; the exit status allows for documented known failures
  return args.exit_status(all_checks);
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main<Args>("p_alpha_rung: error: ", argc, argv, [](const Args& args) {
    return args.part == "forced" ? run_forced(args) : run_piston(args);
  });
}
