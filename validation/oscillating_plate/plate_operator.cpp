// Operator-level check of the oscillating plate (issue #17 item 1): the
// period of the plate's lowest bending mode from rubble's own linearised
// right-hand side, without time stepping.
//
//   plate_operator --scene FILE --resolutions 5,8,12 [--hfact 2.0,2.4]
//                  [--epsilon 0,0.3] [--records DIR] [--label NAME] [--set key=value ...]
//                  [--ungrouped] [--check-grouping]
//
// For every resolution n (particles through the thickness H, dx = H/n),
// support radius hfact (H_kernel/dx) and artificial-stress epsilon, the
// plate scene is built at rest (positions fixed for good) and the real
// evaluation (the step sequence's evaluate: continuity density, EOS, kernel-gradient
// correction, Hooke's law, artificial stress, clamp) is probed:
//   1. a small velocity on one degree of freedom j of one free particle,
//      everything else at rest (groups of dofs far enough apart not to
//      interact are probed in one evaluation): the rates dS/dt and drho/dt of every
//      particle (clamp included) are the column B e_j of the strain map;
//   2. those rates, times tau, as the stress and density of an otherwise
//      resting state: the acceleration of every free particle is tau K e_j,
//      K = d2v/dt2 per unit velocity. It is taken as the central difference
//      of the states +tau B e_j and -tau B e_j.
// About the rest state the evaluation is linear in (v, S, rho) except for
// the artificial stress, which acts on the tensile principal stresses only:
// the central difference takes the mean of its two one-sided slopes
// (R -> -(eps/2) sigma/rho^2 on every principal stress), the linear model
// of a mode whose cross-section is half in tension, half in compression.
// The viscosity acts only on approaching pairs and needs a velocity, so it
// does not enter K (a lossless operator, as the thin-plate theory is).
// Positions do not move, so XSPH and the Jaumann rotation (quadratic in the
// perturbation) do not enter either.
//
// The lowest bending mode is the eigenvalue -omega^2 of K nearest the shift
// -(omega_theory / 1.15)^2, found by inverse iteration with a banded LU of
// K - shift I (dofs ordered by x, so K is banded), started from the
// Euler-Bernoulli mode shape. Its eigenvector's thickness-averaged v_y is
// correlated with that shape: >= 0.99 says the mode is the bending mode
// and not one of SPH's spurious (near zero-energy) modes.
//
// Checks: every configuration converges to a bending mode (correlation >=
// 0.99); for each support radius and epsilon the period error falls from each
// resolution to the next (the operator converges), and the period
// extrapolated by T(n) = T_inf (1 + a/n + b/n^2) is within 2 % of the
// thin-plate theory (issue #17 item 2's bound for the time-domain rung's
// limit). The period errors and T_inf are reported beside the time-domain
// rung (docs/verification.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "../../verification/common/args.hpp"
#include "../../verification/common/record.hpp"
#include "plate.hpp"
#include "rubble/drivers/cpu_stepper.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/scene/scene.hpp"

namespace {

using rubble::Real;

std::string g(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", x);
  return b;
}
using rubble::verification::Check;
using rubble::verification::Json;

struct Args {
  std::string scene, records = "reports/records", label = "plate_operator";
  std::vector<double> resolutions, hfacts = {2.4}, epsilons = {0.0, 0.3};
  std::vector<std::string> sets, known_failures;
  bool ungrouped = false;  // one dof per probe (slow): a check of the grouping
  bool check_grouping = false;  // also the coarsest case ungrouped: the periods must agree
};

Args parse(int argc, char** argv) {
  Args a;
  rubble::verification::ArgReader r(argc, argv);
  while (!r.done())
    if (!(r.value("--scene", a.scene) || r.value("--records", a.records) || r.value("--label", a.label) ||
          r.list("--resolutions", a.resolutions) || r.list("--hfact", a.hfacts) || r.list("--epsilon", a.epsilons) ||
          r.append("--set", a.sets) || r.append("--known-failure", a.known_failures) ||
          r.flag("--ungrouped", a.ungrouped) || r.flag("--check-grouping", a.check_grouping)))
      r.unknown();
  if (a.scene.empty() || a.resolutions.empty()) throw std::runtime_error("need --scene and --resolutions");
  rubble::verification::require_increasing_whole(a.resolutions, 1, "particles through the thickness");
  return a;
}

// Gaussian elimination with partial pivoting of a banded matrix kept in
// dense row-major storage: lower bandwidth p, upper q (pivoting widens the
// upper band to p + q). Solves A x = b for many right-hand sides.
class BandedLu {
 public:
  BandedLu(std::vector<double> a, std::size_t n, std::size_t p, std::size_t q) : a_(std::move(a)), n_(n), p_(p), q_(q + p) {
    piv_.resize(n_);
    for (std::size_t k = 0; k < n_; ++k) {
      const std::size_t last = std::min(n_ - 1, k + p_);
      std::size_t r = k;
      for (std::size_t i = k + 1; i <= last; ++i)
        if (std::fabs(at(i, k)) > std::fabs(at(r, k))) r = i;
      piv_[k] = r;
      const std::size_t cend = std::min(n_ - 1, k + q_);
      if (r != k)
        for (std::size_t j = k; j <= cend; ++j) std::swap(at(k, j), at(r, j));
      const double d = at(k, k);
      if (d == 0) throw std::runtime_error("singular shifted operator (the shift is an eigenvalue)");
      for (std::size_t i = k + 1; i <= last; ++i) {
        const double f = at(i, k) / d;
        at(i, k) = f;
        if (f != 0)
          for (std::size_t j = k + 1; j <= cend; ++j) at(i, j) -= f * at(k, j);
      }
    }
  }
  std::vector<double> solve(std::vector<double> b) const {
    for (std::size_t k = 0; k < n_; ++k) {
      std::swap(b[k], b[piv_[k]]);
      const std::size_t last = std::min(n_ - 1, k + p_);
      for (std::size_t i = k + 1; i <= last; ++i) b[i] -= at(i, k) * b[k];
    }
    for (std::size_t k = n_; k-- > 0;) {
      const std::size_t cend = std::min(n_ - 1, k + q_);
      double s = b[k];
      for (std::size_t j = k + 1; j <= cend; ++j) s -= at(k, j) * b[j];
      b[k] = s / at(k, k);
    }
    return b;
  }

 private:
  double& at(std::size_t i, std::size_t j) { return a_[i * n_ + j]; }
  double at(std::size_t i, std::size_t j) const { return a_[i * n_ + j]; }
  std::vector<double> a_;
  std::size_t n_, p_, q_;
  std::vector<std::size_t> piv_;
};

struct ModeResult {
  double period = 0, error = 0, correlation = 0, seconds = 0;
  std::size_t dofs = 0, bandwidth = 0, iterations = 0, probes = 0;
  bool converged = false;
};

ModeResult bending_mode(const Args& args, double n, double hfact, double eps, bool ungrouped) {
  const auto start = std::chrono::steady_clock::now();
  const rubble::Scene base = rubble::load_scene_file(args.scene, args.sets);
  const rubble::plate::Plate plate = rubble::plate::plate_of(base);
  const double dx = plate.H / n;
  std::vector<std::string> sets = args.sets;
  for (std::size_t i = 0; i < base.bodies.size(); ++i)
    sets.push_back("bodies." + std::to_string(i) + ".spacing=" + rubble::verification::exact_number(dx));
  sets.push_back("simulation.hfact=" + rubble::verification::exact_number(hfact));
  const std::string mat = "materials." + base.materials[0].name + ".artificial_stress.";
  if (eps > 0) sets.push_back(mat + "epsilon=" + rubble::verification::exact_number(eps));
  else sets.push_back(mat + "enabled=false");
  rubble::Scene scene = rubble::load_scene_file(args.scene, sets);
  for (rubble::BodyConfig& b : scene.bodies) b.velocity = {0.0, 0.0, 0.0};

  const rubble::Features needs = rubble::features_of_scene(scene);
  rubble::ParticleStore<2> ps;
  rubble::generate_bodies<2>(scene, hfact, needs, ps);
  const rubble::Box<2> domain = rubble::domain_from_scene<2>(scene);
  // as given: sorted and evaluated below, not by the stepper
  rubble::CpuStepper<2> sys(scene, ps, domain, /*resumed=*/true);
  sys.sort_particles();
  const std::size_t np = ps.n;
  const std::vector<Real> rho_rest = ps.rho, u_rest = ps.u, h_rest = ps.h;

  // free particles ordered by x, then y: K is banded in this order
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < np; ++i)
    if (ps.boundary.empty() || ps.boundary[i] == 0) free.push_back(i);
  std::sort(free.begin(), free.end(), [&](std::size_t a, std::size_t b) {
    return ps.x[a][0] != ps.x[b][0] ? ps.x[a][0] < ps.x[b][0] : ps.x[a][1] < ps.x[b][1];
  });
  const std::size_t nd = 2 * free.size();

  auto rest = [&]() {
    for (std::size_t i = 0; i < np; ++i) {
      ps.v[i] = rubble::Vec<2>::zero();
      ps.S[i] = rubble::Mat<2>::zero();
      ps.rho[i] = rho_rest[i];
      ps.u[i] = u_rest[i];
      ps.h[i] = h_rest[i];
    }
  };
  // Probes: a velocity v_probe on one dof moves the stress of the particles
  // within one kernel support Hk of it, and so the acceleration of those
  // within 2 Hk. Dofs whose particles lie more than 4 Hk apart cannot reach
  // a common particle, so one evaluation probes a whole group of them: the
  // particles whose lattice indices agree modulo P > 4 Hk/dx (and one
  // component). Each response is attributed to the group member within
  // 2 Hk of it (there is at most one). --ungrouped probes one dof per
  // evaluation; --check-grouping compares both on each sweep's coarsest
  // case (the ctest does).
  const double cl = std::sqrt((plate.K + 4.0 / 3.0 * plate.mu) / plate.rho0);
  const Real v_probe = Real(1e-6 * cl);  // strains of ~1e-6: far inside the linear range
  const Real tau = Real(dx / cl);
  const double Hk = hfact * dx, reach = 2 * Hk * (1 + 1e-9);
  const long P = ungrouped ? 1000 : long(std::floor(4 * Hk / dx)) + 1;
  double xmin = 1e300, ymin = 1e300;
  for (const std::size_t i : free) xmin = std::min(xmin, double(ps.x[i][0])), ymin = std::min(ymin, double(ps.x[i][1]));
  std::vector<std::vector<std::size_t>> groups(std::size_t(P * P));  // members: indices into `free`
  for (std::size_t m = 0; m < free.size(); ++m) {
    const long ix = std::lround((double(ps.x[free[m]][0]) - xmin) / dx), iy = std::lround((double(ps.x[free[m]][1]) - ymin) / dx);
    groups[std::size_t((ix % P) * P + iy % P)].push_back(m);
  }
  std::vector<double> K(nd * nd, 0.0);
  std::vector<rubble::Mat<2>> dS(np);
  std::vector<Real> drho(np);
  std::vector<rubble::Vec<2>> a_plus(np);
  std::size_t probes = 0;
  for (const std::vector<std::size_t>& group : groups) {
    if (group.empty()) continue;
    // the member each free particle's response belongs to (or none)
    std::vector<std::ptrdiff_t> owner(free.size(), -1);
    for (std::size_t m = 0; m < free.size(); ++m)
      for (const std::size_t q : group)
        if (rubble::norm(ps.x[free[m]] - ps.x[free[q]]) <= Real(reach)) {
          if (owner[m] >= 0) throw std::runtime_error("probe group members within 4 Hk of each other");
          owner[m] = std::ptrdiff_t(q);
        }
    for (int comp = 0; comp < 2; ++comp) {
      ++probes;
      rest();
      for (const std::size_t q : group) ps.v[free[q]][comp] = v_probe;
      sys.evaluate();
      for (std::size_t i = 0; i < np; ++i) dS[i] = ps.dSdt[i], drho[i] = ps.drhodt[i];
      for (const int sign : {1, -1}) {
        rest();
        for (std::size_t i = 0; i < np; ++i) {
          ps.S[i] = (Real(sign) * tau) * dS[i];
          ps.rho[i] = rho_rest[i] + Real(sign) * tau * drho[i];
        }
        sys.evaluate();
        if (sign > 0) {
          for (std::size_t i = 0; i < np; ++i) a_plus[i] = ps.dvdt[i];
          continue;
        }
        for (std::size_t m = 0; m < free.size(); ++m) {
          const rubble::Vec<2> am = ps.dvdt[free[m]], ap = a_plus[free[m]];
          if (owner[m] < 0) {
            if (ap[0] != 0 || ap[1] != 0 || am[0] != 0 || am[1] != 0)
              throw std::runtime_error("a probe reached a particle beyond 2 Hk: the grouping is wrong");
            continue;
          }
          const std::size_t j = 2 * std::size_t(owner[m]) + std::size_t(comp);
          for (int c = 0; c < 2; ++c)
            K[(2 * m + std::size_t(c)) * nd + j] = double(ap[c] - am[c]) / (2 * double(tau) * double(v_probe));
        }
      }
    }
  }
  ModeResult r;
  r.dofs = nd;
  r.probes = probes;
  std::size_t lower = 0, upper = 0;
  for (std::size_t i = 0; i < nd; ++i)
    for (std::size_t j = 0; j < nd; ++j)
      if (K[i * nd + j] != 0) {
        if (i > j) lower = std::max(lower, i - j);
        else upper = std::max(upper, j - i);
      }
  r.bandwidth = std::max(lower, upper);

  // inverse iteration about the shift, from the beam's mode shape
  const double shift = -std::pow(plate.omega / 1.15, 2);
  std::vector<double> A = K;
  for (std::size_t i = 0; i < nd; ++i) A[i * nd + i] -= shift;
  const BandedLu lu(std::move(A), nd, lower, upper);
  const double k = rubble::plate::kKL / plate.L;
  std::vector<double> x(nd, 0.0);
  for (std::size_t m = 0; m < free.size(); ++m) {
    const double s = double(ps.x[free[m]][0]) - plate.xc;
    x[2 * m + 1] = s > 0 ? rubble::plate::mode_shape(k * s) : 0.0;
  }
  double lambda = shift, prev = 0;
  for (r.iterations = 1; r.iterations <= 200; ++r.iterations) {
    const std::vector<double> y = lu.solve(x);
    const double xy = std::inner_product(x.begin(), x.end(), y.begin(), 0.0);
    const double xx = std::inner_product(x.begin(), x.end(), x.begin(), 0.0);
    lambda = shift + xx / xy;
    const double norm = std::sqrt(std::inner_product(y.begin(), y.end(), y.begin(), 0.0));
    for (std::size_t i = 0; i < nd; ++i) x[i] = y[i] / norm;
    if (r.iterations > 2 && std::fabs(lambda - prev) <= 1e-12 * std::fabs(lambda)) {
      r.converged = true;
      break;
    }
    prev = lambda;
  }
  // thickness-averaged v_y per column against the beam shape
  std::vector<double> col_x, col_v;
  for (std::size_t m = 0; m < free.size(); ++m) {
    const double px = double(ps.x[free[m]][0]);
    if (col_x.empty() || std::fabs(px - col_x.back()) > 1e-9 * plate.L) col_x.push_back(px), col_v.push_back(0.0);
    col_v.back() += x[2 * m + 1];
  }
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t c = 0; c < col_x.size(); ++c) {
    const double s = col_x[c] - plate.xc;
    const double f = s > 0 ? rubble::plate::mode_shape(k * s) : 0.0;
    sab += f * col_v[c], saa += f * f, sbb += col_v[c] * col_v[c];
  }
  r.correlation = std::fabs(sab) / std::sqrt(saa * sbb);
  r.period = lambda < 0 ? 2 * std::numbers::pi / std::sqrt(-lambda) : NAN;
  r.error = r.period / plate.period - 1;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

int main(int argc, char** argv) try {
  const Args a = parse(argc, argv);
  const rubble::Scene scene = rubble::load_scene_file(a.scene, a.sets);
  const rubble::plate::Plate plate = rubble::plate::plate_of(scene);
  const char* as_form = rubble::artificial_stress_form_name(scene.materials[0].artificial_stress.form);
  std::printf("thin-plate theory: T = %.6g s (L = %g m, H = %g m, E = %.6g Pa, nu = %.4f)\n", plate.period, plate.L,
              plate.H, plate.E, plate.nu);
  std::vector<Check> all;
  for (const double hf : a.hfacts)
    for (const double eps : a.epsilons) {
      // one case per (support, eps), one record per resolution; a check is
      // written into the record of the resolution it judges
      const std::string cfg = "eps " + g(eps) + ", support " + g(hf) + " dx";
      const std::string label = a.label + "_s" + g(hf) + "_eps" + g(eps);
      std::vector<ModeResult> res;
      std::vector<std::vector<Check>> checks(a.resolutions.size());
      for (std::size_t i = 0; i < a.resolutions.size(); ++i) {
        const double n = a.resolutions[i];
        const ModeResult m = bending_mode(a, n, hf, eps, a.ungrouped);
        if (a.check_grouping && i == 0) {
          // the grouped probes against one dof per probe (--check-grouping)
          const ModeResult u = bending_mode(a, n, hf, eps, true);
          std::printf("  ungrouped: T %.9g s (grouped %.9g s), %zu probes\n", u.period, m.period, u.probes);
          checks[i].push_back({"grouped probes give the ungrouped period, " + cfg + ", H/dx " + g(n) +
                                   ": |T_grouped/T_ungrouped - 1|",
                               std::fabs(m.period / u.period - 1), 1e-9, "<=",
                               "the grouping only saves evaluations (round-off of the eigenvalue: ~1e-12)"});
        }
        std::printf("H/dx %4g  support %.2f dx  eps %.2f  dofs %5zu  band %4zu  T %.6g s  error %+7.2f %%  "
                    "shape corr %.5f  iters %3zu  probes %4zu  %.1f s\n",
                    n, hf, eps, m.dofs, m.bandwidth, m.period, 100 * m.error, m.correlation, m.iterations, m.probes,
                    m.seconds);
        std::fflush(stdout);
        checks[i].push_back({"bending mode found, " + cfg + ", H/dx " + g(n) + ": correlation with the beam shape",
                             m.converged ? m.correlation : 0.0, 0.99, ">=",
                             "the inverse iteration converged to the first bending mode, not a spurious SPH mode"});
        if (i > 0)
          checks[i].push_back({"period error falls from H/dx " + g(a.resolutions[i - 1]) + " to " + g(n) + ", " + cfg +
                                   ": |e_fine| - |e_coarse|",
                               std::fabs(m.error) - std::fabs(res.back().error), 0.0, "<=",
                               "a consistent operator converges (issue #17 item 1)"});
        res.push_back(m);
      }
      double e_inf = NAN, a_coef = NAN;
      if (res.size() >= 2) {
        // the extrapolated period of the operator (plate.hpp)
        std::vector<double> periods;
        for (const ModeResult& m : res) periods.push_back(m.period);
        const rubble::plate::PeriodLimit fit = rubble::plate::extrapolate_period(
            std::vector<double>(a.resolutions.begin(), a.resolutions.begin() + res.size()), periods);
        e_inf = fit.T_inf / plate.period - 1;
        a_coef = fit.a;
        std::printf("  fit T = T_inf (1 + a/n%s): T_inf error %+.2f %%, a = %.3f\n", fit.terms == 3 ? " + b/n^2" : "",
                    100 * e_inf, a_coef);
        checks.back().push_back({"T_inf within 2 % of thin-plate theory, " + cfg + ": |T_inf/T_theory - 1|",
                                 std::fabs(e_inf), 0.02, "<=",
                                 "issue #17 item 2's bound for the limit of the time-domain rung, applied to the "
                                 "operator"});
      }
      for (std::size_t i = 0; i < res.size(); ++i) {
        const ModeResult& m = res[i];
        bool passed = true;
        const Json check_json = rubble::verification::judge_checks(checks[i], passed);
        all.insert(all.end(), checks[i].begin(), checks[i].end());
        const Json record = Json::object({
            {"rung", "oscillating_plate"},
            {"case", label},
            {"parameters", Json::object({{"method", "linearised right-hand side (plate_operator)"}, {"L", plate.L},
                                         {"H", plate.H}, {"E", plate.E}, {"nu", plate.nu}, {"hfact", hf},
                                         {"artificial_stress_epsilon", eps},
                                         {"artificial_stress_form", eps > 0 ? as_form : "off"},
                                         {"theory_period", plate.period}})},
            {"resolution", a.resolutions[i]},
            {"resolution_name", "H/dx"},
            {"n_particles", double(m.dofs / 2)},
            {"dimension", 2},
            {"errors", Json::object({{"period", Json::object({{"rel", std::fabs(m.error)}})}})},
            {"measures", Json::object({{"period", m.period}, {"signed_error", m.error},
                                       {"shape_correlation", m.correlation}, {"dofs", double(m.dofs)},
                                       {"probes", double(m.probes)}, {"iterations", double(m.iterations)},
                                       {"t_inf_error", e_inf}, {"t_inf_a", a_coef}})},
            {"wall_seconds", m.seconds},
            {"checks", check_json},
        });
        rubble::verification::write_record(a.records, "oscillating_plate-" + label + "-" + g(a.resolutions[i]),
                                           record, "cpu");
      }
    }
  return rubble::verification::rung_exit_status(all, a.known_failures);
} catch (const std::exception& e) {
  std::fprintf(stderr, "plate_operator: error: %s\n", e.what());
  return 2;
}
