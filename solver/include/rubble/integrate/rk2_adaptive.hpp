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
// (Frobenius norms). A step with err > tol is
// rejected and retried; the next step size is
//   dt_new = dt * clamp(0.9 (tol/err)^(1/3), 0.2, 2),
// never above the Courant and force limits.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "rubble/particles/particle_store.hpp"

namespace rubble {

struct Rk2Result {
  Real dt_taken;  // the step that was accepted
  Real dt_next;   // proposal for the next step
  int rejections;
};

template <int D, class System>
Rk2Result rk2_adaptive_step(System& sys, ParticleStore<D>& ps, Real dt, Real tol, Real dt_min) {
  const std::size_t n = ps.n;
  const bool evolve_rho = !ps.drhodt.empty();
  const bool evolve_S = !ps.dSdt.empty();  // solids
  const ParticleStore<D> y0 = ps;  // state and k1 (its rates)
  int rejections = 0;
  // dx/dt: v, plus the XSPH correction when the run uses it
  const auto xdot = [](const ParticleStore<D>& y, std::size_t i) { return position_rate(y, i); };

  for (;;) {
    // stage 2: y_n + dt k1
#pragma omp parallel for if (n > 4096)
    for (std::size_t i = 0; i < n; ++i) {
      ps.x[i] = sys.domain().wrap(y0.x[i] + dt * xdot(y0, i));
      ps.v[i] = y0.v[i] + dt * y0.dvdt[i];
      ps.u[i] = y0.u[i] + dt * y0.dudt[i];
      if (evolve_rho) ps.rho[i] = y0.rho[i] + dt * y0.drhodt[i];
      if (evolve_S) ps.S[i] = y0.S[i] + dt * y0.dSdt[i];
    }
    sys.evaluate();
    const ParticleStore<D> y1 = ps;  // k2 = rates of y1

    // stage 3: y_n + dt/4 (k1 + k2)
    const Real q = Real(0.25) * dt;
#pragma omp parallel for if (n > 4096)
    for (std::size_t i = 0; i < n; ++i) {
      ps.x[i] = sys.domain().wrap(y0.x[i] + q * (xdot(y0, i) + xdot(y1, i)));
      ps.v[i] = y0.v[i] + q * (y0.dvdt[i] + y1.dvdt[i]);
      ps.u[i] = y0.u[i] + q * (y0.dudt[i] + y1.dudt[i]);
      if (evolve_rho) ps.rho[i] = y0.rho[i] + q * (y0.drhodt[i] + y1.drhodt[i]);
      if (evolve_S) ps.S[i] = y0.S[i] + q * (y0.dSdt[i] + y1.dSdt[i]);
    }
    sys.evaluate();  // k3 = rates in ps

    // Heun solution and the error against SSP-RK3:
    // y_heun - y_rk3 = (2/3) dt [ (k1 + k2)/2 - k3 ].
    const Real c23 = Real(2) / Real(3) * dt;
    Real err = 0;
    ParticleStore<D>& k3 = ps;
#pragma omp parallel for reduction(max : err) if (n > 4096)
    for (std::size_t i = 0; i < n; ++i) {
      const Vec<D> dx = c23 * (Real(0.5) * (xdot(y0, i) + xdot(y1, i)) - xdot(k3, i));
      const Vec<D> dv = c23 * (Real(0.5) * (y0.dvdt[i] + y1.dvdt[i]) - k3.dvdt[i]);
      const Real du = c23 * (Real(0.5) * (y0.dudt[i] + y1.dudt[i]) - k3.dudt[i]);
      Real e = std::max(norm(dx) / y0.h[i], norm(dv) / (norm(y0.v[i]) + y0.cs[i] + Real(1e-300)));
      e = std::max(e, std::fabs(du) / (std::fabs(y0.u[i]) + y0.cs[i] * y0.cs[i] + Real(1e-300)));
      if (evolve_rho) {
        const Real drho = c23 * (Real(0.5) * (y0.drhodt[i] + y1.drhodt[i]) - k3.drhodt[i]);
        e = std::max(e, std::fabs(drho) / y0.rho[i]);
      }
      if (evolve_S) {
        const Mat<D> dS = c23 * (Real(0.5) * (y0.dSdt[i] + y1.dSdt[i]) - k3.dSdt[i]);
        const Real scale = std::sqrt(double_dot(y0.S[i], y0.S[i])) + y0.rho[i] * y0.cs[i] * y0.cs[i] + Real(1e-300);
        e = std::max(e, std::sqrt(double_dot(dS, dS)) / scale);
      }
      err = std::max(err, e);
    }

    const Real grow = err > 0 ? Real(0.9) * std::cbrt(tol / err) : Real(2);
    const Real factor = std::clamp(grow, Real(0.2), Real(2));
    if (err <= tol || dt <= dt_min) {
      const Real h2 = Real(0.5) * dt;
#pragma omp parallel for if (n > 4096)
      for (std::size_t i = 0; i < n; ++i) {
        ps.x[i] = sys.domain().wrap(y0.x[i] + h2 * (xdot(y0, i) + xdot(y1, i)));
        ps.v[i] = y0.v[i] + h2 * (y0.dvdt[i] + y1.dvdt[i]);
        ps.u[i] = y0.u[i] + h2 * (y0.dudt[i] + y1.dudt[i]);
        if (evolve_rho) ps.rho[i] = y0.rho[i] + h2 * (y0.drhodt[i] + y1.drhodt[i]);
        if (evolve_S) ps.S[i] = y0.S[i] + h2 * (y0.dSdt[i] + y1.dSdt[i]);
      }
      sys.evaluate();  // k1 of the next step
      return {dt, dt * factor, rejections};
    }
    // rejected: back to y_n with a smaller step
    ps = y0;
    dt = std::max(dt * factor, dt_min);
    ++rejections;
  }
}

}  // namespace rubble
