#pragma once
// Artificial stress against the tensile instability (Monaghan 2000, JCP
// 159:290; Gray, Monaghan & Swift 2001, CMAME 190:6641). In each particle's
// principal frame of the total stress sigma = -p I + S, a tensile principal
// stress sigma'_i > 0 gets the repulsive term R'_i = -eps sigma'_i / rho^2
// (compressive ones get 0); R is rotated back to the particle frame. A pair
// adds (R_a + R_b) f_ab^n to the stress term of the momentum equation, with
// f_ab = W(r_ab) / W(dp), dp the initial particle spacing.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/physics/symmetric_eigen.hpp"

namespace rubble {

struct ArtificialStressParams {
  Real epsilon;   // typically 0.2-0.3
  Real exponent;  // n, typically 4
};

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
