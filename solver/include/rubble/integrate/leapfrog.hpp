#pragma once
// Kick-drift-kick leapfrog (symplectic, second order; e.g. Springel 2005,
// MNRAS 364:1105, §2.5). The rates in the store must be those of the current
// state on entry; on return they are those of the new state, so each step
// costs one evaluation of the right-hand side.
//
//   v_{1/2} = v_n + dt/2 a_n          (likewise u, rho with continuity density, and S for solids)
//   x_{n+1} = x_n + dt v_{1/2}    (+ dt dv_XSPH,n with XSPH, xsph.hpp)
//   evaluate a_{n+1} at x_{n+1} (with v, u predicted to t_{n+1} for the viscosity)
//   v_{n+1} = v_{1/2} + dt/2 a_{n+1}
//   end of step: the system's end_step(alpha_n) (porous states back onto the
//   loading envelope from alpha_n; plastic return, when a material yields)
// Solids with simulation.stress_update = "staggered" advance S and rho as
// the central-difference scheme of explicit structural dynamics does
// (Belytschko, Liu & Moran 2000, Nonlinear Finite Elements for Continua and
// Structures, §6.2.2: the stress at t_{n+1} from the strain rate of
// v_{n+1/2}, before the forces of t_{n+1}):
//
//   v_{1/2} = v_n + dt/2 a_n,  x_{n+1} = x_n + dt v_{1/2}
//   pass 1 with v_{1/2}: L, dS/dt, drho/dt;  S_{n+1} = S_n + dt dS/dt, rho likewise
//   pass 2 with S_{n+1}, p(rho_{n+1}) (and v_{1/2} for the viscosity): a_{n+1}
//   v_{n+1} = v_{1/2} + dt/2 a_{n+1}
//   u_{n+1} = u_n + dt du/dt, du/dt the step's trapezoidal work (the
//             evaluation's; predicted as u_n + dt (du/dt)_n for its EOS)
//
// The predicted form above is, for the linear elastic waves of a solid (S
// and rho are driven by v, v by S and rho), a two-stage explicit scheme
// whose amplification factor exceeds 1 by ~(omega dt)^4/8 for a mode of
// frequency omega: without viscosity a resting lattice's fastest modes grow
// (docs/physics.md, "Stress update"). The staggered form is symplectic for
// that linear system (|g| = 1 for omega dt < 2), at the same one evaluation
// per step.
// The distention alpha of porous materials is evolved like u, and kept >= 1
// (integrated_alpha); its rate is <= 0, so alpha never rises. The damage
// root delta = D^(1/d) of damaged solids likewise, kept <= 1 with a rate >= 0
// (integrated_damage_root), and held to its cap at the end of the step. The
// viscosity switch's alpha likewise (kept >= 0, held to its bounds at the
// end of the step).
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/particles/store_view.hpp"
#include "rubble/physics/damage.hpp"
#include "rubble/physics/viscosity_switch.hpp"

namespace rubble {

// The half-step values a leapfrog step keeps between its two halves
// (nullptr for fields the run does not evolve).
template <int D>
struct LeapfrogHalf {
  Vec<D>* v = nullptr;
  Real* u = nullptr;
  Real* rho = nullptr;
  Mat<D>* S = nullptr;
  Real* alpha = nullptr;
  Real* damage_root = nullptr;
  Real* av_alpha = nullptr;  // the viscosity switch's alpha
  // the staggered stress update: S and rho are not kicked (S, rho are
  // nullptr here); the evaluation sees v_{1/2} and advances them itself,
  // and u (u_n here) advances by dt du/dt at the end of the step
  bool staggered = false;
};

// alpha0 + w d alpha/dt, never below 1 (full compaction); w >= 0 and
// d alpha/dt <= 0, so alpha never rises (porosity.hpp).
RUBBLE_HD_INLINE Real integrated_alpha(Real alpha0, Real w, Real dalphadt) {
  const Real a = alpha0 + w * dalphadt;
  return a > Real(1) ? a : Real(1);
}

// Second half: v, u (rho, S) from the half step with the new rates (u a
// whole step from u_n under the staggered stress update).
template <int D>
RUBBLE_HD_INLINE void leapfrog_kick(const StoreView<D>& s, const LeapfrogHalf<D>& half_state, std::size_t i, Real dt) {
  const Real half = Real(0.5) * dt;
  s.v[i] = half_state.v[i] + half * s.dvdt[i];
  s.u[i] = half_state.u[i] + (half_state.staggered ? dt : half) * s.dudt[i];
  if (half_state.rho) s.rho[i] = half_state.rho[i] + half * s.drhodt[i];
  if (half_state.S) s.S[i] = half_state.S[i] + half * s.dSdt[i];
  if (half_state.alpha) s.alpha[i] = integrated_alpha(half_state.alpha[i], half, s.dalphadt[i]);
  if (half_state.damage_root)
    s.damage_root[i] = integrated_damage_root(half_state.damage_root[i], half, s.ddamage_root_dt[i]);
  if (half_state.av_alpha) s.av_alpha[i] = integrated_switch_alpha(half_state.av_alpha[i], half, s.dav_alpha_dt[i]);
}

// First half of particle i's step: kick to the half step, drift the
// position (with the XSPH correction when on), and predict the end-of-step
// values that the evaluation at the new positions uses.
template <int D>
RUBBLE_HD_INLINE void leapfrog_kick_drift(const StoreView<D>& s, const LeapfrogHalf<D>& half_state, const Box<D>& domain,
                                          std::size_t i, Real dt) {
  const Real half = Real(0.5) * dt;
  half_state.v[i] = s.v[i] + half * s.dvdt[i];
  half_state.u[i] = half_state.staggered ? s.u[i] : s.u[i] + half * s.dudt[i];
  if (half_state.rho) half_state.rho[i] = s.rho[i] + half * s.drhodt[i];
  if (half_state.S) half_state.S[i] = s.S[i] + half * s.dSdt[i];
  if (half_state.alpha) half_state.alpha[i] = integrated_alpha(s.alpha[i], half, s.dalphadt[i]);
  if (half_state.damage_root)
    half_state.damage_root[i] = integrated_damage_root(s.damage_root[i], half, s.ddamage_root_dt[i]);
  if (half_state.av_alpha) half_state.av_alpha[i] = integrated_switch_alpha(s.av_alpha[i], half, s.dav_alpha_dt[i]);
  // XSPH (when on) adds its correction, evaluated at the start of the step
  const Vec<D> xsph = s.xsph_v ? s.xsph_v[i] : Vec<D>::zero();
  s.x[i] = domain.wrap(s.x[i] + dt * (half_state.v[i] + xsph));
  // the staggered update: the evaluation sees v_{1/2}, S and rho of the
  // step's start, and u predicted a whole step (porous and damaged
  // materials, whose alpha and D would be predicted here, are refused)
  if (half_state.staggered) {
    s.v[i] = half_state.v[i];
    s.u[i] = half_state.u[i] + dt * s.dudt[i];
    return;
  }
  leapfrog_kick<D>(s, half_state, i, dt);  // predicted end-of-step values
}

// The arrays a step keeps between its stages, owned by the system (so a
// run allocates them once): Array is std::vector on the host, the CUDA
// backend's device array there; Store a copy of the particle store
// (ParticleStore, DeviceStore) for the RK2 stages.
template <int D, template <class> class Array, class Store>
struct IntegratorScratch {
  Array<Vec<D>> v_half;
  Array<Real> u_half, rho_half, alpha_half, alpha_start, damage_half, av_half;
  Array<Mat<D>> S_half;
  Store y0, y1;  // rk2_adaptive_step: y_n with k1, and the second stage with k2
};

// One kick-drift-kick step of `sys`, written once for every backend. The
// system supplies (rubble/drivers/step_sequence.hpp, or a test's host
// system): size(), view(), domain(), integrator_scratch(),
// for_each(what, n, f) running f(i) for every particle, evaluate(), and
// end_step(alpha_start, dt); with the staggered stress update also
// evaluate_staggered(dt) (which advances S and rho between its passes);
// with rigid tools rigid_drift(dt, staggered) and rigid_kick(dt), the
// tools' own halves of the step (drivers/step_sequence.hpp).
template <int D, class System>
void leapfrog_step(System& sys, Real dt, bool staggered = false) {
  const std::size_t n = sys.size();
  const StoreView<D> s = sys.view();
  auto& w = sys.integrator_scratch();
  // the half-step arrays of the fields the run evolves (nullptr: not kicked)
  auto half_array = [n](auto& array, bool used) {
    if (!used) return decltype(array.data())(nullptr);
    array.resize(n);
    return array.data();
  };
  const LeapfrogHalf<D> half{half_array(w.v_half, true),
                             half_array(w.u_half, true),
                             half_array(w.rho_half, s.drhodt && !staggered),
                             half_array(w.S_half, s.dSdt && !staggered),
                             half_array(w.alpha_half, s.dalphadt != nullptr),
                             half_array(w.damage_half, s.ddamage_root_dt != nullptr),
                             half_array(w.av_half, s.dav_alpha_dt != nullptr),
                             staggered};
  // porous materials: the distention at the start of the step (end_step)
  Real* alpha_start = half_array(w.alpha_start, s.dalphadt != nullptr);
  if (alpha_start) {
    const Real* alpha = s.alpha;
    sys.for_each("leapfrog alpha_n", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { alpha_start[i] = alpha[i]; });
  }
  const Box<D> domain = sys.domain();
  sys.for_each("leapfrog kick-drift", n,
               [=] RUBBLE_LAMBDA(std::uint32_t i) { leapfrog_kick_drift<D>(s, half, domain, i, dt); });
  // rigid tools (physics/rigid_body.hpp), when the system has them: their
  // own kick-drift, and their particles placed at the new pose
  constexpr bool tools = requires { sys.rigid_drift(dt, staggered); };
  if constexpr (tools) sys.rigid_drift(dt, staggered);
  if constexpr (requires { sys.evaluate_staggered(dt); }) {
    if (staggered) sys.evaluate_staggered(dt);
    else sys.evaluate();
  } else {
    if (staggered) throw std::logic_error("leapfrog_step: this system has no staggered evaluation");
    sys.evaluate();
  }
  sys.for_each("leapfrog kick", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { leapfrog_kick<D>(s, half, i, dt); });
  if constexpr (tools) sys.rigid_kick(dt);
  sys.end_step(alpha_start, dt);
}

}  // namespace rubble
