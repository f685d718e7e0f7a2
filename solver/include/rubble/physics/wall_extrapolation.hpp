#pragma once
// The state of a wall particle extrapolated from the material it holds:
// the generalised wall boundary condition of Adami, Hu & Adams 2012
// (J. Comput. Phys. 231:7057, their eq. 27), extended to solids by
// extrapolating the deviatoric stress the same way.
//
// For a wall particle w with free neighbours f (kernel weights W_wf):
//
//   p_w   = [ sum_f p_f W_wf + (g - a_w) . sum_f rho_f (x_w - x_f) W_wf ] / sum_f W_wf
//   S_w   = sum_f S_f W_wf / sum_f W_wf
//   rho_w = sum_f rho_f W_wf / sum_f W_wf,   c_w = sum_f c_f W_wf / sum_f W_wf
//
// p_w is the Shepard interpolation of the neighbours' pressure plus the
// hydrostatic increase across the distance to the wall particle, which makes
// a body at rest under the body force g balance exactly at the wall
// (Adami et al. 2012, sec. 2.3). The increase is added only when it is
// positive (the wall particle lies below its neighbours, along g): a wall
// that rises above the material's free surface would otherwise get the
// linear field continued past the surface, a tension that pulls material up
// the wall (measured: -225 Pa at the top of the back wall of the a = 4
// granular column, whose top corner then dilated to half its density and
// blew up). A lid pressing on a material under gravity gets the Shepard
// pressure without the (negative) increase, an error of order rho g h. rubble's boundary particles move with a
// prescribed constant velocity, so a_w = 0. The density is the neighbours'
// (the pair force uses sigma_w/rho_w^2 beside sigma_f/rho_f^2), and the
// sound speed theirs (the viscosity and the time step read it).
//
// Why: a wall whose state evolves by the continuity equation (dynamic
// boundary particles) remembers the history of its neighbourhood. A floor
// particle that was uncovered at t = 0 and is then covered by sliding
// material gains the whole kernel mass of the new neighbours as density and
// pushes the material away with a pressure many times its weight (measured
// in the granular column collapse: 12-13 kPa under a 1 cm layer, whose
// weight is 0.26 kPa). The extrapolated wall has no such memory.
#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// Kernel-weighted sums over the free neighbours of one wall particle.
template <int D>
struct WallSums {
  Real w = 0;                       // sum W
  Real p = 0, rho = 0, cs = 0;      // sum p W, sum rho W, sum c W
  Vec<D> rho_r = Vec<D>::zero();    // sum rho (x_w - x_f) W
  Mat<D> S = Mat<D>::zero();        // sum S W
};

// Adds free neighbour f, at separation dx = x_w - x_f and kernel weight w.
template <int D>
RUBBLE_HD_INLINE void wall_sums_add(WallSums<D>& sum, Real w, const Vec<D>& dx, Real p_f, Real rho_f, Real c_f,
                                    const Mat<D>& S_f) {
  sum.w += w;
  sum.p += p_f * w;
  sum.rho += rho_f * w;
  sum.cs += c_f * w;
  sum.rho_r += (rho_f * w) * dx;
  sum.S += w * S_f;
}

struct WallState {
  Real p, rho, cs;
};

// The extrapolated pressure, density and sound speed (the deviator:
// wall_deviator); needs sum.w > 0 (a wall particle with no free neighbour
// keeps its state: the caller checks).
template <int D>
RUBBLE_HD_INLINE WallState wall_state(const WallSums<D>& sum, const Vec<D>& g) {
  const Real inv = Real(1) / sum.w;
  const Real hydrostatic = dot(g, sum.rho_r) * inv;  // > 0 for a wall particle below its neighbours
  return WallState{sum.p * inv + (hydrostatic > Real(0) ? hydrostatic : Real(0)), sum.rho * inv, sum.cs * inv};
}

template <int D>
RUBBLE_HD_INLINE Mat<D> wall_deviator(const WallSums<D>& sum) {
  return (Real(1) / sum.w) * sum.S;
}

}  // namespace rubble
