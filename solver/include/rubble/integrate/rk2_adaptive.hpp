#pragma once
// Embedded second-order Runge-Kutta with error control (after miluphcuda's
// rk2_adaptive). Three evaluations per step share their first two stages
// between Heun's method (2nd order, the accepted solution) and the
// Shu-Osher SSP-RK3 scheme (3rd order, the error estimate):
//   k1 = f(y_n)
//   k2 = f(y_n + dt k1)
//   k3 = f(y_n + dt/4 (k1 + k2))
//   y_heun = y_n + dt/2 (k1 + k2)
//   y_rk3  = y_n + dt/6 (k1 + k2 + 4 k3)
//   err = max over particles and fields of |y_heun - y_rk3| / scale
// with scale h for positions, |v| + c_s for velocities, |u| + c_s^2 for the
// internal energy (c_s^2 is the medium's mechanical energy scale, so a cold
// solid with u = 0 is not held to an absolute error of zero) and rho for
// density, and |S| + rho c_s^2 for the deviatoric stress of solids
// (Frobenius norms; not for porous particles, below).
// Left out of the error, their change per step limited instead
// (dt_limit_particle), as for leapfrog:
//  - the damage root delta = D^(1/d) (kDamageStepChange);
//  - the distention alpha of porous materials (kAlphaStepFraction): its
//    rate switches at the loading envelope (compaction on it, none below,
//    porosity.hpp), so a stage on one side and a stage on the other make
//    the embedded estimate of order dt instead of dt^2, and the controller
//    shrinks the step without end (issue #50 item 5: a basalt disc at
//    4.4 km/s into porous_basalt stepped at 2e-11 s from first contact,
//    1/3000 of its Courant step). The accepted alpha does not come from
//    this integration anyway: the end of each step returns it to the
//    envelope (porosity_end_step_particle);
//  - for the same reason the deviatoric stress of porous particles, whose
//    rate carries J08's factor f = 1 + (rho/alpha) dalpha/drho
//    (porosity.hpp), which switches with alpha's rate.
// miluphcuda's rk2_adaptive, the scheme's source, controls x, v, rho and u
// only (src/rk2adaptive.cu: RK2_USE_VELOCITY/DENSITY/ENERGY_ERROR).
// With both left out that impact steps at ~5e-9 s (the velocity error then
// sets it; test_integrators: Rk2Porous.*).
// After the accepted combination the system's end_step() runs (the plastic
// return, when a material yields), then the evaluation for the next k1. A step with err > tol is
// rejected and retried; the next step size is
//   dt_new = dt * clamp(0.9 (tol/err)^(1/3), 0.2, 2),
// never above the Courant and force limits.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/particles/store_view.hpp"

namespace rubble {

struct Rk2Result {
  Real dt_taken;  // the step that was accepted
  Real dt_next;   // proposal for the next step
  int rejections;
};

// One particle of a stage: y = y0 + w k_a (kb == nullptr) or
// y = y0 + w (k_a + k_b), where k_a, k_b are the rates held by the views
// ka, kb (dx/dt = v plus the XSPH correction when on).
template <int D>
RUBBLE_HD_INLINE void rk2_combine(const StoreView<D>& y, const StoreView<D>& y0, const StoreView<D>& ka,
                                  const StoreView<D>* kb, Real w, const Box<D>& domain, std::size_t i) {
  if (!kb) {
    y.x[i] = domain.wrap(y0.x[i] + w * ka.position_rate(i));
    y.v[i] = y0.v[i] + w * ka.dvdt[i];
    y.u[i] = y0.u[i] + w * ka.dudt[i];
    if (y.drhodt) y.rho[i] = y0.rho[i] + w * ka.drhodt[i];
    if (y.dSdt) y.S[i] = y0.S[i] + w * ka.dSdt[i];
    if (y.dalphadt) y.alpha[i] = integrated_alpha(y0.alpha[i], w, ka.dalphadt[i]);
    if (y.ddamage_root_dt) y.damage_root[i] = integrated_damage_root(y0.damage_root[i], w, ka.ddamage_root_dt[i]);
    if (y.dav_alpha_dt) y.av_alpha[i] = integrated_switch_alpha(y0.av_alpha[i], w, ka.dav_alpha_dt[i]);
    return;
  }
  y.x[i] = domain.wrap(y0.x[i] + w * (ka.position_rate(i) + kb->position_rate(i)));
  y.v[i] = y0.v[i] + w * (ka.dvdt[i] + kb->dvdt[i]);
  y.u[i] = y0.u[i] + w * (ka.dudt[i] + kb->dudt[i]);
  if (y.drhodt) y.rho[i] = y0.rho[i] + w * (ka.drhodt[i] + kb->drhodt[i]);
  if (y.dSdt) y.S[i] = y0.S[i] + w * (ka.dSdt[i] + kb->dSdt[i]);
  if (y.dalphadt) y.alpha[i] = integrated_alpha(y0.alpha[i], w, ka.dalphadt[i] + kb->dalphadt[i]);
  if (y.ddamage_root_dt)
    y.damage_root[i] = integrated_damage_root(y0.damage_root[i], w, ka.ddamage_root_dt[i] + kb->ddamage_root_dt[i]);
  if (y.dav_alpha_dt) y.av_alpha[i] = integrated_switch_alpha(y0.av_alpha[i], w, ka.dav_alpha_dt[i] + kb->dav_alpha_dt[i]);
}

// The scaled error of particle i: y_heun - y_rk3 = c23 [ (k1 + k2)/2 - k3 ]
// with c23 = 2 dt / 3, each field over its scale (see above).
template <int D>
RUBBLE_HD_INLINE Real rk2_error_particle(const StoreView<D>& y0, const StoreView<D>& y1, const StoreView<D>& k3,
                                         Real c23, std::size_t i) {
  const Vec<D> dx = c23 * (Real(0.5) * (y0.position_rate(i) + y1.position_rate(i)) - k3.position_rate(i));
  const Vec<D> dv = c23 * (Real(0.5) * (y0.dvdt[i] + y1.dvdt[i]) - k3.dvdt[i]);
  const Real du = c23 * (Real(0.5) * (y0.dudt[i] + y1.dudt[i]) - k3.dudt[i]);
  const Real ex = norm(dx) / y0.h[i], ev = norm(dv) / (norm(y0.v[i]) + y0.cs[i] + Real(1e-300));
  Real e = ex > ev ? ex : ev;
  const Real eu = std::fabs(du) / (std::fabs(y0.u[i]) + y0.cs[i] * y0.cs[i] + Real(1e-300));
  e = eu > e ? eu : e;
  if (y0.drhodt) {
    const Real drho = c23 * (Real(0.5) * (y0.drhodt[i] + y1.drhodt[i]) - k3.drhodt[i]);
    const Real er = std::fabs(drho) / y0.rho[i];
    e = er > e ? er : e;
  }
  const bool porous = y0.alpha && y0.alpha[i] > Real(1);  // alpha and S of porous particles: see above
  if (y0.dSdt && !porous) {
    const Mat<D> dS = c23 * (Real(0.5) * (y0.dSdt[i] + y1.dSdt[i]) - k3.dSdt[i]);
    const Real scale = std::sqrt(double_dot(y0.S[i], y0.S[i])) + y0.rho[i] * y0.cs[i] * y0.cs[i] + Real(1e-300);
    const Real es = std::sqrt(double_dot(dS, dS)) / scale;
    e = es > e ? es : e;
  }
  return e;
}

// Step-size factor from the error: clamp(0.9 (tol/err)^(1/3), 0.2, 2).
RUBBLE_HD_INLINE Real rk2_step_factor(Real err, Real tol) {
  const Real grow = err > 0 ? Real(0.9) * std::cbrt(tol / err) : Real(2);
  return grow < Real(0.2) ? Real(0.2) : grow > Real(2) ? Real(2) : grow;
}

// The largest of two values, as std::max and thrust::maximum pick it.
struct MaxOf {
  RUBBLE_HD Real operator()(Real a, Real b) const { return a < b ? b : a; }
};

// One accepted step of `sys`, written once for every backend. Beyond what
// leapfrog_step asks of the system (leapfrog.hpp): reduce(n, f, init, op),
// and copies of the whole store: save_state(copy), restore_state(copy),
// view_of(copy).
template <int D, class System>
Rk2Result rk2_adaptive_step(System& sys, Real dt, Real tol, Real dt_min) {
  const std::size_t n = sys.size();
  auto& w = sys.integrator_scratch();
  sys.save_state(w.y0);  // state and k1 (its rates)
  const StoreView<D> v0 = sys.view_of(w.y0);
  const Box<D> domain = sys.domain();
  int rejections = 0;
  // rigid tools (physics/rigid_body.hpp), when the system has them, take
  // the same stages: rigid_rk2_stage(w, with_k2) sets each tool to
  // y_n + w (k1 [+ k2]) and places its particles
  constexpr bool tools = requires { sys.rigid_rk2_begin(); };
  if constexpr (tools) sys.rigid_rk2_begin();

  for (;;) {
    const StoreView<D> y = sys.view();
    // stage 2: y_n + dt k1
    sys.for_each("rk2 stage 2", n,
                 [=] RUBBLE_LAMBDA(std::uint32_t i) { rk2_combine<D>(y, v0, v0, nullptr, dt, domain, i); });
    if constexpr (tools) sys.rigid_rk2_stage(dt, false);
    sys.evaluate();
    sys.save_state(w.y1);  // k2 = rates of y1
    if constexpr (tools) sys.rigid_rk2_keep_k2();
    const StoreView<D> v1 = sys.view_of(w.y1);

    // stage 3: y_n + dt/4 (k1 + k2)
    const Real q = Real(0.25) * dt;
    sys.for_each("rk2 stage 3", n,
                 [=] RUBBLE_LAMBDA(std::uint32_t i) { rk2_combine<D>(y, v0, v0, &v1, q, domain, i); });
    if constexpr (tools) sys.rigid_rk2_stage(q, true);
    sys.evaluate();  // k3 = rates in the store

    // Heun solution and the error against SSP-RK3
    const Real c23 = Real(2) / Real(3) * dt;
    const Real err = sys.reduce(
        n, [=] RUBBLE_LAMBDA(std::uint32_t i) { return rk2_error_particle<D>(v0, v1, y, c23, i); }, Real(0), MaxOf{});

    const Real factor = rk2_step_factor(err, tol);
    if (err <= tol || dt <= dt_min) {
      const Real h2 = Real(0.5) * dt;
      sys.for_each("rk2 final", n,
                   [=] RUBBLE_LAMBDA(std::uint32_t i) { rk2_combine<D>(y, v0, v0, &v1, h2, domain, i); });
      if constexpr (tools) sys.rigid_rk2_stage(h2, true);
      sys.end_step(v0.alpha, dt);
      sys.evaluate();  // k1 of the next step
      return {dt, dt * factor, rejections};
    }
    // rejected: back to y_n with a smaller step
    sys.restore_state(w.y0);
    if constexpr (tools) sys.rigid_rk2_restore();
    dt = std::max(dt * factor, dt_min);
    ++rejections;
  }
}

}  // namespace rubble
