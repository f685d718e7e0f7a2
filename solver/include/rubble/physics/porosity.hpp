#pragma once
// The p–α porosity model (Herrmann 1969, J. Appl. Phys. 40:2490; Carroll &
// Holt 1972, J. Appl. Phys. 43:1626; as adapted to SPH by Jutzi, Benz &
// Michel 2008, Icarus 198:242 — "J08" below — and Jutzi, Michel, Hiraoka,
// Nakamura & Benz 2009, Icarus 201:802 — "J09"; seed paper §II.C;
// PHYSICS.md §4).
//
// State: the distention α = ρ_s/ρ ≥ 1 (ρ_s matrix density, ρ bulk density).
// The pores carry no mass and no energy, so the matrix has the bulk specific
// internal energy u, and (seed eq. 12, J08)
//   p = p_s(ρ_s, u)/α = p_s(αρ, u)/α,
// p_s being the matrix EOS with the material's add-ons (eos_evaluate).
//
// Crush curve α_c(p) (the plastic loading boundary), for p_e < p < p_s:
//   quadratic (J08 eq. 8):  α_c = 1 + (α_e − 1) [(p_s − p)/(p_s − p_e)]²
//   steep (J09):            α_c = 1 + (α_e − α_t) [(p_t − p)/(p_t − p_e)]^n1
//                                   + (α_t − 1) [(p_s − p)/(p_s − p_e)]^n2   (p < p_t)
//                           α_c = 1 + (α_t − 1) [(p_s − p)/(p_s − p_e)]^n2   (p_t ≤ p < p_s)
//   α_c = α_e for p ≤ p_e, 1 for p ≥ p_s. α_t is a shape parameter of the
//   steep curve, not α_c(p_t). Both forms are continuous at p_e, p_t and p_s;
//   dα_c/dp is continuous at p_t for n1 > 1 and at p_s for n2 > 1, and jumps
//   at p_e (from 0 to the plastic slope). Requires p_e < p_t < p_s, n1, n2 ≥ 1.
//   As in miluphcuda and J08's own simplification, α_e is also the initial
//   distention α0. The elastic compaction below p_e is then left out of the
//   crush curve's α_e: small for J08 §5.1's porous aluminium (α falls by
//   ~1.2e-3 up to p_e, tested), not in general — with c_e = 1500 m/s on the
//   Tillotson basalt of `porous_basalt` it took 13 % of the porosity by p_e
//   and moved the start of crushing from 200 to 417 MPa, which is why that
//   library material has no elastic branch (its source, miluphcuda, uses
//   c_e only to interpolate a sound speed).
//
// Elastic branch (J08 §2, after Herrmann 1969; the same formula is in
// Spheral's PalphaPorosity and, commented out, in miluphcuda's pressure.cu):
//   dα/dp|_el = (α²/K_s) (1 − 1/h²),   h(α) = 1 + (α − 1)(c_e − c_s0)/(c_s0 (α_e − 1)),
// K_s = ρ_s0 c_s0² the matrix bulk modulus (ρ_s0 the matrix EOS's reference
// density; Spheral's K_S0). h is the ratio of the porous to the matrix sound
// speed, linear in α between 1 (α = 1) and c_e/c_s0 (α = α_e): with this
// slope the porous material's elastic wave speed is h c_s, i.e. c_e at α_e
// (derivation: dα/α = dρ_s/ρ_s − dρ/ρ with dρ_s/ρ_s ≈ α dp/K_s and
// dρ/ρ = dp/(ρ h² c_s²)). It is off (0) when c_e or c_s0 is 0 or c_e ≥ c_s0.
// The virgin elastic curve is its integral from (p = 0, α = α_e), in closed
// form (porosity_elastic_curve_pressure, partial fractions):
//   p_el(α) = K_s/(−k) [Φ(α_e − 1) − Φ(α − 1)],  k = (c_e/c_s0 − 1)/(α_e − 1) < 0,
//   Φ(t) = ½ ln t − k²/(2(k − 2)²) ln(2 + kt) + C ln(1 + t) − D/(1 + t),
//   C = −2(1 − k)/(k − 2)²,  D = −(1 − k)²/(2 − k);   p_el → ∞ as α → 1.
//
// Evolution (J08; PHYSICS.md §4). From p = p_s(αρ, u)/α and dα/dt = (dα/dp) dp/dt:
//   dα/dt = (dα/dp) [α ρ̇ ∂p_s/∂ρ_s + u̇ ∂p_s/∂u] / [α + (dα/dp)(p − ρ ∂p_s/∂ρ_s)]
// with the partials at (ρ_s, u) (eos_pressure_derivatives_limited). Which
// dα/dp (porosity_branch):
//   The loading envelope is α_load(p) = min(α_el(p), α_c(p)): the virgin
//   elastic curve until it meets the crush curve (just above p_e), then the
//   crush curve — Herrmann's picture, continuous by construction.
//   - Plastic: p > p_e and α ≥ α_c(p) (within kPorosityCurveRelTol): dα_c/dp.
//   - Elastic: not plastic, p ≥ 0 and the state on the virgin elastic curve,
//     α ≥ α_el(p) (within the tolerance): dα/dp|_el.
//   - None: below the envelope — material that was compacted and unloaded, or
//     is reloading — or in tension: dα/dt = 0. Because a compacted α never
//     rises (below), an unloaded state keeps the α it had when it left the
//     envelope, so it returns to the envelope at the very point it left it,
//     and dα/dt stays 0 until then. In particular compacted material
//     (α < α_e) reloading below p_e does not compact: its elastic range is
//     the frozen-α matrix response, and compacting it would ratchet α down
//     in every tension–compression cycle.
//   The virgin elastic curve is REVERSIBLE (Herrmann 1969; Spheral's
//   PalphaPorosity lets α rise on elastic unloading): a state on it that has
//   never crushed — α ≥ α_v, the distention where the elastic curve meets the
//   crush curve (porosity_virgin_elastic) — follows it both ways, so a load
//   below the crush curve that passes leaves α₀ behind (tested: a
//   load–unload cycle returns α to α₀). Once crushed (α < α_v) α never rises
//   again (PHYSICS.md §4, miluphcuda).
//   dα/dt ≠ 0 when loading on the envelope (the numerator above is > 0; the
//   denominator is > 0 in every sane state, so this is the sign of dp/dt),
//   and when unloading on the virgin elastic curve (then dα/dt ≥ 0, back up
//   the curve towards α_e). 0 for α ≤ 1 or when the denominator is ≤ 0 (a
//   guard; it does not occur for solid matrices).
//   An explicit step can end off the envelope (a shock, p > p_s, or a
//   virgin state unloaded past the curve): the integrator then returns α to
//   it at the end of the step, α ← porous_alpha_on_loading_curve(matrix, pp,
//   ρ, u, α_max) with α_max the start-of-step α, or α_e for a virgin elastic
//   state (porosity_return_bound), and limits the step so that α changes by
//   at most a fraction (PHYSICS.md: 1e-2) per step (porosity_dt_limit).
//
// Sound speed (PorousEosState::c2): the frozen-α value, ∂p/∂ρ|_{u,α} +
//   (p/ρ²) ∂p/∂u|_{ρ,α}, which for p = p_s(αρ, u)/α is exactly the matrix
//   c²(ρ_s, u) (with its floors). This deliberately differs from J08 and
//   PHYSICS.md, which interpolate between c_e and c_s0 in α
//   (porous_elastic_sound_speed2 gives that value, h² c_s²): the
//   interpolated speed is the equilibrium speed along the elastic branch,
//   but with α frozen on unloading and below the envelope the discrete
//   system carries signals at the matrix speed, so a Courant condition built
//   on h c_s would be too long by 1/h (1.3 for porous aluminium, more for
//   very porous materials). The matrix value is an upper bound in every
//   branch (elastic h c_s and plastic speeds are lower), hence safe.
//
// Deviatoric stress (porous_deviatoric_factor): 1/α, the Carroll & Holt /
//   PHYSICS.md scaling S = S_s/α of the matrix stress, equivalently the
//   shear modulus μ = μ_s/α (Spheral's PorousShearModulusPolicy does exactly
//   this). rubble evolves the matrix deviator S_s (Hooke's law with μ_s) and
//   lets S_s/α act.
// Its rate (porous_deviatoric_rate_factor; PorosityParams::
//   deviatoric_rate_factor, on by default): J08 §2 multiply the deviatoric
//   stress rate by f = 1 + (ρ/α) dα/dρ during compaction (miluphcuda's
//   pressure.cu p.f with internal_forces.cu's STRESS_PALPHA_POROSITY;
//   Spheral's optional jutziStateUpdate, fDS). Those codes evolve the bulk
//   deviator S = S_s/α by dS/dt = (f Ṡ_el − S α̇)/α, i.e. the matrix deviator
//   by dS_s/dt = f Ṡ_el: the same as rubble's S_s with its rate times f.
//   Since f dρ/ρ = dρ/ρ + dα/α = dρ_s/ρ_s, the factor makes the deviator
//   follow the MATRIX strain only: pore collapse is not elastic shear of the
//   matrix. Without it a uniaxial compaction of porous_basalt loads the
//   matrix deviator with the whole bulk strain, ~5 times too much by full
//   compaction (test_porosity: porosity_deviator.*). Here dα/dρ is the
//   step's own α̇/ρ̇ (the codes evaluate the chain rule along the adiabat;
//   the same up to the heating of viscosity), clamped to [0, 1] as Spheral
//   does. It inherits a first-order error from an explicit stage that lands
//   just below a curving envelope (that stage sees α̇ = 0, so f = 1, where
//   the end-of-step return corrects α but not S): measured on the uniaxial
//   compaction to full compaction, the matrix deviator is 1.4 % high at
//   2e4 steps and within 1e-4 at 4e4 and 8e4 (test_porosity). Returning the
//   stage states to the envelope would remove it (not done).
// Yield strength: a porous material's Y (von Mises) and k_c (Drucker-Prager)
//   are BULK values — the return limits the acting deviator S_s/α — as in
//   miluphcuda, the J08 lineage whose porous examples rubble's library takes
//   its parameters from. Spheral can instead treat Y as a matrix value
//   (YieldStrengthPolicy's scaleWithPorosity: Y/α for the bulk).
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/eos/eos_derivatives.hpp"

namespace rubble {

enum class CrushCurve : int { Quadratic = 0, Steep = 1 };

struct PorosityParams {          // plain data, copied to the GPU as it is
  bool enabled = false;
  CrushCurve curve = CrushCurve::Quadratic;
  Real alpha_e = 1;              // distention at the elastic limit = initial distention alpha0
  Real p_e = 0;                  // elastic limit [Pa]
  Real p_s = 0;                  // full-compaction pressure [Pa]
  Real p_t = 0, alpha_t = 1;     // steep curve: transition pressure and distention
  Real n1 = 1, n2 = 2;           // steep curve exponents (the quadratic curve is n2 = 2 with one term)
  Real c_e = 0, c_s0 = 0;        // porous elastic sound speed and matrix sound speed [m/s]
  bool deviatoric_rate_factor = true;  // J08's factor f on a porous solid's dS/dt (porous_deviatoric_rate_factor)
};

// Relative tolerance of "on the crush curve / on the elastic curve": far above
// the round-off of α_c(p(ρ, u, α)) (~1e-13 relative), far below any physical
// unloading. A state left more than this below the envelope by an explicit
// step is treated as unloaded for one step, then re-seated by the return to
// the envelope.
constexpr double kPorosityCurveRelTol = 1e-8;

// α on the crush curve (header comment; J08 eq. 8, J09). The curve alone:
// `enabled` is not looked at.
RUBBLE_HD_INLINE Real crush_curve_alpha(const PorosityParams& pp, Real p) {
  if (p <= pp.p_e) return pp.alpha_e;
  if (p >= pp.p_s) return Real(1);
  const Real xs = (pp.p_s - p) / (pp.p_s - pp.p_e);  // in (0, 1)
  switch (pp.curve) {  // no default: a new curve is a compiler warning here
    case CrushCurve::Steep: {
      Real a = Real(1) + (pp.alpha_t - Real(1)) * std::pow(xs, pp.n2);
      if (p < pp.p_t) a += (pp.alpha_e - pp.alpha_t) * std::pow((pp.p_t - p) / (pp.p_t - pp.p_e), pp.n1);
      return a;
    }
    case CrushCurve::Quadratic: break;
  }
  return Real(1) + (pp.alpha_e - Real(1)) * xs * xs;
}

// dα_c/dp ≤ 0; 0 outside (p_e, p_s):
//   quadratic: −2 (α_e − 1)(p_s − p)/(p_s − p_e)²
//   steep:     −n1 (α_e − α_t) x_t^(n1−1)/(p_t − p_e) [p < p_t] − n2 (α_t − 1) x_s^(n2−1)/(p_s − p_e),
//              x_t = (p_t − p)/(p_t − p_e), x_s = (p_s − p)/(p_s − p_e)
RUBBLE_HD_INLINE Real crush_curve_dalpha_dp(const PorosityParams& pp, Real p) {
  if (p <= pp.p_e || p >= pp.p_s) return Real(0);
  const Real ws = pp.p_s - pp.p_e, xs = (pp.p_s - p) / ws;
  switch (pp.curve) {  // no default: a new curve is a compiler warning here
    case CrushCurve::Steep: {
      Real d = -pp.n2 * (pp.alpha_t - Real(1)) * std::pow(xs, pp.n2 - Real(1)) / ws;
      if (p < pp.p_t) {
        const Real wt = pp.p_t - pp.p_e;
        d -= pp.n1 * (pp.alpha_e - pp.alpha_t) * std::pow((pp.p_t - p) / wt, pp.n1 - Real(1)) / wt;
      }
      return d;
    }
    case CrushCurve::Quadratic: break;
  }
  return Real(-2) * (pp.alpha_e - Real(1)) * xs / ws;
}

// ---- elastic branch -------------------------------------------------------

// K_s = ρ_s0 c_s0², ρ_s0 the matrix EOS's reference density; 0 for an ideal
// gas (no reference density: no elastic branch).
RUBBLE_HD_INLINE Real porosity_matrix_bulk_modulus(const EosParams& matrix, const PorosityParams& pp) {
  Real rho0 = 0;
  switch (matrix.kind) {  // no default: a new kind states its reference density here
    case EosKind::Tillotson: rho0 = matrix.tillotson.rho0; break;
    case EosKind::Murnaghan: rho0 = matrix.murnaghan.rho0; break;
    case EosKind::IdealGas: break;
  }
  return rho0 * pp.c_s0 * pp.c_s0;
}

// Whether the elastic branch is on: K_s > 0, 0 < c_e < c_s0, α_e > 1.
RUBBLE_HD_INLINE bool porosity_elastic_enabled(const EosParams& matrix, const PorosityParams& pp) {
  return porosity_matrix_bulk_modulus(matrix, pp) > Real(0) && pp.c_e > Real(0) && pp.c_e < pp.c_s0 &&
         pp.alpha_e > Real(1);
}

// h(α) = c_porous/c_matrix = 1 + (α − 1)(c_e − c_s0)/(c_s0 (α_e − 1)), α taken
// in [1, α_e]; 1 where the elastic branch is off.
RUBBLE_HD_INLINE Real porosity_sound_speed_ratio(const PorosityParams& pp, Real alpha) {
  if (!(pp.c_s0 > Real(0)) || !(pp.c_e > Real(0)) || !(pp.alpha_e > Real(1))) return Real(1);
  const Real a = alpha < Real(1) ? Real(1) : (alpha > pp.alpha_e ? pp.alpha_e : alpha);
  return Real(1) + (a - Real(1)) * (pp.c_e - pp.c_s0) / (pp.c_s0 * (pp.alpha_e - Real(1)));
}

// J08's interpolated (elastic-branch equilibrium) sound speed squared,
// h(α)² c²_matrix; for diagnostics and reports (the solver's c² is the
// frozen-α value, PorousEosState::c2).
RUBBLE_HD_INLINE Real porous_elastic_sound_speed2(const PorosityParams& pp, Real alpha, Real c2_matrix) {
  const Real h = porosity_sound_speed_ratio(pp, alpha);
  return h * h * c2_matrix;
}

// dα/dp on the elastic branch, (α²/K_s)(1 − 1/h²) ≤ 0; 0 where it is off or α ≤ 1.
RUBBLE_HD_INLINE Real porosity_elastic_dalpha_dp(const EosParams& matrix, const PorosityParams& pp, Real alpha) {
  if (!porosity_elastic_enabled(matrix, pp) || alpha <= Real(1)) return Real(0);
  const Real h = porosity_sound_speed_ratio(pp, alpha);
  return alpha * alpha / porosity_matrix_bulk_modulus(matrix, pp) * (Real(1) - Real(1) / (h * h));
}

// p_el(α): the pressure on the virgin elastic curve through (0, α_e), in
// closed form (header comment). 0 for α ≥ α_e, +∞ for α ≤ 1. Where the
// elastic branch is off the "curve" is α = α_e: 0 for α ≥ α_e, +∞ below.
RUBBLE_HD_INLINE Real porosity_elastic_curve_pressure(const EosParams& matrix, const PorosityParams& pp, Real alpha) {
  if (alpha >= pp.alpha_e) return Real(0);
  if (!porosity_elastic_enabled(matrix, pp) || alpha <= Real(1)) return Real(INFINITY);
  const Real K = porosity_matrix_bulk_modulus(matrix, pp);
  const Real k = (pp.c_e / pp.c_s0 - Real(1)) / (pp.alpha_e - Real(1));  // in (−1/(α_e − 1), 0)
  const Real x = alpha - Real(1), xe = pp.alpha_e - Real(1);
  const Real km2 = (k - Real(2)) * (k - Real(2));
  const Real B_k = -k * k / (Real(2) * km2);          // B/k of the partial fractions
  const Real C = Real(-2) * (Real(1) - k) / km2;
  const Real D = -(Real(1) - k) * (Real(1) - k) / (Real(2) - k);
  // Φ(xe) − Φ(x), each term written as a log of a ratio / a difference quotient
  const Real dphi = Real(0.5) * std::log(xe / x) + B_k * std::log((Real(2) + k * xe) / (Real(2) + k * x)) +
                    C * std::log((Real(1) + xe) / (Real(1) + x)) -
                    D * (x - xe) / ((Real(1) + x) * (Real(1) + xe));
  return K / (-k) * dphi;
}

// ---- porous EOS -----------------------------------------------------------

struct PorousEosState {
  Real p;           // p = p_s(αρ, u)/α
  Real c2;          // frozen-α squared sound speed = the matrix c²(αρ, u) (header comment)
  EosState matrix;  // the matrix state at (ρ_s = αρ, u), with the material's add-ons
};

// p = p_s(αρ, u)/α with p_s from eos_evaluate (the material's add-ons), and
// c² = ∂p/∂ρ|_{u,α} + (p/ρ²) ∂p/∂u|_{ρ,α} = c²_s(αρ, u): see the header
// comment for why the solver uses this and not J08's interpolation. With
// porosity off (pp.enabled false) α is ignored (taken as 1): eos_evaluate.
RUBBLE_HD_INLINE PorousEosState porous_eos_evaluate(const EosParams& matrix, const PorosityParams& pp, Real rho, Real u,
                                                    Real alpha) {
  const Real a = pp.enabled ? alpha : Real(1);
  PorousEosState s;
  s.matrix = eos_evaluate(matrix, a * rho, u);
  s.p = s.matrix.p / a;
  s.c2 = s.matrix.c2;
  return s;
}

// ---- evolution ------------------------------------------------------------

enum class PorosityBranch : int { None = 0, Elastic = 1, Plastic = 2 };

// Which slope dα/dp a LOADING state (p, α) follows (header comment): Plastic
// on (or above) the crush curve for p > p_e, Elastic on (or above) the virgin
// elastic curve for p ≥ 0, None below the envelope, in tension, or for α ≤ 1.
RUBBLE_HD_INLINE PorosityBranch porosity_branch(const EosParams& matrix, const PorosityParams& pp, Real p, Real alpha) {
  if (!pp.enabled || alpha <= Real(1)) return PorosityBranch::None;
  const Real tol = Real(kPorosityCurveRelTol) * alpha;
  if (p > pp.p_e && alpha >= crush_curve_alpha(pp, p) - tol) return PorosityBranch::Plastic;
  if (p >= Real(0) && porosity_elastic_enabled(matrix, pp)) {
    // α ≥ α_el(p) − tol  ⇔  p ≥ p_el(α) − tol/|dα/dp|_el  (p_el decreasing in α)
    const Real slope = porosity_elastic_dalpha_dp(matrix, pp, alpha);  // < 0 here
    if (p >= porosity_elastic_curve_pressure(matrix, pp, alpha) + tol / slope) return PorosityBranch::Elastic;
  }
  return PorosityBranch::None;
}

// Whether α belongs to the virgin (never crushed) part of the elastic curve:
// the elastic branch is on and the curve's pressure at α is still below the
// crush curve, α_c(p_el(α)) ≥ α — i.e. α ≥ α_v, where the two curves meet
// (α_el decreases with p and lies below α_c before the meeting point, above
// it after). Crushed material has α < α_v. α_e itself is virgin.
RUBBLE_HD_INLINE bool porosity_virgin_elastic(const EosParams& matrix, const PorosityParams& pp, Real alpha) {
  if (!pp.enabled || !porosity_elastic_enabled(matrix, pp) || alpha <= Real(1)) return false;
  if (alpha >= pp.alpha_e) return true;
  const Real tol = Real(kPorosityCurveRelTol) * alpha;
  return crush_curve_alpha(pp, porosity_elastic_curve_pressure(matrix, pp, alpha)) >= alpha - tol;
}

// The upper bound of the end-of-step return (porous_alpha_on_loading_curve):
// α_e for a virgin elastic state — it may rise back up the reversible curve —
// else the start-of-step α (a crushed α never rises).
RUBBLE_HD_INLINE Real porosity_return_bound(const EosParams& matrix, const PorosityParams& pp, Real alpha_start) {
  return porosity_virgin_elastic(matrix, pp, alpha_start) ? pp.alpha_e : alpha_start;
}

// dα/dp of the branch porosity_branch chooses (0 for None).
RUBBLE_HD_INLINE Real porosity_dalpha_dp(const EosParams& matrix, const PorosityParams& pp, Real p, Real alpha) {
  switch (porosity_branch(matrix, pp, p, alpha)) {
    case PorosityBranch::Plastic: return crush_curve_dalpha_dp(pp, p);
    case PorosityBranch::Elastic: return porosity_elastic_dalpha_dp(matrix, pp, alpha);
    case PorosityBranch::None: break;
  }
  return Real(0);
}

// dα/dt (header comment): the chain rule of J08 with the branch's dα/dp —
// when loading on the envelope (≤ 0), or unloading on the virgin elastic
// curve (≥ 0); 0 otherwise, for α ≤ 1 or porosity off.
RUBBLE_HD_INLINE Real porosity_dalpha_dt(const EosParams& matrix, const PorosityParams& pp, Real rho, Real u, Real alpha,
                                         Real drhodt, Real dudt) {
  if (!pp.enabled || alpha <= Real(1)) return Real(0);
  const Real rho_s = alpha * rho;
  const Real p = eos_evaluate(matrix, rho_s, u).p / alpha;
  const EosDerivatives d = eos_pressure_derivatives_limited(matrix, rho_s, u);
  const Real num = alpha * drhodt * d.dp_drho + dudt * d.dp_du;  // α × dp/dt at frozen α
  const bool loading = num > Real(0);
  const PorosityBranch branch = porosity_branch(matrix, pp, p, alpha);
  // unloading: α frozen, except on the reversible virgin elastic curve
  if (!loading && !(num < Real(0) && branch == PorosityBranch::Elastic && porosity_virgin_elastic(matrix, pp, alpha)))
    return Real(0);
  const Real dadp = branch == PorosityBranch::Plastic   ? crush_curve_dalpha_dp(pp, p)
                    : branch == PorosityBranch::Elastic ? porosity_elastic_dalpha_dp(matrix, pp, alpha)
                                                        : Real(0);
  if (dadp == Real(0)) return Real(0);
  const Real den = alpha + dadp * (p - rho * d.dp_drho);
  if (!(den > Real(0))) return Real(0);
  const Real r = dadp * num / den;
  if (loading) return r < Real(0) ? r : Real(0);
  return r > Real(0) ? r : Real(0);
}

// The return to the loading envelope: the α ≤ alpha_max at which the state
// (ρ, u, α) lies on α_load(p(ρ, u, α)) = min(α_el, α_c); alpha_max itself when
// that state is on or below the envelope. Bisection on "above the envelope",
// which is monotone in α because p = p_s(αρ, u)/α grows with α
// (ρ_s ∂p_s/∂ρ_s > p_s) while α_c(p) falls and p_el(α) falls. Also how a test
// finds the state on the curve. With porosity off: alpha_max.
RUBBLE_HD_INLINE Real porous_alpha_on_loading_curve(const EosParams& matrix, const PorosityParams& pp, Real rho, Real u,
                                                    Real alpha_max) {
  if (!pp.enabled || alpha_max <= Real(1)) return alpha_max;
  const bool elastic = porosity_elastic_enabled(matrix, pp);
  auto above = [&](Real a) {
    const Real p = eos_evaluate(matrix, a * rho, u).p / a;
    if (a > crush_curve_alpha(pp, p)) return true;
    return elastic && p > porosity_elastic_curve_pressure(matrix, pp, a);
  };
  if (!above(alpha_max)) return alpha_max;
  Real lo = 1, hi = alpha_max;  // above(lo) is false: α_c ≥ 1 and p_el(1) = +∞
  for (int it = 0; it < 200; ++it) {
    const Real mid = Real(0.5) * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    if (above(mid)) hi = mid;
    else lo = mid;
  }
  return lo;
}

// Time-step limit that keeps the fractional change of α per step at most
// max_fraction (PHYSICS.md §4: about 1e-2): max_fraction α/|dα/dt|; +∞ when
// dα/dt = 0.
RUBBLE_HD_INLINE Real porosity_dt_limit(Real alpha, Real dalphadt, Real max_fraction) {
  const Real r = dalphadt < Real(0) ? -dalphadt : dalphadt;
  return r > Real(0) ? max_fraction * alpha / r : Real(INFINITY);
}

// J08's factor on a porous solid's deviatoric stress rate (header comment):
// f = 1 + (ρ/α) dα/dρ with dα/dρ = α̇/ρ̇ of the step, clamped to [0, 1]; 1
// when ρ̇ = 0 or α ≤ 1.
RUBBLE_HD_INLINE Real porous_deviatoric_rate_factor(Real rho, Real alpha, Real drhodt, Real dalphadt) {
  if (!(alpha > Real(1)) || drhodt == Real(0) || dalphadt == Real(0)) return Real(1);
  const Real f = Real(1) + rho / alpha * dalphadt / drhodt;
  return f < Real(0) ? Real(0) : (f > Real(1) ? Real(1) : f);
}

// Factor on a porous solid's deviatoric stress (equivalently its shear
// modulus): 1/α (Carroll & Holt 1972; PHYSICS.md §4; Spheral's
// PorousShearModulusPolicy, μ = μ_s/α); 1 with porosity off. See the header
// comment for J08's additional rate factor f.
RUBBLE_HD_INLINE Real porous_deviatoric_factor(const PorosityParams& pp, Real alpha) {
  if (!pp.enabled || !(alpha > Real(1))) return Real(1);
  return Real(1) / alpha;
}

}  // namespace rubble
