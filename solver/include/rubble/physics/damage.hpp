#pragma once
// Tensile damage after Grady & Kipp (1980, Int. J. Rock Mech. Min. Sci.
// 17:147) with explicit Weibull flaws as Benz & Asphaug put it into SPH
// (1994, Icarus 107:98 — "BA94"; 1995, Comput. Phys. Commun. 87:253 —
// "BA95"); docs/physics.md, "Fracture".
//
// Flaws. A brittle solid holds n(eps) = k eps^m flaws per unit volume that
// activate at a tensile strain below eps (Weibull 1939; k [m^-3] and m are
// material constants). A body of volume V gets flaws j = 1, 2, ... with
// activation strains
//   eps_j = (j / (k V))^(1/m)                                     (BA94, BA95)
// each given to a particle chosen at random, until every particle holds at
// least one: about N ln N flaws for N particles (a coupon-collector count).
// In 1-D and 2-D the body is a slab of unit depth: V is its length times
// 1 m^2, or its area times 1 m, so k keeps its 3-D unit.
//
// Per particle rubble stores the number of its flaws n_f and the smallest and
// largest activation strain eps_min, eps_max (not the whole list). Because
// eps_j^m is proportional to j and the particle's flaws are a uniform random
// subset of the j's, the n_f - 2 flaws between the two stored ends are, given
// the ends, spread uniformly in eps^m between them, so the expected number
// active at a strain eps is (active_flaws)
//   n_act = 0                                                   eps < eps_min
//         = 1 + (n_f - 2) x,  x = (eps^m - eps_min^m)/(eps_max^m - eps_min^m)
//         = n_f                                                 eps >= eps_max
// (the weakest flaw, plus the share x of the interior ones; the strongest
// joins only at eps_max). Exact for n_f <= 2, the expected count otherwise.
//
// Growth. Damage D in [0, 1] is the cracked fraction of a particle's volume.
// A crack grows at the speed c_g = f_c c_l (f_c = 0.4 by default, the value
// of BA94; c_l the longitudinal sound speed sqrt(c_s^2 + 4 mu/(3 rho))), so in
// d dimensions the cracked measure grows as (c_g t)^d and
//   d(D^(1/d))/dt = n_act c_g / R_s                       (BA95, d = 3)
// with R_s the crack-growth length (CrackLength): by default the radius of
// the particle's volume V_p = m/rho (sphere in 3-D, disc in 2-D, half the
// length in 1-D: particle_radius), BA95's "radius of the volume"; or the
// kernel support radius, as miluphcuda (damage.cu, 1/sml) and Spheral take
// it, so that Weibull parameters calibrated with those codes carry over.
// The evolved field is delta = D^(1/d) ("damage_root").
// It grows only while the local tensile strain exceeds the particle's
// weakest flaw (n_act > 0) and never decreases. By default (BA95) a
// particle's damage cannot exceed the fraction of its flaws ever activated,
// D <= n_act,max / n_f; DamageParams::capped = false drops that cap (D <= 1
// only).
//
// What the cap does to the strain-rate law (docs/physics.md, "Fracture"; the
// rung verification/fracture_strain_rate). Without the cap, under a strain
// growing as eps_dot t, in 1-D (V_p = 2 R_s, n_act = k V_p eps^m on average)
//   delta(t) = 2 k c_g eps_dot^m t^(m+1) / (m+1),
// Grady & Kipp's law: the failure strain grows as eps_dot^(1/(m+1)), set by
// the material (k, m, c_g) and not by the particles. With the cap the
// particle's D is also held below n_act/n_f = (eps/eps_max)^m (its flaws
// spread uniformly in eps^m up to its largest, eps_max); the ratio of the
// free growth to the cap is n_f c_g t / ((m+1) R_s) = (eps_max/eps_GK)^m at
// the Grady-Kipp failure time. So whenever the particle still has flaws to
// activate at the Grady-Kipp failure strain (eps_max > eps_GK) the cap binds
// and the particle breaks only near its own eps_max, whatever the rate; when
// it has none left (eps_max < eps_GK) growth runs at the saturated
// n_f c_g / R_s and the failure stress rises ~linearly with the rate. The
// Grady-Kipp regime is squeezed to the single rate where eps_max = eps_GK,
// and eps_max is a property of the draw (about (N ln N/(k V))^(1/m)), not
// of the material.
//
// Local strain (BA94 eq. 9; miluphcuda's damage.cu does the same):
//   eps = sigma_t / ((1 - D) E)
// with sigma_t the largest principal value of the stress that ACTS, i.e. the
// damaged stress -p_D I + f_D S (p_D = damaged_pressure, f_D = the
// deviatoric factor: 1 - D, or 1 when damage spares the deviator), and
// E = 9 K mu/(3 K + mu) the Young's modulus (K = rho c_s^2 from the EOS, mu
// the shear modulus). Dividing by 1 - D gives the strain of the intact
// skeleton that carries the acting stress. This differs from the intact
// stress's sigma_t/E in compression: a compressive p acts in full, so it
// enters as p/(1 - D) and a damaged particle under pressure needs a larger
// deviator to reach tension (damage_local_strain). Where damage spares the
// deviator (deviatoric = false, or a Collins-type yield surface) the acting
// deviator is the intact one and enters as S/(1 - D). A fully damaged
// particle (D = 1) grows no further: its strain is reported as 0.
// The out-of-plane components count: plane strain (2-D)
// carries sigma_zz = S_zz - p with S_zz = -(S_xx + S_yy), uniaxial strain
// (1-D) sigma_yy = sigma_zz = -S_xx/2 - p (jaumann_rate.hpp).
//
// Effect on the stress (BA94): damaged material carries no tension, a
// negative pressure acts as (1 - D) p and a compression as p; the deviatoric
// stress acts as (1 - D) S unless the material's damage is limited to the
// pressure (DamageParams::deviatoric = false). The evolved S stays the
// undamaged one (its yield surface, when the material has plasticity, is
// that of the intact material).
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/symmetric_eigen.hpp"

namespace rubble {

// The length R_s over which a crack crosses a particle (growth above).
enum class CrackLength : int { ParticleRadius = 0, KernelSupport = 1 };

struct DamageParams {
  bool enabled = false;
  Real weibull_k = 0;       // k [m^-3]: n(eps) = k eps^m flaws per unit volume
  Real weibull_m = 0;       // m [1]
  Real crack_speed = 0.4;   // c_g / c_l
  bool deviatoric = true;   // damage also reduces the deviatoric stress
  bool capped = true;       // D <= n_act,max / n_f (BA95); false: D <= 1 only
  CrackLength crack_length = CrackLength::ParticleRadius;  // R_s of the growth law
};

// Largest change of delta = D^(1/d) in one step (dt_limit_particle): a
// particle takes at least 10 steps to break, so a failure time is resolved
// to ~10 % of the growth time R_s / (n_act c_g) or better.
constexpr Real kDamageStepChange = Real(0.1);

// Activation strain of the j-th flaw (j >= 1) of a body of volume V:
// (j / (k V))^(1/m).
RUBBLE_HD_INLINE Real weibull_activation_strain(Real j, Real kV, Real m) { return std::pow(j / kV, Real(1) / m); }

// D from delta = D^(1/d).
template <int D>
RUBBLE_HD_INLINE Real damage_from_root(Real delta) {
  if constexpr (D == 1) return delta;
  else if constexpr (D == 2) return delta * delta;
  else return delta * delta * delta;
}

// delta = D^(1/d) from D.
template <int D>
RUBBLE_HD_INLINE Real damage_root_from(Real damage) {
  if constexpr (D == 1) return damage;
  else if constexpr (D == 2) return std::sqrt(damage);
  else return std::cbrt(damage);
}

// Radius of a particle of measure V_p (volume in 3-D, area in 2-D, length
// in 1-D): the sphere's, the disc's, half the length.
template <int D>
RUBBLE_HD_INLINE Real particle_radius(Real measure) {
  if constexpr (D == 1) return Real(0.5) * measure;
  else if constexpr (D == 2) return std::sqrt(measure / Real(3.14159265358979323846));
  else return std::cbrt(Real(3) * measure / (Real(4) * Real(3.14159265358979323846)));
}

// Young's modulus from the bulk modulus K and the shear modulus mu.
RUBBLE_HD_INLINE Real youngs_modulus(Real K, Real mu) { return Real(9) * K * mu / (Real(3) * K + mu); }

// Largest principal value of the 3-D stress sigma = -p I + S of a D-dim.
// particle, with the implied out-of-plane components (see above).
template <int D>
RUBBLE_HD_INLINE Real max_principal_stress(const Mat<D>& S, Real p) {
  if constexpr (D == 1) {
    const Real sxx = S.m[0][0] - p, syy = Real(-0.5) * S.m[0][0] - p;
    return sxx > syy ? sxx : syy;
  } else if constexpr (D == 2) {
    const Real a = S.m[0][0], d = S.m[1][1], b = Real(0.5) * (S.m[0][1] + S.m[1][0]);
    const Real in_plane = Real(0.5) * (a + d) + std::sqrt(Real(0.25) * (a - d) * (a - d) + b * b) - p;
    const Real szz = -(a + d) - p;
    return in_plane > szz ? in_plane : szz;
  } else {
    const SymmetricEigen<3> e = symmetric_eigen<3>(S);
    Real s = e.lambda[0];
    for (int i = 1; i < 3; ++i) s = e.lambda[i] > s ? e.lambda[i] : s;
    return s - p;
  }
}

// Local tensile strain sigma_t / E (0 when no principal stress is tensile).
template <int D>
RUBBLE_HD_INLINE Real local_tensile_strain(const Mat<D>& S, Real p, Real youngs) {
  const Real st = max_principal_stress<D>(S, p);
  return st > Real(0) && youngs > Real(0) ? st / youngs : Real(0);
}

// The local strain of a damaged particle (header comment, BA94 eq. 9):
// sigma_t/((1 - D) E) of the acting stress -p_acting I + S_acting, i.e.
// local_tensile_strain of (S_acting, p_acting)/(1 - D). 0 for D >= 1.
template <int D>
RUBBLE_HD_INLINE Real damage_local_strain(const Mat<D>& S_acting, Real p_acting, Real damage, Real youngs) {
  const Real intact = Real(1) - damage;
  if (!(intact > Real(0))) return Real(0);
  return local_tensile_strain<D>(S_acting, p_acting, youngs) / intact;
}

// Number of a particle's flaws active at strain eps (see above); n_f = 0
// (a particle without flaws: another material, a wall) gives 0.
RUBBLE_HD_INLINE Real active_flaws(Real eps, int n_f, Real eps_min, Real eps_max, Real m) {
  if (n_f <= 0 || !(eps >= eps_min)) return 0;
  if (eps >= eps_max) return Real(n_f);
  if (n_f <= 2) return Real(1);  // only the weakest is active below eps_max
  const Real lo = std::pow(eps_min, m), hi = std::pow(eps_max, m);
  const Real n = Real(1) + Real(n_f - 2) * (std::pow(eps, m) - lo) / (hi - lo);
  return n < Real(n_f) ? n : Real(n_f);
}

// The cap on delta: D <= n_act,max / n_f, i.e. delta <= (n_act,max/n_f)^(1/d)
// (capped, BA95), or 1 once a flaw has been active (not capped).
template <int D>
RUBBLE_HD_INLINE Real damage_root_cap(Real n_active_max, int n_f, bool capped = true) {
  if (n_f <= 0 || n_active_max <= Real(0)) return 0;
  if (!capped) return 1;
  const Real frac = n_active_max >= Real(n_f) ? Real(1) : n_active_max / Real(n_f);
  return damage_root_from<D>(frac);
}

// d delta/dt = n_act c_g / R_s while the particle is in tension beyond its
// weakest flaw and below its cap (damage_root_cap); 0 otherwise. n_act is
// the count at the current strain, n_active_max the most ever activated
// (>= n_act after the caller's max).
template <int D>
RUBBLE_HD_INLINE Real damage_root_rate(Real delta, Real n_act, Real n_active_max, int n_f, Real crack_speed,
                                       Real radius, bool capped = true) {
  if (n_act <= Real(0) || radius <= Real(0)) return 0;
  const Real nmax = n_active_max > n_act ? n_active_max : n_act;
  if (delta >= damage_root_cap<D>(nmax, n_f, capped)) return 0;
  return n_act * crack_speed / radius;
}

// delta0 + w d delta/dt, never above 1 (the rate is >= 0: delta never falls).
RUBBLE_HD_INLINE Real integrated_damage_root(Real delta0, Real w, Real rate) {
  const Real d = delta0 + w * rate;
  return d < Real(1) ? d : Real(1);
}

// The pressure that acts: a tension (p < 0) is carried by the intact
// fraction 1 - D, a compression in full.
RUBBLE_HD_INLINE Real damaged_pressure(Real p, Real damage) { return p < Real(0) ? (Real(1) - damage) * p : p; }

// The factor on the deviatoric stress that acts: 1 - D, or 1 when the
// material's damage acts on the pressure only.
RUBBLE_HD_INLINE Real damaged_deviatoric_factor(const DamageParams& dp, Real damage) {
  return dp.deviatoric ? Real(1) - damage : Real(1);
}

// Step limit from the growth rate: the change of delta per step is at most
// fraction (kDamageStepChange); no limit when the particle does not grow,
// nor when it is within `fraction` of its cap (room = cap - delta <=
// fraction): the cap holds its change to the room however long the step,
// and its growth then follows the cap, i.e. the strain, which the other
// limits resolve. (Without that exception a particle creeping up its cap
// under a compression — the local strain falls as D grows — held every step
// to fraction/rate although it grew by far less: the Nakamura rung took 3.5
// times the steps.)
RUBBLE_HD_INLINE Real damage_dt_limit(Real rate, Real fraction, Real room = Real(1)) {
  return rate > Real(0) && room > fraction ? fraction / rate : Real(1e30);
}

}  // namespace rubble
