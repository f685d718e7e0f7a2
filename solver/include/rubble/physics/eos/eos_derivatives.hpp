#pragma once
// Partial derivatives of the pressure, ∂p/∂ρ|_u and ∂p/∂u|_ρ, in closed form
// for every equation of state. The p–α porosity model needs them for the
// matrix material (Jutzi, Benz & Michel 2008, Icarus 198:242, the chain rule
// for dα/dt; PHYSICS.md §4; physics/porosity.hpp).
//
// eos_pressure_derivatives: the RAW equation of state (eos_evaluate_raw):
//   ideal gas   p = (γ − 1) ρ u:   ∂p/∂ρ = (γ − 1) u,         ∂p/∂u = (γ − 1) ρ
//   Murnaghan   isothermal:        ∂p/∂ρ = (K0/ρ0) η^(n−1),   ∂p/∂u = 0
//   Tillotson, compressed (η ≥ 1) and expanded cold (u ≤ E_iv): the
//     compressed formula's partials (tillotson_compressed, tillotson.hpp):
//       ∂p_c/∂ρ = (a + b/ω) u + 2bu(ω − 1)/ω² + (A + 2Bμ)/ρ0
//       ∂p_c/∂u = ρ (a + b/ω²)
//   Tillotson, expanded hot (u ≥ E_cv): the expanded formula's partials
//     (tillotson_expanded):
//       ∂p_e/∂ρ = a u + [b u/ω + 2bu(ω − 1)/ω² + (A e^{−βz}/ρ0)(1 + βμ/η²)] e^{−αz²}
//                 + (bρu/ω + Aμ e^{−βz}) e^{−αz²} · 2αz/(η² ρ0)
//       ∂p_e/∂u = ρ (a + b e^{−αz²}/ω²)
//   Tillotson, partial vaporisation: p = w_c p_c + w_e p_e with the weights
//     w_c = (E_cv − u)/(E_cv − E_iv), w_e = (u − E_iv)/(E_cv − E_iv), which
//     depend on u but not on ρ:
//       ∂p/∂ρ = w_c ∂p_c/∂ρ + w_e ∂p_e/∂ρ
//       ∂p/∂u = w_c ∂p_c/∂u + w_e ∂p_e/∂u + (p_e − p_c)/(E_cv − E_iv)
//   These are direct derivatives, not c² − (p/ρ²) ∂p/∂u; the unit tests
//   (test_porosity.cpp) check them against centred finite differences in
//   every regime, and that ∂p/∂ρ + (p/ρ²) ∂p/∂u reproduces the EOS's own c².
//   At a regime boundary (η = 1, u = E_iv, u = E_cv) p is continuous but
//   ∂p/∂u (and, at η = 1, ∂²p/∂ρ²) has a kink; the value returned is that of
//   the regime tillotson_regime assigns to the state.
//
// eos_pressure_derivatives_limited: the partials of eos_evaluate's p, that is
//   with the material's add-ons (eos.hpp): where the pressure floor p_min
//   acts, p is constant and both partials are 0; where the tension cut-off
//   acts, Murnaghan p = 0 (partials 0) and Tillotson p = w_e p_e, whose
//   partials are w_e ∂p_e/∂ρ and w_e ∂p_e/∂u + p_e/(E_cv − E_iv) (0 in cold
//   states, those of p_e in hot ones). The sound-speed floors change c², not
//   p, and do not enter.
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/eos/eos.hpp"

namespace rubble {

struct EosDerivatives {
  Real dp_drho;  // ∂p/∂ρ at constant specific internal energy u
  Real dp_du;    // ∂p/∂u at constant density ρ
};

// Partial derivatives of the raw EOS (eos_evaluate_raw), see the header comment.
RUBBLE_HD_INLINE EosDerivatives eos_pressure_derivatives(const EosParams& e, Real rho, Real u) {
  EosDerivatives d{Real(0), Real(0)};
  switch (e.kind) {
    case EosKind::Murnaghan:
      d.dp_drho = murnaghan_sound_speed2(e.murnaghan, rho);  // (K0/ρ0) η^(n−1) = dp/dρ
      d.dp_du = Real(0);
      break;
    case EosKind::Tillotson: {
      const TillotsonParams& t = e.tillotson;
      switch (tillotson_regime(t, rho, u)) {
        case TillotsonRegime::Compressed:
        case TillotsonRegime::ExpandedCold: {
          const TillotsonBranch c = tillotson_compressed(t, rho, u);
          d.dp_drho = c.dpdrho;
          d.dp_du = c.dpdu;
          break;
        }
        case TillotsonRegime::ExpandedHot: {
          const TillotsonBranch x = tillotson_expanded(t, rho, u);
          d.dp_drho = x.dpdrho;
          d.dp_du = x.dpdu;
          break;
        }
        case TillotsonRegime::PartialVaporisation: {
          const TillotsonBranch c = tillotson_compressed(t, rho, u), x = tillotson_expanded(t, rho, u);
          const Real width = t.E_cv - t.E_iv;
          const Real wc = (t.E_cv - u) / width, we = (u - t.E_iv) / width;
          d.dp_drho = wc * c.dpdrho + we * x.dpdrho;
          d.dp_du = wc * c.dpdu + we * x.dpdu + (x.p - c.p) / width;
          break;
        }
      }
      break;
    }
    case EosKind::IdealGas:
      d.dp_drho = (e.ideal_gas.gamma - Real(1)) * u;
      d.dp_du = (e.ideal_gas.gamma - Real(1)) * rho;
      break;
  }
  return d;
}

// Partial derivatives of eos_evaluate's pressure (with the tension cut-off
// and the pressure floor), see the header comment.
RUBBLE_HD_INLINE EosDerivatives eos_pressure_derivatives_limited(const EosParams& e, Real rho, Real u) {
  const EosState s = eos_evaluate(e, rho, u);
  if (s.limited & kEosPressureFloor) return EosDerivatives{Real(0), Real(0)};
  const EosLimits& l = e.limits;
  if (l.rho_limit > Real(0)) {
    switch (e.kind) {  // no default: a new kind states its cut-off here
      case EosKind::Murnaghan:
        if (rho < l.rho_limit * e.murnaghan.rho0) return EosDerivatives{Real(0), Real(0)};
        break;
      case EosKind::Tillotson:
        if (rho < l.rho_limit * e.tillotson.rho0) {
          // rho_limit < 1 in practice, so the state is expanded: p = w_e p_e
          const TillotsonBranch hot = tillotson_hot_share(e.tillotson, rho, u);
          return EosDerivatives{hot.dpdrho, hot.dpdu};
        }
        break;
      case EosKind::IdealGas: break;  // no reference density (the scene refuses rho_limit)
    }
  }
  return eos_pressure_derivatives(e, rho, u);
}

}  // namespace rubble
