#pragma once
// Analytic two-wave solution of planar piston compaction of a porous
// material with the p–α model (Jutzi, Benz & Michel 2008, Icarus 198:242,
// §5.1: porous aluminium driven at 458 m/s into a rigid wall; PHYSICS.md §4,
// reference test (b)). The porous EOS, the crush curve and the elastic branch
// of dα/dt are the solver's own (physics/porosity.hpp), so this reference
// checks the hydrodynamics and the time integration of the p–α model, not
// the formulas of porosity.hpp (those have their own unit tests).
//
// Frame ("piston frame"): the undisturbed material (rho0, u0, alpha0, p0,
// v = 0) fills x > 0; a piston enters it from the left at speed V > 0. Two
// plane waves run ahead of the piston:
//
//  1. The elastic precursor takes the material from p0 along the elastic
//     branch of the p–α model (α changes only through the elastic dα/dp) to
//     the kink of the loading envelope min(α_el(p), α_c(p)) of
//     porosity.hpp: the pressure p_k where the virgin elastic curve meets
//     the crush curve. The elastic branch has lowered α a little below α_e
//     at p_e, so p_k is slightly above p_e (81.3 MPa for J08's aluminium,
//     p_e = 80 MPa); p_k = p_e when the elastic branch is off. Below p_k the
//     wave speed is the elastic one, above it the much lower plastic one, so
//     the precursor carries exactly p_k (written p_E below). Its speed grows with pressure (the matrix stiffens
//     and α falls, which raises the porous sound speed c(α)), so the
//     compression steepens into a shock, a jump from state 0 to state E. Its
//     Rankine–Hugoniot conditions are
//       mass       m = rho0 (U_e − 0) = rho_E (U_e − v_E)
//       momentum   p_E − p0 = m v_E,  i.e. m² = (p_E − p0)/(1/rho0 − 1/rho_E)
//       energy     u_E − u0 = (p0 + p_E)/2 (1/rho0 − 1/rho_E)
//     and α_E is the distention at the end of the elastic path. α_E is path
//     dependent (dα/dt is a rate law, not a function of state), so it is
//     integrated along the path of a steady viscous shock structure with the
//     same mass flux m: there the total stress p + q follows the Rayleigh line
//       P(rho) = p0 + m² (1/rho0 − 1/rho)
//     and the energy equation gives du/drho = P/rho², so
//       u(rho) = u0 + p0 (1/rho0 − 1/rho) + (m²/2)(1/rho0 − 1/rho)²,
//     which ends on the energy jump above; along it
//       dα/drho = porosity_dalpha_dt(matrix, por, rho, u(rho), α, 1, P/rho²)
//     (the chain rule with drho/dt = 1, du/dt = du/drho), by RK4 in rho.
//     rho_E is found by bisection so that the end state has
//     p(rho_E, u_E, α_E) = p_E (porous_eos_evaluate). This is the path an
//     SPH shock smeared by artificial viscosity follows (a steady viscous
//     profile); the isentropic path differs from it by third order in the
//     (small, ~0.2 %) compression and changes α_E by far less than 1e-6.
//     The speed c_e of Jutzi's model is the small-amplitude speed of this
//     branch at α0; U_e lies between the path's sound speeds at 0 and E.
//
//  2. The compaction shock takes the material from E to the piston's state
//     S (v_S = V). Its end state lies ON the crush curve,
//       α_S = crush_curve_alpha(p_S),  p_S = p_s(α_S rho_S, u_S)/α_S,
//     (the min with α_E only guards round-off: for p_S > p_k the curve lies
//     below α_E), with
//     the jump conditions (front speed U_s, mass flux m_s)
//       m_s = rho_E (U_s − v_E) = rho_S (U_s − v_S)
//       p_S − p_E = m_s (v_S − v_E)   ⇒ (v_S − v_E)² = (p_S − p_E)(1/rho_E − 1/rho_S)
//       u_S − u_E = (p_E + p_S)/2 (1/rho_E − 1/rho_S).
//     For a trial p_S the density rho_S solving the EOS with the energy jump
//     is found by bisection (p grows with rho along the Hugoniot); the outer
//     unknown p_S is the root of R(p_S) = (p_S − p_E)(1/rho_E − 1/rho_S) −
//     (V − v_E)², again by bisection (R grows with p_S).
//
// When V <= v_E the piston is too slow to crush the material: a single
// elastic shock carries the state (two_waves = false) and compacted ==
// elastic. When the compaction shock found from E would be faster than the
// precursor (a strong drive: about 1.5 km/s for the aluminium of J08), the
// two-wave structure does not exist: one shock takes the undisturbed state
// to the crush curve (overdriven = true, elastic == compacted). The wall frame of Jutzi's setup (material moving at −V onto a
// rigid wall at x = 0) is the piston frame shifted by −V: sample_wall_frame.
//
// Host-only reference code in double precision (whatever rubble::Real is).
#include <cmath>
#include <stdexcept>
#include <string>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/porosity.hpp"

namespace rubble {

// A plateau: density (bulk), specific internal energy, pressure (bulk),
// distention, velocity (in the frame of the solution that returns it).
struct PorousPistonState {
  double rho = 0, u = 0, p = 0, alpha = 1, v = 0;
};

struct PorousPistonSolution {
  PorousPistonState initial, elastic, compacted;  // piston frame (initial at rest)
  double elastic_speed = 0;     // U_e, precursor speed into the undisturbed material
  double compaction_speed = 0;  // U_s, compaction shock speed (same frame)
  double piston_speed = 0;      // V
  bool two_waves = true;        // false: V <= v_E, a single elastic wave
  double p_kink = 0;             // precursor amplitude: the loading envelope's kink (>= p_e)
  bool overdriven = false;      // a single compaction shock (it would outrun the precursor); elastic == compacted
  // c_path_initial: small-amplitude speed of the elastic branch at rest
  // (forward difference along it; U_e > it for a compressive shock).
  // c_path_elastic: the backward difference at E; since E sits on the
  // envelope's kink the lower point falls below the envelope, where alpha is
  // frozen, so this is the frozen (matrix) speed there, an upper bound only
  double c_path_initial = 0, c_path_elastic = 0;
};

// Residuals of one plane jump a -> b moving at U, relative to the flux
// scales (0 for an exact jump): mass rho(U − v); momentum p + rho(U − v)²…
// written as the change of momentum flux; energy as the change of the total
// energy flux rho(U − v)(u + v²/2) + p v… the forms the solver conserves,
// independent of the Hugoniot form used to build the solution.
struct JumpResiduals {
  double mass = 0, momentum = 0, energy = 0;
};

inline JumpResiduals porous_jump_residuals(const PorousPistonState& a, const PorousPistonState& b, double U) {
  JumpResiduals r;
  const double ja = a.rho * (U - a.v), jb = b.rho * (U - b.v);
  r.mass = (ja - jb) / std::fabs(ja);
  // momentum conservation in the lab frame: d/dt(rho v) + d/dx(rho v² + p) = 0
  // across a front x = U t:  U [rho v] = [rho v² + p]
  const double mom_a = a.rho * a.v * (a.v - U) + a.p, mom_b = b.rho * b.v * (b.v - U) + b.p;
  r.momentum = (mom_b - mom_a) / (std::fabs(a.p) + std::fabs(b.p) + std::fabs(ja * (b.v - a.v)));
  // energy: U [rho E] = [rho E v + p v], E = u + v²/2
  const double Ea = a.u + 0.5 * a.v * a.v, Eb = b.u + 0.5 * b.v * b.v;
  const double en_a = a.rho * Ea * (a.v - U) + a.p * a.v, en_b = b.rho * Eb * (b.v - U) + b.p * b.v;
  r.energy = (en_b - en_a) / (std::fabs(a.p * a.v) + std::fabs(b.p * b.v) + std::fabs(ja) * (std::fabs(Ea) + std::fabs(Eb)));
  return r;
}

class PorousPiston {
 public:
  // matrix: the matrix EOS; por: the p–α parameters (por.alpha_e = alpha0);
  // rho0, u0: the undisturbed bulk density and specific energy; V: piston speed.
  PorousPiston(const EosParams& matrix, const PorosityParams& por, double rho0, double u0, double piston_speed,
               int path_steps = 1000)
      : m_(matrix), q_(por), steps_(path_steps) {
    if (!(rho0 > 0) || !(piston_speed > 0) || !(q_.alpha_e > 1) || !(q_.p_s > q_.p_e))
      throw std::invalid_argument("PorousPiston: need rho0 > 0, V > 0, alpha_e > 1, p_s > p_e");
    PorousPistonSolution& s = s_;
    s.piston_speed = piston_speed;
    s.initial = {rho0, u0, pressure(rho0, u0, q_.alpha_e), double(q_.alpha_e), 0.0};
    if (!(s.initial.p < q_.p_e))
      throw std::invalid_argument("PorousPiston: the undisturbed pressure " + std::to_string(s.initial.p) +
                                  " is not below p_e");
    // the kink of the loading envelope min(alpha_el(p), alpha_c(p))
    // (porosity.hpp): where the virgin elastic curve meets the crush curve,
    // just above p_e (81.3 MPa for J08's aluminium); p_e itself when the
    // elastic branch is off
    s.p_kink = double(q_.p_e);
    if (porosity_elastic_enabled(m_, q_)) {
      // alpha* with crush(p_el(alpha*)) = alpha*: below it the elastic curve
      // lies beyond the crush curve (crush(p_el(alpha)) < alpha), above it not
      double lo = 1, hi = q_.alpha_e;
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (!(mid > lo && mid < hi)) break;
        const double pe = double(porosity_elastic_curve_pressure(m_, q_, Real(mid)));
        if (double(crush_curve_alpha(q_, Real(pe))) < mid) lo = mid;
        else hi = mid;
      }
      s.p_kink = double(porosity_elastic_curve_pressure(m_, q_, Real(0.5 * (lo + hi))));
    }
    double U = 0;
    s.elastic = elastic_jump(s.p_kink, U);
    s.elastic_speed = U;
    if (piston_speed <= s.elastic.v) {
      // one elastic wave: find its pressure p1 in (p0, p_e] with v1 = V
      double lo = s.initial.p, hi = s.p_kink;
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (!(mid > lo && mid < hi)) break;
        double Um = 0;
        if (elastic_jump(mid, Um).v < piston_speed) lo = mid;
        else hi = mid;
      }
      s.elastic = elastic_jump(hi, U);
      s.elastic_speed = U;
      s.compacted = s.elastic;
      s.compaction_speed = U;
      s.two_waves = false;
    } else {
      compaction_jump(s.elastic);
      if (!(s.compaction_speed < s.elastic_speed)) {
        // overdriven: the compaction shock would outrun the precursor, so a
        // single shock takes the undisturbed material to the crush curve
        s.overdriven = true;
        compaction_jump(s.initial);
        s.elastic = s.compacted;
        s.elastic_speed = s.compaction_speed;
      }
    }
    s.c_path_initial = path_sound_speed(s.initial, +1);
    s.c_path_elastic = path_sound_speed(s.elastic);
  }

  const PorousPistonSolution& solution() const { return s_; }

  // Wall frame: rigid wall at x = 0, material in x > 0 arriving at −V.
  double elastic_front(double t) const { return (s_.elastic_speed - s_.piston_speed) * t; }
  double compaction_front(double t) const { return (s_.compaction_speed - s_.piston_speed) * t; }
  PorousPistonState wall_frame(const PorousPistonState& a) const {
    PorousPistonState b = a;
    b.v -= s_.piston_speed;
    return b;
  }
  PorousPistonState sample_wall_frame(double x, double t) const {
    if (x < compaction_front(t)) return wall_frame(s_.compacted);
    if (x < elastic_front(t)) return wall_frame(s_.elastic);
    return wall_frame(s_.initial);
  }

  // The bulk pressure of the solver's porous EOS.
  double pressure(double rho, double u, double alpha) const {
    return double(porous_eos_evaluate(m_, q_, Real(rho), Real(u), Real(alpha)).p);
  }

 private:
  // The elastic jump from the initial state to pressure p1 (see the header):
  // bisection on rho1 so that the end of the viscous path has pressure p1.
  PorousPistonState elastic_jump(double p1, double& U) const {
    const PorousPistonState& a = s_.initial;
    PorousPistonState end;
    auto shoot = [&](double rho1) {
      end = elastic_path(a, rho1, p1);
      return end.p - p1;
    };
    double lo = a.rho, hi = a.rho * 1.001;
    int grow = 0;
    while (shoot(hi) < 0) {
      lo = hi;
      hi = a.rho + 2 * (hi - a.rho);
      if (++grow > 60) throw std::runtime_error("PorousPiston: no elastic state reaches p = " + std::to_string(p1));
    }
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (!(mid > lo && mid < hi)) break;
      if (shoot(mid) < 0) lo = mid;
      else hi = mid;
    }
    shoot(hi);
    const double dv = 1 / a.rho - 1 / end.rho;  // specific-volume jump
    const double m = std::sqrt((p1 - a.p) / dv);
    U = m / a.rho;
    end.v = m * dv;
    end.p = p1;  // the root: equal to the EOS pressure to the bisection's round-off
    return end;
  }

  // The end state of the viscous path from a to rho1 whose Rayleigh line
  // ends at p1: u from the energy integral, alpha by RK4 in rho.
  PorousPistonState elastic_path(const PorousPistonState& a, double rho1, double p1) const {
    const double m2 = (p1 - a.p) / (1 / a.rho - 1 / rho1);
    auto u_of = [&](double rho) {
      const double dv = 1 / a.rho - 1 / rho;
      return a.u + a.p * dv + 0.5 * m2 * dv * dv;
    };
    auto rate = [&](double rho, double alpha) {
      const double P = a.p + m2 * (1 / a.rho - 1 / rho);
      return double(porosity_dalpha_dt(m_, q_, Real(rho), Real(u_of(rho)), Real(alpha), Real(1), Real(P / (rho * rho))));
    };
    double alpha = a.alpha;
    const double d = (rho1 - a.rho) / steps_;
    for (int k = 0; k < steps_; ++k) {
      const double r = a.rho + k * d;
      const double k1 = rate(r, alpha), k2 = rate(r + d / 2, alpha + d / 2 * k1);
      const double k3 = rate(r + d / 2, alpha + d / 2 * k2), k4 = rate(r + d, alpha + d * k3);
      alpha += d / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    PorousPistonState e;
    e.rho = rho1;
    e.u = u_of(rho1);
    e.alpha = alpha;
    e.p = pressure(rho1, e.u, alpha);
    return e;
  }

  // sqrt(dp/drho) along the elastic branch just below state a (u following
  // du = p/rho² drho): backward difference over 1e-6 rho with alpha from the
  // rate law evaluated at the lower point (the end state E sits on the
  // envelope's kink, above which the plastic slope would apply).
  // At the undisturbed state (sgn = +1) the difference is forward instead
  // (below it the material is in tension, where alpha is frozen).
  double path_sound_speed(const PorousPistonState& a, double sgn = -1) const {
    const double h = -sgn * 1e-6 * a.rho, du = a.p / (a.rho * a.rho);
    const double rb = a.rho - h, ub = a.u - h * du;  // the other point
    const double da = double(porosity_dalpha_dt(m_, q_, Real(rb), Real(ub), Real(a.alpha), Real(1), Real(du)));
    const double c2 = (pressure(a.rho, a.u, a.alpha) - pressure(rb, ub, a.alpha - h * da)) / h;  // h < 0: forward
    return c2 > 0 ? std::sqrt(c2) : 0.0;
  }

  // State S behind the compaction shock for a trial p_S (alpha on the crush
  // curve, energy from the Hugoniot relation, rho_S from the EOS).
  PorousPistonState compacted_state(const PorousPistonState& e, double pS) const {
    PorousPistonState c;
    c.p = pS;
    // on the crush curve; where the curve lies above alpha_E (the narrow band
    // just above p_e that the elastic branch has already crossed) alpha
    // stays alpha_E, since it never rises
    c.alpha = std::fmin(double(crush_curve_alpha(q_, Real(pS))), e.alpha);
    auto u_of = [&](double rho) { return e.u + 0.5 * (e.p + pS) * (1 / e.rho - 1 / rho); };
    auto F = [&](double rho) { return pressure(rho, u_of(rho), c.alpha) - pS; };
    double lo = e.rho * c.alpha / e.alpha * 0.999, hi = e.rho * e.alpha / c.alpha * 1.01;
    if (F(lo) > 0) lo = e.rho * 0.5;
    int grow = 0;
    while (F(hi) < 0) {
      lo = hi;
      hi *= 1.5;
      if (++grow > 100) throw std::runtime_error("PorousPiston: no compacted density reaches p = " + std::to_string(pS));
    }
    for (int it = 0; it < 300; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (!(mid > lo && mid < hi)) break;
      if (F(mid) < 0) lo = mid;
      else hi = mid;
    }
    c.rho = 0.5 * (lo + hi);
    c.u = u_of(c.rho);
    return c;
  }

  // The compaction shock from state e (the elastic state; the undisturbed one
  // when overdriven) to the piston's velocity.
  void compaction_jump(const PorousPistonState e) {
    PorousPistonSolution& s = s_;
    const double dv2 = (s.piston_speed - e.v) * (s.piston_speed - e.v);
    auto R = [&](double pS) {
      const PorousPistonState c = compacted_state(e, pS);
      return (pS - e.p) * (1 / e.rho - 1 / c.rho) - dv2;
    };
    double lo = e.p, hi = 2 * std::fmax(e.p, double(q_.p_e)) + 1;
    int grow = 0;
    while (R(hi) < 0) {
      lo = hi;
      hi *= 2;
      if (++grow > 100) throw std::runtime_error("PorousPiston: no compaction shock matches the piston speed");
    }
    for (int it = 0; it < 300; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (!(mid > lo && mid < hi)) break;
      if (R(mid) < 0) lo = mid;
      else hi = mid;
    }
    s.compacted = compacted_state(e, 0.5 * (lo + hi));
    s.compacted.v = s.piston_speed;
    const double ms = (s.compacted.p - e.p) / (s.piston_speed - e.v);  // mass flux
    s.compaction_speed = e.v + ms / e.rho;
  }

  EosParams m_;
  PorosityParams q_;
  int steps_;
  PorousPistonSolution s_;
};

}  // namespace rubble
