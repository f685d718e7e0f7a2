#pragma once
// The elastic energy a solid particle stores, computed from its density and
// deviatoric stress alone - independent of the evolved internal energy u -
// so that an energy budget built on it can fail when the energy equation's
// strain rate differs from the one that evolves S (issue #17 item 4).
//
//   volumetric part  u_s(rho) - u_0: the specific internal energy gained
//                    along the isentrope du/drho = p(rho, u)/rho^2 from the
//                    particle's initial state (rho_0, u_0) - the pressure
//                    work alone, for any EOS (Tillotson's p depends on u, so
//                    the isentrope is integrated, not written in closed form);
//   shear part       J2 / (2 mu rho) per unit mass, J2 = S:S/2 of the full
//                    3-D deviator (plane strain in 2-D: S_zz = -(S_xx + S_yy);
//                    jaumann_rate.hpp: deviatoric_j2). Its rate is
//                    (1/rho) S:eps_dot + (J2/(2 mu rho)) tr(eps_dot): the
//                    energy equation's shear heating plus a term of relative
//                    size |strain| that the budget neglects.
// Host only, double precision: the tests and rungs' reference.
#include <cmath>

#include "rubble/core/mat.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/jaumann_rate.hpp"

namespace rubble {

// u on the isentrope through (rho0, u0) at density rho: classical RK4 in rho
// with `steps` steps (error ~ (drho)^4; 64 steps over a strain of 1e-2
// leave ~1e-14 relative).
inline double isentrope_energy(const EosParams& eos, double rho0, double u0, double rho, int steps = 64) {
  const auto f = [&](double r, double u) {
    const double p = eos_evaluate(eos, Real(r), Real(u)).p;
    return p / (r * r);
  };
  const double dr = (rho - rho0) / steps;
  double r = rho0, u = u0;
  for (int i = 0; i < steps; ++i) {
    const double k1 = f(r, u);
    const double k2 = f(r + 0.5 * dr, u + 0.5 * dr * k1);
    const double k3 = f(r + 0.5 * dr, u + 0.5 * dr * k2);
    const double k4 = f(r + dr, u + dr * k3);
    u += dr * (k1 + 2 * k2 + 2 * k3 + k4) / 6;
    r += dr;
  }
  return u;
}

// Shear strain energy per unit mass, J2 / (2 mu rho) [J/kg].
template <int D>
double shear_strain_energy(const Mat<D>& S, double mu, double rho) {
  return double(deviatoric_j2<D>(S)) / (2 * mu * rho);
}

}  // namespace rubble
