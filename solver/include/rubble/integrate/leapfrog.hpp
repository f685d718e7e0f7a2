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
#include <cstddef>
#include <vector>

#include "rubble/particles/particle_store.hpp"

namespace rubble {

template <int D, class System>
void leapfrog_step(System& sys, ParticleStore<D>& ps, Real dt) {
  const std::size_t n = ps.n;
  const bool evolve_rho = !ps.drhodt.empty();
  const bool evolve_S = !ps.dSdt.empty();  // solids: the deviatoric stress
  const Real half = Real(0.5) * dt;
  std::vector<Vec<D>> v_half(n);
  std::vector<Real> u_half(n), rho_half(evolve_rho ? n : 0);
  std::vector<Mat<D>> S_half(evolve_S ? n : 0);

#pragma omp parallel for if (n > 4096)
  for (std::size_t i = 0; i < n; ++i) {
    v_half[i] = ps.v[i] + half * ps.dvdt[i];
    u_half[i] = ps.u[i] + half * ps.dudt[i];
    if (evolve_rho) rho_half[i] = ps.rho[i] + half * ps.drhodt[i];
    if (evolve_S) S_half[i] = ps.S[i] + half * ps.dSdt[i];
    // XSPH (when on) adds its correction, evaluated at the start of the step
    const Vec<D> xsph = ps.xsph_v.empty() ? Vec<D>::zero() : ps.xsph_v[i];
    ps.x[i] = sys.domain().wrap(ps.x[i] + dt * (v_half[i] + xsph));
    // predicted end-of-step values, used only inside the evaluation
    ps.v[i] = v_half[i] + half * ps.dvdt[i];
    ps.u[i] = u_half[i] + half * ps.dudt[i];
    if (evolve_rho) ps.rho[i] = rho_half[i] + half * ps.drhodt[i];
    if (evolve_S) ps.S[i] = S_half[i] + half * ps.dSdt[i];
  }
  sys.evaluate();
#pragma omp parallel for if (n > 4096)
  for (std::size_t i = 0; i < n; ++i) {
    ps.v[i] = v_half[i] + half * ps.dvdt[i];
    ps.u[i] = u_half[i] + half * ps.dudt[i];
    if (evolve_rho) ps.rho[i] = rho_half[i] + half * ps.drhodt[i];
    if (evolve_S) ps.S[i] = S_half[i] + half * ps.dSdt[i];
  }
}

}  // namespace rubble
