#pragma once
// Tillotson equation of state (Tillotson 1962, General Atomic GA-3216;
// Melosh 1989, Impact Cratering, App. II; Benz & Asphaug 1999, Icarus
// 142:5; seed paper eqs. 8-9; PHYSICS.md §3).
//
//   η = ρ/ρ0,  μ = η − 1,  z = 1/η − 1,  ω = u/(E0 η²) + 1
//   compressed formula  p_c = (a + b/ω) ρ u + A μ + B μ²
//   expanded formula    p_e = a ρ u + [b ρ u/ω + A μ e^{−β z}] e^{−α z²}
//
// Regimes (TillotsonRegime):
//   Compressed           η ≥ 1 (any u)                 p = p_c
//   ExpandedCold         η < 1, u ≤ E_iv               p = p_c
//   PartialVaporisation  η < 1, E_iv < u < E_cv        p = w_c p_c + w_e p_e,
//                        w_c = (E_cv − u)/(E_cv − E_iv), w_e = (u − E_iv)/(E_cv − E_iv)
//   ExpandedHot          η < 1, u ≥ E_cv               p = p_e
// p is continuous across η = 1 (p_c = p_e there), u = E_iv and u = E_cv;
// ∂p/∂u has kinks at E_iv and E_cv, so c² jumps there.
//
// Sound speed c² = ∂p/∂ρ|_u + (p/ρ²) ∂p/∂u|_ρ, in closed form:
//   compressed / cold: PHYSICS.md's first closed form (form 1 below), whose
//     modulus term is (A + 2Bμ)/ρ0 — not /ρ;
//   expanded hot: the same definition with p_e's partial derivatives;
//   partial vaporisation: the branches' partial derivatives blended with the
//     pressure's weights, plus the weights' own u-derivative,
//       c² = w_c c²_c(p) + w_e c²_e(p) + (p/ρ²)(p_e − p_c)/(E_cv − E_iv),
//     where c²_X(p) = ∂p_X/∂ρ + (p/ρ²) ∂p_X/∂u is the branch's closed form
//     evaluated with the blended p. The last term is what makes c² the
//     derivative of the blended pressure; a blend of c² alone misses it.
// These are the raw thermodynamic values: c² < 0 occurs in cold expanded
// (tension) states. The floor and the other add-ons are applied by eos.hpp.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

struct TillotsonParams {
  Real rho0 = 0;   // reference density ρ0 [kg/m³] (> 0)
  Real A = 0;      // bulk modulus [Pa] (> 0)
  Real B = 0;      // nonlinear compression coefficient [Pa] (>= 0)
  Real E0 = 0;     // E0 [J/kg] (the energy scale in ω; > 0)
  Real E_iv = 0;   // specific energy of incipient vaporisation [J/kg] (> 0)
  Real E_cv = 0;   // specific energy of complete vaporisation [J/kg] (> E_iv)
  Real a = 0;      // dimensionless (>= 0)
  Real b = 0;      // dimensionless (>= 0)
  Real alpha = 0;  // α: decay of the expanded terms, e^{−α z²} (>= 0)
  Real beta = 0;   // β: decay of the cold term, e^{−β z} (>= 0)
};

enum class TillotsonRegime : int { Compressed = 0, ExpandedCold = 1, PartialVaporisation = 2, ExpandedHot = 3 };

// A branch formula's pressure and partial derivatives ∂p/∂ρ|_u, ∂p/∂u|_ρ.
struct TillotsonBranch {
  Real p;
  Real dpdrho;
  Real dpdu;
};

struct TillotsonState {
  Real p;       // pressure = p_cold + p_hot
  Real c2;      // squared sound speed (raw: may be ≤ 0 in tension)
  Real p_cold;  // the compressed formula's share w_c p_c (w_c = 1 cold, 0 hot)
  Real p_hot;   // the expanded formula's share w_e p_e
  TillotsonRegime regime;
};

// Compressed formula p_c (also the cold expanded one) and its derivatives:
//   ∂p_c/∂ρ = (a + b/ω) u + 2bu(ω − 1)/ω² + (A + 2Bμ)/ρ0
//   ∂p_c/∂u = ρ (a + b/ω²)
RUBBLE_HD_INLINE TillotsonBranch tillotson_compressed(const TillotsonParams& t, Real rho, Real u) {
  const Real eta = rho / t.rho0, mu = eta - Real(1);
  const Real omega = u / (t.E0 * eta * eta) + Real(1);
  TillotsonBranch r;
  r.p = (t.a + t.b / omega) * rho * u + t.A * mu + t.B * mu * mu;
  r.dpdrho = (t.a + t.b / omega) * u + Real(2) * t.b * u * (omega - Real(1)) / (omega * omega) +
             (t.A + Real(2) * t.B * mu) / t.rho0;
  r.dpdu = rho * (t.a + t.b / (omega * omega));
  return r;
}

// Expanded formula p_e and its derivatives; with X = bρu/ω, Y = Aμ e^{−βz},
// E = e^{−αz²} and dz/dρ = −1/(η² ρ0):
//   ∂p_e/∂ρ = a u + [b u/ω + 2bu(ω − 1)/ω² + (A e^{−βz}/ρ0)(1 + βμ/η²)] E
//             + (X + Y) E · 2αz/(η² ρ0)
//   ∂p_e/∂u = ρ (a + b E/ω²)
RUBBLE_HD_INLINE TillotsonBranch tillotson_expanded(const TillotsonParams& t, Real rho, Real u) {
  const Real eta = rho / t.rho0, mu = eta - Real(1), eta2 = eta * eta;
  const Real omega = u / (t.E0 * eta2) + Real(1);
  const Real z = t.rho0 / rho - Real(1);
  const Real eb = std::exp(-t.beta * z), ea = std::exp(-t.alpha * z * z);
  const Real X = t.b * rho * u / omega, Y = t.A * mu * eb;
  TillotsonBranch r;
  r.p = t.a * rho * u + (X + Y) * ea;
  r.dpdrho = t.a * u +
             (t.b * u / omega + Real(2) * t.b * u * (omega - Real(1)) / (omega * omega) +
              t.A * eb / t.rho0 * (Real(1) + t.beta * mu / eta2)) *
                 ea +
             (X + Y) * ea * Real(2) * t.alpha * z / (eta2 * t.rho0);
  r.dpdu = rho * (t.a + t.b * ea / (omega * omega));
  return r;
}

// PHYSICS.md §3, first closed form of the compressed-branch c², for a given
// pressure p (p_c itself, or the blended p in partial vaporisation):
//   c² = (a + b/ω)u + 2bu(ω − 1)/ω² + (A + 2Bμ)/ρ0 + (p/ρ)[a + b/ω − b(ω − 1)/ω²]
RUBBLE_HD_INLINE Real tillotson_compressed_c2_form1(const TillotsonParams& t, Real rho, Real u, Real p) {
  const Real eta = rho / t.rho0, mu = eta - Real(1);
  const Real omega = u / (t.E0 * eta * eta) + Real(1), w2 = omega * omega;
  return (t.a + t.b / omega) * u + Real(2) * t.b * u * (omega - Real(1)) / w2 + (t.A + Real(2) * t.B * mu) / t.rho0 +
         p / rho * (t.a + t.b / omega - t.b * (omega - Real(1)) / w2);
}

// The second closed form (equal to the first when p = p_c; checked in
// test_eos.cpp; not used by the solver — do not mix terms of the two):
//   c² = (p/ρ)(1 + a + b/ω) + b(ω − 1)/ω² (2u − p/ρ) + (A + B(η² − 1))/ρ
RUBBLE_HD_INLINE Real tillotson_compressed_c2_form2(const TillotsonParams& t, Real rho, Real u, Real p) {
  const Real eta = rho / t.rho0;
  const Real omega = u / (t.E0 * eta * eta) + Real(1);
  return p / rho * (Real(1) + t.a + t.b / omega) + t.b * (omega - Real(1)) / (omega * omega) * (Real(2) * u - p / rho) +
         (t.A + t.B * (eta * eta - Real(1))) / rho;
}

RUBBLE_HD_INLINE TillotsonRegime tillotson_regime(const TillotsonParams& t, Real rho, Real u) {
  if (rho >= t.rho0) return TillotsonRegime::Compressed;
  if (u <= t.E_iv) return TillotsonRegime::ExpandedCold;
  if (u >= t.E_cv) return TillotsonRegime::ExpandedHot;
  return TillotsonRegime::PartialVaporisation;
}

RUBBLE_HD_INLINE TillotsonState tillotson_evaluate(const TillotsonParams& t, Real rho, Real u) {
  TillotsonState s;
  s.regime = tillotson_regime(t, rho, u);
  const Real rho2 = rho * rho;
  switch (s.regime) {
    case TillotsonRegime::Compressed:
    case TillotsonRegime::ExpandedCold: {
      const TillotsonBranch c = tillotson_compressed(t, rho, u);
      s.p_cold = c.p;
      s.p_hot = Real(0);
      s.p = c.p;
      s.c2 = tillotson_compressed_c2_form1(t, rho, u, c.p);
      break;
    }
    case TillotsonRegime::ExpandedHot: {
      const TillotsonBranch e = tillotson_expanded(t, rho, u);
      s.p_cold = Real(0);
      s.p_hot = e.p;
      s.p = e.p;
      s.c2 = e.dpdrho + e.p / rho2 * e.dpdu;
      break;
    }
    case TillotsonRegime::PartialVaporisation: {
      const TillotsonBranch c = tillotson_compressed(t, rho, u), e = tillotson_expanded(t, rho, u);
      const Real width = t.E_cv - t.E_iv;
      const Real wc = (t.E_cv - u) / width, we = (u - t.E_iv) / width;
      s.p_cold = wc * c.p;
      s.p_hot = we * e.p;
      s.p = s.p_cold + s.p_hot;
      s.c2 = wc * tillotson_compressed_c2_form1(t, rho, u, s.p) + we * (e.dpdrho + s.p / rho2 * e.dpdu) +
             s.p / rho2 * (e.p - c.p) / width;
      break;
    }
  }
  return s;
}

// The expanded formula's share of the pressure, p_hot = w_e p_e (0 cold, the
// blend's share in partial vaporisation, p_e hot; 0 for η ≥ 1), with its
// partial derivatives: ∂/∂ρ = w_e ∂p_e/∂ρ, ∂/∂u = w_e ∂p_e/∂u + p_e/(E_cv − E_iv)
// in partial vaporisation. It is the pressure the tension cut-off leaves
// (eos.hpp), whose sound speed and partials both the EOS and
// eos_derivatives.hpp take from here.
RUBBLE_HD_INLINE TillotsonBranch tillotson_hot_share(const TillotsonParams& t, Real rho, Real u) {
  switch (tillotson_regime(t, rho, u)) {
    case TillotsonRegime::ExpandedHot: return tillotson_expanded(t, rho, u);
    case TillotsonRegime::PartialVaporisation: {
      const TillotsonBranch x = tillotson_expanded(t, rho, u);
      const Real width = t.E_cv - t.E_iv;
      const Real we = (u - t.E_iv) / width;
      return TillotsonBranch{we * x.p, we * x.dpdrho, we * x.dpdu + x.p / width};
    }
    case TillotsonRegime::Compressed:
    case TillotsonRegime::ExpandedCold: break;  // cold: no hot share
  }
  return TillotsonBranch{Real(0), Real(0), Real(0)};
}

// Host helper: the regime's name as `rubble eos` prints it.
inline const char* tillotson_regime_name(TillotsonRegime r) {
  switch (r) {
    case TillotsonRegime::Compressed: return "compressed";
    case TillotsonRegime::ExpandedCold: return "expanded_cold";
    case TillotsonRegime::PartialVaporisation: return "partial_vaporisation";
    case TillotsonRegime::ExpandedHot: return "expanded_hot";
  }
  return "unknown";
}

}  // namespace rubble
