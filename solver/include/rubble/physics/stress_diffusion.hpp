#pragma once
// Deviatoric stress diffusion (after Feng, Fourtakas, Rogers & Lombardi 2021,
// Comput. Geotech. 138:104356, who add a delta-SPH-like diffusion to the
// stress rate of granular SPH to remove particle-scale stress noise):
//
//   dS_a/dt += zeta h_a c_a D_a,
//   D_a = sum_b V_b 2 (x_ab . grad_a W_ab) / (r_ab^2 + 0.01 h_a^2)
//                   (S_a - S_b - dS^H_ab),
//
// V_b = m_b/rho_b, x_ab = x_a - x_b, grad_a W_ab the kernel gradient at a.
// Without dS^H, D_a is the SPH Laplacian of S (Brookshaw 1985): since
// x_ab . grad_a W_ab = r W'(r) < 0, a particle whose stress exceeds its
// neighbours' is pulled towards them, and zeta h c D_a is a diffusion with
// coefficient zeta h c (a length times a speed), which vanishes as h -> 0.
//
// dS^H_ab is the difference of the geostatic deviator between a and b under
// the uniform body force g (simulation.gravity): a column at rest has
// sigma_v = -rho g z below its top and sigma_h = K0 sigma_v horizontally,
// whose deviator is linear in the height z = -x.g/|g|,
//
//   S^H(x) = -rho (x . g) (1 - K0) (g g^T/|g|^2 - I/3)   (+ const),
//
// so dS^H_ab = -rho (x_ab . g) (1 - K0) (g g^T/|g|^2 - I/3). Subtracting it
// keeps the diffusion from eroding the stress gradient that holds a body up
// under gravity, where the kernel is truncated at the free surface (Feng et
// al.'s correction; they take K0 = 1 - sin phi, Jaky 1944). In 2-D and 1-D
// the matrices are the in-plane blocks of the 3-D ones: the implied
// components (S_zz = -(S_xx + S_yy) in plane strain) follow.
//
// Only the deviator is diffused here; the pressure comes from the density
// (continuity) and is not (Feng et al. diffuse the full stress).
#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// dS^H_ab: the geostatic deviator's difference between a and b at
// separation dx = x_a - x_b, bulk density rho, body force g, lateral
// earth-pressure ratio K0. Zero without a body force.
template <int D>
RUBBLE_HD_INLINE Mat<D> geostatic_deviator_difference(const Vec<D>& dx, const Vec<D>& g, Real rho, Real k0) {
  const Real g2 = dot(g, g);
  if (!(g2 > Real(0))) return Mat<D>::zero();
  Mat<D> m = Mat<D>::outer(g, g) * (Real(1) / g2);
  for (int i = 0; i < D; ++i) m.m[i][i] -= Real(1) / Real(3);
  return (-rho * dot(dx, g) * (Real(1) - k0)) * m;
}

// One neighbour's contribution to D_a: V_b 2 (dx . grad_a W)/(r^2 + 0.01 h_a^2) (S_a - S_b - dS^H).
template <int D>
RUBBLE_HD_INLINE Mat<D> stress_diffusion_pair_term(const Mat<D>& S_a, const Mat<D>& S_b, const Mat<D>& dSH,
                                                   Real vol_b, const Vec<D>& dx, const Vec<D>& grad_a, Real h_a) {
  const Real f = Real(2) * vol_b * dot(dx, grad_a) / (dot(dx, dx) + Real(0.01) * h_a * h_a);
  return f * (S_a - S_b - dSH);
}

}  // namespace rubble
