#pragma once
// XSPH (Monaghan 1989, JCP 82:1; Monaghan 1992, ARA&A 30:543, eq. 4.3):
// particles move with a velocity smoothed over their neighbours,
//
//   dx_a/dt = v_a + eps sum_b (m_b / rhobar_ab) (v_b - v_a) W_ab,
//   rhobar_ab = (rho_a + rho_b)/2,  W_ab = (W(r, h_a) + W(r, h_b))/2,
//
// which keeps neighbouring particles moving coherently and suppresses
// interpenetration and the clumping that precedes tensile fracture (Gray,
// Monaghan & Swift 2001 use eps = 0.5 for the colliding rubber rings). The
// momentum equation is unchanged; the pair term is antisymmetric in (a, b),
// so sum_a m_a (dx_a/dt - v_a) = 0 and the centre of mass moves with the
// total momentum. eps = 0 is plain SPH.
#include "rubble/core/hd.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// One neighbour's contribution (without eps): (m_b / rhobar) (v_b - v_a) W_ab.
template <int D>
RUBBLE_HD_INLINE Vec<D> xsph_pair_term(Real m_b, Real rho_a, Real rho_b, const Vec<D>& v_ba, Real w_ab) {
  return (Real(2) * m_b * w_ab / (rho_a + rho_b)) * v_ba;
}

}  // namespace rubble
