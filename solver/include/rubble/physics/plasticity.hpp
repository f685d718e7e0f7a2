#pragma once
// Perfect plasticity of the deviatoric stress: von Mises (metals, the
// simplest strength cap), Drucker–Prager (regolith, soils) after
// Bui, Fukagawa, Sako & Ohno 2008, IJNAMG 32:1537 ("Lagrangian meshfree
// particles method (SPH) for large deformation and failure flows of
// geomaterial using elastic–plastic soil constitutive model"), and the
// pressure-dependent strength of intact and damaged rock of Collins, Melosh
// & Ivanov 2004, Meteoritics & Planet. Sci. 39:217 (collins_yield_strength).
//
// Conventions (as in the rest of rubble):
//  * sigma = -p I + S, tension positive; p is the pressure, compression
//    positive; I1 = tr sigma = -3 p because the FULL 3-D deviator is
//    traceless.
//  * J2 = S:S/2 of the full 3-D deviator (deviatoric_j2): 2-D is plane strain
//    with S_zz = -(S_xx + S_yy) implied, 1-D is uniaxial strain with
//    S_yy = S_zz = -S_xx/2 implied (jaumann_rate.hpp). Scaling the in-plane S
//    scales the implied components with it, so every return below acts on
//    the full 3-D deviator.
//
// Yield functions (f > 0: outside the elastic domain):
//  von Mises      f = sqrt(3 J2) - Y
//  Drucker–Prager f = sqrt(J2) + alpha_phi I1 - k_c          (Bui 2008)
//  Collins        f = sqrt(J2) - Y(p, D, u)                  (Collins 2004)
// Plastic potential of the Drucker–Prager model (non-associated when
// alpha_psi != alpha_phi):  g = sqrt(J2) + alpha_psi I1.
//
// The return mapping runs after the elastic (trial) update of S and p; see
// plastic_return() for the algorithm and the meaning of every output.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/jaumann_rate.hpp"

namespace rubble {

enum class PlasticityModel : int { None = 0, VonMises = 1, DruckerPrager = 2, Collins = 3 };

// Which Mohr–Coulomb fit turns (phi, c) into the Drucker–Prager constants:
//  PlaneStrain  — Bui 2008 (their eq. for plane strain): the DP cone that
//                 gives the Mohr–Coulomb failure stress in plane strain when
//                 the plastic out-of-plane strain rate vanishes; use it for 2-D
//                 plane-strain runs (rubble's 2-D).
//  Compression  — the cone through the compressive meridian of the
//                 Mohr–Coulomb pyramid (triaxial/uniaxial compression is
//                 exact); the usual 3-D choice, the outer cone.
//  Extension    — the cone through the tensile meridian of the pyramid
//                 (triaxial extension: uniaxial tension and equal biaxial
//                 compression are exact); the inner of the two 3-D vertex
//                 cones (between its vertices it still pokes slightly out
//                 of the pyramid).
// All cones share the Mohr–Coulomb apex, I1 = 3 c cot(phi), so
// k_c/alpha_phi is the same for every fit and two fits' constants differ by
// the same factor (compression / plane strain 1.3263, extension / plane
// strain 1.0572 at phi = 19.8 deg).
enum class DpConeFit : int { PlaneStrain = 0, Compression = 1, Extension = 2 };

struct PlasticityParams {  // plain data, copied to the GPU as it is
  PlasticityModel model = PlasticityModel::None;
  Real yield_stress = 0;        // von Mises Y [Pa]
  Real alpha_phi = 0, k_c = 0;  // Drucker–Prager f = sqrt(J2) + alpha_phi I1 - k_c [-, Pa]
  Real alpha_psi = 0;           // dilatancy coefficient of g = sqrt(J2) + alpha_psi I1 (0 = no dilatancy)
  // Collins et al. 2004 (collins_yield_strength), a limit on sqrt(J2):
  Real cohesion = 0;            // Y_0: intact strength at p = 0 [Pa]
  Real friction_intact = 0;     // mu_i: intact friction coefficient [-]
  Real strength_limit = 0;      // Y_M: intact strength at p -> infinity [Pa], > Y_0
  Real cohesion_damaged = 0;    // Y_d0: damaged strength at p = 0 [Pa], <= Y_0
  Real friction_damaged = 0;    // mu_d: damaged friction coefficient [-]
  Real melt_energy = 0;         // u_melt: thermal softening factor 1 - u/u_melt (0 = none) [J/kg]
};

// Outcome of plastic_return. The first five members are the agreed API; the
// last one is extra information with a default so aggregate initialisation
// with five values still works.
template <int D>
struct PlasticReturn {
  Mat<D> S;      // returned deviator (in-plane components; the implied ones follow)
  Real p;        // returned pressure [Pa]
  Real dlambda;  // plastic multiplier increment Delta lambda (see plastic_return) [-]
  Real deps_p;   // increment of the accumulated equivalent plastic strain, sqrt(2/3 de^p:de^p) [-]
  Real deps_v;   // plastic volumetric strain increment of the flow rule, 3 alpha_psi dlambda (expansion > 0) [-]
  Real deps_crack = 0;  // volumetric opening of tension cracking, (p_apex - p_trial)/K >= 0 [-]
};

// ---------------------------------------------------------------------------
// Host-side constructors of the constants (plain inline: std::tan etc.).
// Preconditions (checked by the scene parser, not here): 0 <= phi < 90 deg,
// 0 <= psi <= phi, cohesion >= 0, Y >= 0.

// Drucker–Prager slope coefficient for an angle (phi for alpha_phi, psi for
// alpha_psi):
//   PlaneStrain: tan(a)/sqrt(9 + 12 tan^2 a)            (Bui 2008)
//   Compression: 2 sin(a)/(sqrt(3) (3 - sin a))
//   Extension:   2 sin(a)/(sqrt(3) (3 + sin a))
inline Real dp_cone_alpha(Real angle_deg, DpConeFit fit) {
  const Real a = angle_deg * Real(3.14159265358979323846) / Real(180);
  const Real s = std::sin(a);
  switch (fit) {  // no default: a new fit is a compiler warning here
    case DpConeFit::PlaneStrain: {
      const Real t = std::tan(a);
      return t / std::sqrt(Real(9) + Real(12) * t * t);
    }
    case DpConeFit::Compression: return Real(2) * s / (std::sqrt(Real(3)) * (Real(3) - s));
    case DpConeFit::Extension: break;
  }
  return Real(2) * s / (std::sqrt(Real(3)) * (Real(3) + s));  // the extension cone
}

// Drucker–Prager cohesion term k_c:
//   PlaneStrain: 3 c/sqrt(9 + 12 tan^2 phi)             (Bui 2008)
//   Compression: 6 c cos(phi)/(sqrt(3) (3 - sin phi))
//   Extension:   6 c cos(phi)/(sqrt(3) (3 + sin phi))
inline Real dp_cone_k(Real phi_deg, Real cohesion, DpConeFit fit) {
  const Real a = phi_deg * Real(3.14159265358979323846) / Real(180);
  const Real s = std::sin(a);
  switch (fit) {  // no default: a new fit is a compiler warning here
    case DpConeFit::PlaneStrain: {
      const Real t = std::tan(a);
      return Real(3) * cohesion / std::sqrt(Real(9) + Real(12) * t * t);
    }
    case DpConeFit::Compression: return Real(6) * cohesion * std::cos(a) / (std::sqrt(Real(3)) * (Real(3) - s));
    case DpConeFit::Extension: break;
  }
  return Real(6) * cohesion * std::cos(a) / (std::sqrt(Real(3)) * (Real(3) + s));  // the extension cone
}

// Drucker–Prager constants from the friction angle phi [deg], the cohesion
// c [Pa] and the dilatancy angle psi [deg] (psi = 0: no plastic volume
// change; psi = phi: associated flow), with the same fit for phi and psi.
inline PlasticityParams drucker_prager_params(Real phi_deg, Real cohesion, Real psi_deg, DpConeFit fit) {
  PlasticityParams pp;
  pp.model = PlasticityModel::DruckerPrager;
  pp.alpha_phi = dp_cone_alpha(phi_deg, fit);
  pp.k_c = dp_cone_k(phi_deg, cohesion, fit);
  pp.alpha_psi = dp_cone_alpha(psi_deg, fit);
  return pp;
}

// von Mises with yield stress Y [Pa] (uniaxial-stress yield strength).
inline PlasticityParams von_mises_params(Real Y) {
  PlasticityParams pp;
  pp.model = PlasticityModel::VonMises;
  pp.yield_stress = Y;
  return pp;
}

// Collins et al. 2004 rock strength (model Collins).
inline PlasticityParams collins_params(Real cohesion, Real friction_intact, Real strength_limit,
                                       Real cohesion_damaged, Real friction_damaged, Real melt_energy) {
  PlasticityParams pp;
  pp.model = PlasticityModel::Collins;
  pp.cohesion = cohesion;
  pp.friction_intact = friction_intact;
  pp.strength_limit = strength_limit;
  pp.cohesion_damaged = cohesion_damaged;
  pp.friction_damaged = friction_damaged;
  pp.melt_energy = melt_energy;
  return pp;
}

// ---------------------------------------------------------------------------
// Host-device functions.

// ---- Collins et al. 2004: strength of intact and damaged rock --------------
//
// Y is a limit on sqrt(J2) (the convention of miluphcuda's
// COLLINS_PLASTICITY, "Drucker-Prager-like -> compare to sqrt(J2)", of the
// iSALE-lineage code SALEc, of SWIFT and of OpenSPH; Spheral alone applies
// it to sqrt(3 J2)). p is the pressure of the intact material (compression
// > 0): in compression the one that acts; in tension a damaged particle's
// acting (1 - D) p is turned back into it by the caller
// (plastic_return_particle), so Y_i sees the intact skeleton's tension.
//
//  intact (Lundborg 1968, Collins eq. 3):
//    Y_i(p) = Y_0 + mu_i p / (1 + mu_i p / (Y_M - Y_0))
//  damaged (Collins eq. 4, a Coulomb law with an optional cohesion):
//    Y_d(p) = min(Y_d0 + mu_d p, Y_i(p))
//  damage D in [0, 1] (Collins eq. 5):
//    Y = (1 - D) Y_i + D Y_d
//
// Tension (p < 0), as the iSALE-lineage code does (SALEc's SimpleRock): both
// curves are continued into tension down to their zeros, the intact one at
// p_i0 = -Y_0 (Y_M - Y_0)/(mu_i Y_M), the damaged one at -Y_d0/mu_d, and are
// 0 beyond (no negative strength). The codes differ here (miluphcuda keeps
// Y_i = Y_0 in tension and gives Y_d slope 1; Spheral and SWIFT keep Y_0 and
// set Y_d = 0); continuing the curves is the choice that makes strength
// vanish smoothly as the rock is pulled apart. No further tension cut-off
// lives here: the tension itself is carried by the EOS, reduced to (1 - D) p
// by the Grady-Kipp damage (damage.hpp), which breaks rock in tension; a
// Collins material without damage keeps its intact curve (miluphcuda does
// the same without FRAGMENTATION).
//
// Thermal softening (optional, melt_energy = u_melt > 0): Y_i is multiplied
// by max(0, 1 - u/u_melt) before Y_d and Y are formed, so the whole surface
// falls linearly to 0 at the melt energy. This is miluphcuda's
// COLLINS_PLASTICITY_INCLUDE_MELT_ENERGY (also OpenSPH's); Collins 2004 use
// Ohnaka's (1995) Y tanh(xi (T_m/T - 1)) with a Simon melting curve, which
// needs a temperature the Tillotson EOS does not give (not implemented).

// Y_i(p) with its tensile zero (above); mu_i = 0 gives Y_0 at every p.
RUBBLE_HD_INLINE Real collins_intact_strength(const PlasticityParams& pp, Real p) {
  if (!(pp.friction_intact > Real(0))) return pp.cohesion;
  const Real dY = pp.strength_limit - pp.cohesion;  // > 0 (parser)
  const Real p_zero = -pp.cohesion * dY / (pp.friction_intact * pp.strength_limit);
  if (p <= p_zero) return Real(0);
  const Real x = pp.friction_intact * p;
  return pp.cohesion + x / (Real(1) + x / dY);
}

// The thermal-softening factor on Y_i: max(0, 1 - u/u_melt), 1 without it.
RUBBLE_HD_INLINE Real collins_melt_factor(const PlasticityParams& pp, Real u) {
  if (!(pp.melt_energy > Real(0)) || u <= Real(0)) return Real(1);
  const Real f = Real(1) - u / pp.melt_energy;
  return f > Real(0) ? f : Real(0);
}

// Y_d(p) = min(Y_d0 + mu_d p, Y_i) >= 0, given Y_i at that p.
RUBBLE_HD_INLINE Real collins_damaged_strength(const PlasticityParams& pp, Real p, Real intact) {
  const Real y = pp.cohesion_damaged + pp.friction_damaged * p;
  const Real yd = y < intact ? y : intact;
  return yd > Real(0) ? yd : Real(0);
}

// Y(p, D, u) = (1 - D) Y_i + D Y_d, the limit on sqrt(J2).
RUBBLE_HD_INLINE Real collins_yield_strength(const PlasticityParams& pp, Real p, Real damage, Real u) {
  const Real yi = collins_intact_strength(pp, p) * collins_melt_factor(pp, u);
  const Real yd = collins_damaged_strength(pp, p, yi);
  return (Real(1) - damage) * yi + damage * yd;
}

// Pressure of the Drucker–Prager apex, p = -k_c/(3 alpha_phi) (the most
// tensile hydrostatic state the cone admits); only meaningful for
// alpha_phi > 0.
RUBBLE_HD_INLINE Real dp_apex_pressure(const PlasticityParams& pp) {
  return -pp.k_c / (Real(3) * pp.alpha_phi);
}

// The largest sqrt(J2) the yield surface admits at pressure p (with damage
// D and specific internal energy u, which only the Collins surface reads):
// von Mises Y/sqrt(3); Drucker–Prager k_c - alpha_phi I1 = k_c + 3 alpha_phi p
// (negative beyond the apex); Collins Y(p, D, u); +infinity without
// plasticity. What `rubble strength` tabulates.
RUBBLE_HD_INLINE Real yield_limit_sqrt_j2(const PlasticityParams& pp, Real p, Real damage = 0, Real u = 0) {
  switch (pp.model) {  // no default: a new model is a compiler warning here
    case PlasticityModel::VonMises: return pp.yield_stress / std::sqrt(Real(3));
    case PlasticityModel::DruckerPrager: return pp.k_c - pp.alpha_phi * (Real(-3) * p);
    case PlasticityModel::Collins: return collins_yield_strength(pp, p, damage, u);
    case PlasticityModel::None: break;
  }
  return Real(INFINITY);
}

// Yield function value (> 0 means outside), J2 the full 3-D invariant and
// I1 = -3p; damage D and specific internal energy u enter the Collins
// surface only. For PlasticityModel::None it returns -1 (never yields).
template <int D>
RUBBLE_HD_INLINE Real yield_function(const PlasticityParams& pp, const Mat<D>& S, Real p, Real damage = 0,
                                     Real u = 0) {
  const Real j2 = deviatoric_j2(S);
  switch (pp.model) {  // no default: a new model is a compiler warning here
    case PlasticityModel::Collins: return std::sqrt(j2) - yield_limit_sqrt_j2(pp, p, damage, u);
    case PlasticityModel::VonMises: return std::sqrt(Real(3) * j2) - pp.yield_stress;
    case PlasticityModel::DruckerPrager: return std::sqrt(j2) - yield_limit_sqrt_j2(pp, p);
    case PlasticityModel::None: break;
  }
  return Real(-1);
}

// Return mapping of a trial state (S, p) — the elastic update of this step —
// with shear modulus G and tangent bulk modulus K (K only enters with
// dilatancy and for deps_crack); damage and u enter the Collins surface.
//
// Collins (radial return at fixed p, as miluphcuda, iSALE/SALEc, SWIFT and
// OpenSPH do): with Y = collins_yield_strength(p, D, u), if sqrt(J2) > Y:
//   S <- S Y/sqrt(J2); p unchanged; dlambda = (sqrt(J2) - Y)/G; deps_v = 0
//   (no plastic volume change: the flow is non-associated).
//
// von Mises (radial return, exact for perfect plasticity):
//   q = sqrt(3 J2); if q > Y: S <- S Y/q; p unchanged.
//   dlambda = (q - Y)/(3G) (multiplier of the potential sqrt(3 J2), equal to
//   deps_p); deps_v = 0.
//
// Drucker–Prager (Bui 2008: tension-cracking treatment, then stress scaling):
//  (1) tension cracking: if -alpha_phi I1 + k_c < 0 (hydrostatic stress
//      beyond the apex) the hydrostatic stress moves to the apex,
//      I1 <- k_c/alpha_phi, i.e. p <- -k_c/(3 alpha_phi); S is kept for (2).
//      deps_crack = (p_after - p_trial)/K >= 0 is the volumetric opening this
//      implies (0 when K <= 0).
//  (2) with cap = -alpha_phi I1 + k_c >= 0 and f = sqrt(J2) - cap:
//      if f > 0:
//        alpha_psi == 0 : Bui's stress scaling S <- S r, r = cap/sqrt(J2),
//                         p unchanged; dlambda = f/G.
//        alpha_psi >  0 : consistent return for g = sqrt(J2) + alpha_psi I1
//                         (plastic strain increment dlambda dg/dsigma =
//                         dlambda (alpha_psi I + S/(2 sqrt(J2))), stress
//                         increment -C:that):
//                           dlambda = f/(G + 9 K alpha_phi alpha_psi)
//                           sqrt(J2) <- sqrt(J2_tr) - G dlambda   (S scaled)
//                           I1 <- I1_tr - 9 K alpha_psi dlambda, i.e.
//                           p <- p_tr + 3 K alpha_psi dlambda
//                         which lands exactly on f = 0 and reduces to Bui's
//                         scaling at alpha_psi = 0. After step (1),
//                         sqrt(J2) - G dlambda >= 0 always (no apex
//                         overshoot).
//      deps_v = 3 alpha_psi dlambda (plastic dilatation, > 0 = expansion), so
//      p_out = p_trial + K (deps_v + deps_crack).
//
// deps_p (both models) is the increment of the accumulated equivalent (von
// Mises) plastic strain,
//     deps_p = sqrt(2/3 de^p : de^p),  de^p = (S_trial - S_out)/(2G),
// with the double contraction over the FULL 3-D deviator (the implied
// out-of-plane components included): deps_p = sqrt(J2(S_trial - S_out)/3)/G.
// For the Drucker–Prager shear return deps_p = dlambda/sqrt(3).
//
// p returned equals the trial p except for tension cracking (apex) and
// dilatancy. The caller decides how a changed p persists (an EOS of rho
// alone would recompute the trial p next step).
template <int D>
RUBBLE_HD_INLINE PlasticReturn<D> plastic_return(const PlasticityParams& pp, const Mat<D>& S, Real p, Real G,
                                                 Real K, Real damage = 0, Real u = 0) {
  PlasticReturn<D> r{S, p, Real(0), Real(0), Real(0), Real(0)};
  switch (pp.model) {  // no default: a new model is a compiler warning here
    case PlasticityModel::None: return r;
    case PlasticityModel::Collins: {
      const Real Y = yield_limit_sqrt_j2(pp, p, damage, u);
      const Real sj2 = std::sqrt(deviatoric_j2(S));
      if (sj2 > Y) {
        r.S = S * (Y / sj2);
        r.dlambda = G > Real(0) ? (sj2 - Y) / G : Real(0);
      }
      break;
    }
    case PlasticityModel::VonMises: {
      const Real q = std::sqrt(Real(3) * deviatoric_j2(S));
      if (q > pp.yield_stress) {
        r.S = S * (pp.yield_stress / q);
        r.dlambda = G > Real(0) ? (q - pp.yield_stress) / (Real(3) * G) : Real(0);
      }
      break;
    }
    case PlasticityModel::DruckerPrager: {
      // (1) tension cracking; the cap -alpha_phi I1 + k_c is then exactly 0
      Real cap = yield_limit_sqrt_j2(pp, p);
      if (cap < Real(0)) {
        r.p = dp_apex_pressure(pp);
        if (K > Real(0)) r.deps_crack = (r.p - p) / K;
        cap = Real(0);
      }
      // (2) stress scaling / dilatant return
      const Real sj2 = std::sqrt(deviatoric_j2(S));
      const Real f = sj2 - cap;
      if (f > Real(0)) {
        if (pp.alpha_psi == Real(0)) {
          r.S = S * (cap / sj2);  // Bui 2008 stress scaling, p unchanged
          r.dlambda = G > Real(0) ? f / G : Real(0);
        } else {
          const Real dl = f / (G + Real(9) * K * pp.alpha_phi * pp.alpha_psi);
          const Real sj2_new = sj2 - G * dl;
          r.S = S * (sj2_new / sj2);
          r.p = r.p + Real(3) * K * pp.alpha_psi * dl;
          r.dlambda = dl;
          r.deps_v = Real(3) * pp.alpha_psi * dl;
        }
      }
      break;
    }
  }
  if (G > Real(0)) r.deps_p = std::sqrt(deviatoric_j2(Mat<D>(S - r.S)) / Real(3)) / G;
  return r;
}

}  // namespace rubble
