#pragma once
// Kernel-gradient correction (Randles & Libersky 1996; Bonet & Lok 1999):
//   C_a = ( sum_b (m_b/rho_b) (x_b - x_a) (x) grad_a W_ab )^-1
// so that corrected gradients C_a grad_a W_ab reproduce linear fields
// exactly. Near free surfaces and in sparse regions the sum can be nearly
// singular; then the correction falls back to the identity and the caller
// counts the particle (the counter is reported with the run).
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"

namespace rubble {

// One neighbour's contribution to the matrix being inverted.
template <int D>
RUBBLE_HD_INLINE Mat<D> correction_pair_term(Real m_b, Real rho_b, const Vec<D>& x_ba, const Vec<D>& grad_a_w) {
  return (m_b / rho_b) * Mat<D>::outer(x_ba, grad_a_w);
}

// Invert the summed matrix. Returns false (and the identity) when it is
// ill-conditioned: |det| below min_det relative to the product of its row
// norms (a scale-free measure; the lattice value is ~1).
template <int D>
RUBBLE_HD_INLINE bool correction_matrix(const Mat<D>& sum, Real min_det, Mat<D>& C) {
  Real rows = 1;
  for (int i = 0; i < D; ++i) {
    Real r2 = 0;
    for (int j = 0; j < D; ++j) r2 += sum.m[i][j] * sum.m[i][j];
    rows *= std::sqrt(r2);
  }
  const Real det = determinant(sum);
  if (!(rows > Real(0)) || !(std::fabs(det) >= min_det * rows)) {
    C = Mat<D>::identity();
    return false;
  }
  C = inverse(sum);
  return true;
}

// How much the correction can lengthen a kernel gradient: max(1, ||K||_inf),
// the largest absolute row sum of K = C^T (an upper bound of its spectral
// norm). Where the kernel is truncated - a free surface, an edge, a corner -
// C_a is about the inverse of the kernel's missing share, ~2 on a face and
// ~4 at a corner in 2-D, and the corrected stress terms (solid.hpp) are
// that much stiffer, so the particle's highest frequency rises by the same
// factor: the time step divides h by it (dt_limit_particle). Measured: a 2-D
// basalt block with corrected momentum and energy equations ran away at
// Courant 0.3 with the uncorrected limit and is stable with this one
// (solver/tests/test_solid_run.cpp, ElasticEnergyBudget...).
template <int D>
RUBBLE_HD_INLINE Real correction_gain(const Mat<D>& K) {
  Real g = 1;
  for (int i = 0; i < D; ++i) {
    Real row = 0;
    for (int j = 0; j < D; ++j) row += std::fabs(K.m[i][j]);
    g = row > g ? row : g;
  }
  return g;
}

}  // namespace rubble
