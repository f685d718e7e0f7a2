#pragma once
// Particle shifting: after each accepted step a free particle moves a small
// distance down the gradient of the particle concentration, which spreads
// particles that have come too close without changing what they carry
// (Xu, Stansby & Laurence 2009; Lind, Xu, Stansby & Rogers 2012, J. Comput.
// Phys. 231:1499; the diffusion coefficient scaled with the particle's own
// motion as in Skillen, Lind, Stansby & Rogers 2013, CMAME 265:163; the
// short-range term of Sun, Colagrossi, Marrone & Zhang 2017, CMAME 315:25):
//
//   delta x_a = -A h |dv|_a dt  sum_b V_b [1 + R (W_ab / W(dp))^4] grad_a W_ab
//
// with V_b = m_b/rho_b, h the kernel support radius, dp the particle spacing
// of a's material, R = 0.2. The sum is the gradient of the concentration
// C = sum V_b W_ab, zero on a regular lattice; the R term grows steeply
// below the spacing (W_ab/W(dp) > 1) and is what separates a close pair.
// |dv|_a = max_b |v_b - v_a| is the largest speed of a neighbour relative to
// a: Skillen et al. scale with |v_a| dt, the particle's own displacement in
// the step; the relative speed (the displacement of the neighbourhood
// relative to a) makes the shift Galilean invariant, so that neither a body
// at rest nor one in rigid translation is shifted (with |v_a| a falling
// granular column, rigidly translating at ~1 m/s near its top, had its top
// layer spread apart until it blew up), and the shift vanishes with the step. At a free surface the concentration falls outward and the
// shift would push surface particles out; there (C_a < kShiftSurfaceC) its
// outward component, along -grad C, is removed (Lind et al. 2012, sec. 3.2,
// who remove the normal component at the surface). Each shift is capped at
// kShiftMaxFraction of the spacing.
//
// What a particle carries (density, energy, stress, plastic strain,
// distention) is not corrected for the move: shifts are small (a fraction
// of |v| dt) and the correction would be a Taylor term of the same order.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

constexpr Real kShiftR = Real(0.2);             // weight of the short-range term (Sun et al. 2017)
constexpr Real kShiftSurfaceC = Real(0.95);     // concentration below which a particle counts as at the surface
constexpr Real kShiftMaxFraction = Real(0.1);   // largest shift per step, as a fraction of the spacing

// One neighbour's terms: V_b grad_a W_ab (into grad C) and the same with the
// short-range weight [1 + R (W_ab/W(dp))^4] (into the shift).
template <int D>
struct ShiftSums {
  Real C = 0;                       // sum V_b W_ab (self included by the caller)
  Vec<D> grad_c = Vec<D>::zero();   // sum V_b grad_a W_ab
  Vec<D> weighted = Vec<D>::zero(); // sum V_b [1 + R (W_ab/W(dp))^4] grad_a W_ab
};

template <int D>
RUBBLE_HD_INLINE void shift_sums_add(ShiftSums<D>& s, Real volume_b, Real w, Real w_dp, const Vec<D>& grad_w) {
  s.C += volume_b * w;
  s.grad_c += volume_b * grad_w;
  const Real q = w_dp > Real(0) ? w / w_dp : Real(0);
  const Real q2 = q * q;
  s.weighted += (volume_b * (Real(1) + kShiftR * q2 * q2)) * grad_w;
}

// The shift of a particle whose neighbours move at most at `speed` relative
// to it, with support radius h and spacing dp, over a step dt, with
// coefficient A (simulation.shifting; 0 = off).
template <int D>
RUBBLE_HD_INLINE Vec<D> shifting_displacement(const ShiftSums<D>& s, Real A, Real h, Real speed, Real dt, Real dp) {
  Vec<D> d = (-A * h * speed * dt) * s.weighted;
  if (s.C < kShiftSurfaceC) {  // at a free surface: no outward component (outward = -grad C)
    const Real g = std::sqrt(dot(s.grad_c, s.grad_c));
    if (g > Real(0)) {
      const Vec<D> out = (Real(-1) / g) * s.grad_c;
      const Real along = dot(d, out);
      if (along > Real(0)) d -= along * out;
    }
  }
  const Real len = std::sqrt(dot(d, d));
  const Real cap = kShiftMaxFraction * dp;
  if (len > cap) d *= cap / len;
  return d;
}

}  // namespace rubble
