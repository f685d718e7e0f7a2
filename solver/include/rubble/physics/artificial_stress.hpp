#pragma once
// Artificial stress against the tensile instability (Monaghan 2000, JCP
// 159:290; Gray, Monaghan & Swift 2001, CMAME 190:6641). In each particle's
// principal frame of the total stress sigma = -p I + S, a tensile principal
// stress sigma'_i > 0 gets the repulsive term R'_i = -eps sigma'_i / rho^2
// (compressive ones get 0); R is rotated back to the particle frame. A pair
// adds (R_a + R_b) f_ab^n to the stress term of the momentum equation, with
// f_ab = W(r_ab) / W(dp), dp the initial particle spacing.
//
// Monaghan's form acts wherever a principal stress is tensile, and so also
// on a smooth field on a regular lattice: there it adds -eps c sigma_+ to the
// stress, c the nearest neighbours' share of the kernel's second moment
// (~0.5 at support 2.4 dx with the cubic spline), so the material is softer
// in tension by a fraction that does not fall with resolution (issue #17
// item 3: the oscillating plate's extrapolated period stays 5.4-5.7 % long).
// The "clumping" form (rubble's default) scales R_a by a weight chi_a in
// [0, 1] that is zero while the particle's nearest neighbour is at least
// the local mean spacing s_a = (m_a/rho_a)^(1/D) away, and reaches 1 when
// it is closer than full * s_a (clumping_weight below): the correction acts
// where the tensile instability pairs particles up, and not on a smoothly
// strained lattice, whose bias becomes second order in the strain.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/physics/symmetric_eigen.hpp"

namespace rubble {

// R_a from the particle's total stress sigma and density.
template <int D>
RUBBLE_HD_INLINE Mat<D> artificial_stress_tensor(const Mat<D>& sigma, Real rho, Real epsilon) {
  const SymmetricEigen<D> e = symmetric_eigen(sigma);
  Mat<D> R = Mat<D>::zero();
  for (int i = 0; i < D; ++i) {
    if (e.lambda[i] <= Real(0)) continue;
    const Real r = -epsilon * e.lambda[i] / (rho * rho);
    // add r v_i v_i^T (rotate the principal value back)
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) R.m[a][b] += r * e.V.m[a][i] * e.V.m[b][i];
  }
  return R;
}

// The local mean particle spacing (m/rho)^(1/D): the lattice spacing of a
// cubic lattice of particles of mass m at density rho.
template <int D>
RUBBLE_HD_INLINE Real local_spacing(Real m, Real rho) {
  const Real v = m / rho;
  if constexpr (D == 1) return v;
  else if constexpr (D == 2) return std::sqrt(v);
  else return std::cbrt(v);
}

// chi of the clumping form: 0 while r_min >= onset * s, 1 once r_min <=
// full * s, linear between (continuous in r_min, so R_a stays continuous in
// time). onset <= 0 selects Monaghan's form (chi = 1 everywhere).
RUBBLE_HD_INLINE Real clumping_weight(Real r_min, Real spacing, Real onset, Real full) {
  if (onset <= Real(0)) return Real(1);
  const Real chi = (onset - r_min / spacing) / (onset - full);
  return chi <= Real(0) ? Real(0) : (chi >= Real(1) ? Real(1) : chi);
}

// f_ab^n with f_ab = W(r_ab)/W(dp): both kernel values at the same h.
RUBBLE_HD_INLINE Real artificial_stress_factor(Real w_r, Real w_dp, Real exponent) {
  if (w_dp <= Real(0)) return Real(0);
  const Real f = w_r / w_dp;
  // integer exponents are the common case; pow covers the rest
  const int n = static_cast<int>(exponent);
  if (Real(n) == exponent && n >= 0 && n <= 8) {
    Real fn = 1;
    for (int k = 0; k < n; ++k) fn *= f;
    return fn;
  }
  return std::pow(f, exponent);
}

}  // namespace rubble
