#pragma once
// Artificial conductivity (Price 2008, J. Comput. Phys. 227:10040), which
// smooths the internal energy across contact discontinuities and removes the
// pressure blip at Sod's contact:
//   du_a/dt += sum_b m_b alpha_u v_sig^u (u_a - u_b) / rhobar_ab * F_ab,
// where grad_a W_ab = xhat_ab F_ab (F_ab <= 0) and
//   v_sig^u = sqrt(|p_a - p_b| / rhobar_ab).
// The pair term is antisymmetric, so sum_a m_a du_a/dt is unchanged.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

RUBBLE_HD_INLINE Real conductivity_signal_speed(Real p_a, Real p_b, Real rhobar) {
  return std::sqrt(std::fabs(p_a - p_b) / rhobar);
}

// Contribution of neighbour b to du_a/dt (without the mass m_b).
RUBBLE_HD_INLINE Real conductivity_dudt(Real alpha_u, Real vsig_u, Real u_a, Real u_b, Real rhobar, Real F_ab) {
  return alpha_u * vsig_u * (u_a - u_b) / rhobar * F_ab;
}

}  // namespace rubble
