#pragma once
// Hooke's law for the deviatoric stress with the Jaumann (co-rotational)
// rate (seed paper eqs. 4-6; Libersky & Petschek 1990; Benz & Asphaug 1994):
//
//   dS/dt = 2 mu (eps_dot - (1/3) tr(eps_dot) I) + W S - S W
//   eps_dot = (L + L^T)/2,  W = (L - L^T)/2,  L_ij = dv_i/dx_j
//
// In index form, dS^ab/dt = 2mu(...) + S^ac W^bc + S^bc W^ac (the rotation
// index is the second one in both terms). PHYSICS.md §1 prints
// S^ac R^cb + S^bc R^ca, the opposite sign: that version rotates the stress
// backwards relative to the material. Both keep |S| constant under a rigid
// rotation, so the unit test checks the stronger property that S turns WITH
// the body, S(t) = Q(t) S0 Q(t)^T.
//
// 2-D is plane strain: eps_zz = 0 and the 1/3 above is the 3-D deviator, so
// the out-of-plane deviatoric stress is not zero but follows from
// tracelessness, S_zz = -(S_xx + S_yy); it enters J2 (deviatoric_j2) and
// the plastic return of later issues. 1-D is uniaxial strain likewise
// (S_yy = S_zz = -S_xx/2).
#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"

namespace rubble {

template <int D>
RUBBLE_HD_INLINE Mat<D> strain_rate(const Mat<D>& L) {
  return Real(0.5) * (L + transpose(L));
}

template <int D>
RUBBLE_HD_INLINE Mat<D> rotation_rate(const Mat<D>& L) {
  return Real(0.5) * (L - transpose(L));
}

// dS/dt from the velocity gradient L for shear modulus mu.
template <int D>
RUBBLE_HD_INLINE Mat<D> deviatoric_stress_rate(const Mat<D>& S, const Mat<D>& L, Real mu) {
  const Mat<D> e = strain_rate(L);
  const Mat<D> W = rotation_rate(L);
  Mat<D> dS = Real(2) * mu * (e - (trace(e) / Real(3)) * Mat<D>::identity());
  dS += W * S - S * W;
  return dS;
}

// Out-of-plane deviatoric components implied by tracelessness of the 3-D
// deviator: in 2-D (plane strain) S_zz = -(S_xx + S_yy); in 1-D (uniaxial
// strain) S_yy = S_zz = -S_xx / 2. Returns the sum of their squares.
template <int D>
RUBBLE_HD_INLINE Real out_of_plane_deviator_sq(const Mat<D>& S) {
  if constexpr (D == 3) return Real(0);
  else if constexpr (D == 2) {
    const Real szz = -(S.m[0][0] + S.m[1][1]);
    return szz * szz;
  } else {
    const Real s = Real(-0.5) * S.m[0][0];
    return Real(2) * s * s;
  }
}

// J2 = S:S / 2 of the full 3-D deviator.
template <int D>
RUBBLE_HD_INLINE Real deviatoric_j2(const Mat<D>& S) {
  return Real(0.5) * (double_dot(S, S) + out_of_plane_deviator_sq(S));
}

// Specific shear work (1/rho) S : eps_dot, the energy equation's solid term.
template <int D>
RUBBLE_HD_INLINE Real shear_heating(const Mat<D>& S, const Mat<D>& L, Real rho) {
  return double_dot(S, strain_rate(L)) / rho;
}

}  // namespace rubble
