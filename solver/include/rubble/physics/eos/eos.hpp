#pragma once
// One entry point for every equation of state: the material's EOS is chosen
// at run time from the scene and dispatched here. Each EOS returns the
// pressure and the squared sound speed from (rho, u), and the regime.
//
// eos_evaluate_raw: the equation of state itself (ideal_gas.hpp,
//   murnaghan.hpp, tillotson.hpp), the thermodynamic p and c².
// eos_evaluate: the raw values with the material's add-ons, in this order
//   (docs/physics.md, "Equation of state"):
//   0. internal-energy floor (issue #50 item 2; eos_energy_floor): a state
//      with u below it is evaluated at the floor. Ideal gas: u >= 0 (below,
//      p = (γ−1)ρu < 0). Tillotson: u >= −E0 η²/2, i.e. ω = 1 + u/(E0 η²)
//      >= 1/2: ω vanishes at u = −E0 η², where p and c² diverge; in a vapour
//      at η = 3e-4 that is −1 J/kg (ice), so there the floor is u ≈ 0, while
//      condensed states keep the negative u the energy equation gives them
//      (colder than the reference state; at η = 1 the floor is −E0/2,
//      −5e6 J/kg for ice: a floor at 0 there added the cold compression
//      energy Tillotson keeps outside u, 60 times a self-gravitating basalt
//      sphere's binding energy in 100 s). Murnaghan: none (p does not depend
//      on u). The integrators' stages may pass a u below it (an RK2 stage, a
//      leapfrog prediction); the stored u is raised to the floor at the end
//      of each step, with the energy this adds booked
//      (drivers/step_sequence.hpp, end_step).
//   1. tension cut-off (EosLimits::rho_limit > 0; Murnaghan and Tillotson):
//      for η = ρ/ρ0 < rho_limit, Murnaghan p = 0; Tillotson drops the cold
//      (compressed-formula) share, p = w_e p_e (0 in cold states, p_e
//      unchanged in hot ones) and takes that pressure's c² (0 in cold
//      states, before the floor: tillotson_hot_share). Murnaghan's c² is not
//      changed (finite: K0/ρ0 η^(n−1)).
//   2. minimum pressure (p_min_enabled): p = max(p, p_min).
//   3. Tillotson sound-speed floor, on by default (material key cs_floor):
//      c² = max(c², A/ρ0), the
//      uncompressed bulk value (as Reinhardt & Stadel 2017's Tillotson
//      library and SWIFT's planetary EOS, Kegerreis et al. 2019). It acts
//      only for η < 1 (for η ≥ 1, c² ≥ A/ρ0 already) and covers the cold
//      expanded states where c² ≤ 0.
//   4. minimum sound speed (cs_min > 0): c² = max(c², cs_min²).
// Options 1, 2 and 4 are off unless the material turns them on; 3 is on
// unless it turns it off (then c² ≤ 0 of a cold expanded state reaches the
// driver, which takes c_s = sqrt(max(c², 0))).
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/eos/ideal_gas.hpp"
#include "rubble/physics/eos/murnaghan.hpp"
#include "rubble/physics/eos/tillotson.hpp"

namespace rubble {

enum class EosKind : int { IdealGas = 0, Murnaghan = 1, Tillotson = 2 };

// The add-on options of a material; every one off by default.
struct EosLimits {
  Real rho_limit = 0;          // tension cut-off below η = rho_limit; 0 = off (Murnaghan, Tillotson)
  Real p_min = 0;              // minimum pressure, used when p_min_enabled
  bool p_min_enabled = false;  // (p_min = 0 is a meaningful setting: no tension)
  Real cs_min = 0;             // minimum sound speed; 0 = off
  bool cs_floor = true;        // Tillotson: the floor c^2 >= A/rho0 (on unless the material says cs_floor = false)
};

// Plain-old-data so it can be copied to a device as it is.
struct EosParams {
  EosKind kind = EosKind::IdealGas;
  IdealGasParams ideal_gas{Real(1.4)};
  MurnaghanParams murnaghan{Real(1), Real(1), Real(1)};
  TillotsonParams tillotson{Real(1), Real(1), Real(0), Real(1), Real(1), Real(2), Real(0.5), Real(1), Real(5), Real(5)};
  EosLimits limits{};
};

enum class EosRegime : int {
  IdealGas = 0,
  Murnaghan = 1,
  TillotsonCompressed = 2,
  TillotsonExpandedCold = 3,
  TillotsonPartialVaporisation = 4,
  TillotsonExpandedHot = 5,
};

// Bits of EosState::limited: which add-on changed the raw value.
enum EosLimitFlags : unsigned {
  kEosTensionCutOff = 1u,    // p changed by the tension cut-off
  kEosPressureFloor = 2u,    // p raised to p_min
  kEosSoundSpeedFloor = 4u,  // c² raised to the Tillotson floor A/ρ0
  kEosMinSoundSpeed = 8u,    // c² raised to cs_min²
  kEosEnergyFloor = 16u,     // evaluated at the internal-energy floor (u was below it)
};

// Whether an EOS has the internal-energy floor (add-on 0 above): every kind
// whose pressure depends on u.
RUBBLE_HD_INLINE bool eos_has_energy_floor(const EosParams& e) { return e.kind != EosKind::Murnaghan; }

// The internal-energy floor at density rho [J/kg] (add-on 0 above):
// 0 for the ideal gas, −E0 (rho/rho0)²/2 for Tillotson, −infinity for
// Murnaghan.
RUBBLE_HD_INLINE Real eos_energy_floor(const EosParams& e, Real rho) {
  switch (e.kind) {
    case EosKind::IdealGas: return Real(0);
    case EosKind::Tillotson: {
      const Real eta = rho / e.tillotson.rho0;
      return Real(-0.5) * e.tillotson.E0 * eta * eta;
    }
    case EosKind::Murnaghan: break;
  }
  return Real(-INFINITY);
}

struct EosState {
  Real p;                               // pressure
  Real c2;                              // squared sound speed
  EosRegime regime = EosRegime::IdealGas;
  unsigned limited = 0;                 // EosLimitFlags that acted
};

// The floor of c²: A/ρ0 for Tillotson unless switched off, none (0)
// otherwise.
RUBBLE_HD_INLINE Real eos_c2_floor(const EosParams& e) {
  return e.kind == EosKind::Tillotson && e.limits.cs_floor ? e.tillotson.A / e.tillotson.rho0 : Real(0);
}

RUBBLE_HD_INLINE EosState eos_evaluate_raw(const EosParams& e, Real rho, Real u) {
  EosState s;
  switch (e.kind) {
    case EosKind::Murnaghan:
      s.p = murnaghan_pressure(e.murnaghan, rho);
      s.c2 = murnaghan_sound_speed2(e.murnaghan, rho);
      s.regime = EosRegime::Murnaghan;
      break;
    case EosKind::Tillotson: {
      const TillotsonState t = tillotson_evaluate(e.tillotson, rho, u);
      s.p = t.p;
      s.c2 = t.c2;
      s.regime = static_cast<EosRegime>(static_cast<int>(EosRegime::TillotsonCompressed) + static_cast<int>(t.regime));
      break;
    }
    case EosKind::IdealGas:
      s.p = ideal_gas_pressure(e.ideal_gas, rho, u);
      s.c2 = ideal_gas_sound_speed2(e.ideal_gas, rho, u);
      s.regime = EosRegime::IdealGas;
      break;
  }
  return s;
}

RUBBLE_HD_INLINE EosState eos_evaluate(const EosParams& e, Real rho, Real u) {
  // 0. the internal-energy floor
  const Real u_floor = eos_energy_floor(e, rho);
  const bool floored = u < u_floor;
  if (floored) u = u_floor;
  EosState s = eos_evaluate_raw(e, rho, u);
  if (floored) s.limited |= kEosEnergyFloor;
  const EosLimits& l = e.limits;
  // 1. tension cut-off
  if (l.rho_limit > Real(0)) {
    switch (e.kind) {  // no default: a new kind states its cut-off here
      case EosKind::Murnaghan:
        if (rho < l.rho_limit * e.murnaghan.rho0) {
          if (s.p != Real(0)) s.limited |= kEosTensionCutOff;
          s.p = Real(0);
        }
        break;
      case EosKind::Tillotson:
        if (rho < l.rho_limit * e.tillotson.rho0) {
          const TillotsonState t = tillotson_evaluate(e.tillotson, rho, u);
          if (t.p_cold != Real(0)) s.limited |= kEosTensionCutOff;
          const TillotsonBranch hot = tillotson_hot_share(e.tillotson, rho, u);
          s.p = hot.p;  // = t.p_hot
          s.c2 = hot.dpdrho + hot.p / (rho * rho) * hot.dpdu;  // the sound speed of the pressure left
        }
        break;
      case EosKind::IdealGas: break;  // no reference density (the scene refuses rho_limit)
    }
  }
  // 2. minimum pressure
  if (l.p_min_enabled && s.p < l.p_min) {
    s.p = l.p_min;
    s.limited |= kEosPressureFloor;
  }
  // 3. the Tillotson floor
  const Real floor = eos_c2_floor(e);
  if (floor > Real(0) && s.c2 < floor) {
    s.c2 = floor;
    s.limited |= kEosSoundSpeedFloor;
  }
  // 4. minimum sound speed
  if (l.cs_min > Real(0) && s.c2 < l.cs_min * l.cs_min) {
    s.c2 = l.cs_min * l.cs_min;
    s.limited |= kEosMinSoundSpeed;
  }
  return s;
}

// The specific internal energy u ≥ 0 that gives pressure p at density rho
// (with the material's add-ons), for initial conditions given in pressure;
// −1 when there is none.
//   ideal gas: u = p / ((γ − 1) ρ).
//   Murnaghan: isothermal, p depends on ρ alone: u = 0 when p equals p(ρ) to
//     1e-12 K0, otherwise −1.
//   Tillotson: bisection on [0, u_hi], u_hi doubled from E_cv until
//     p(ρ, u_hi) ≥ p; −1 when p(ρ, 0) > p (a lower pressure would need
//     u < 0) or p is out of reach. Where p(u) is not monotonic (partial
//     vaporisation can bend it) this is one root of the bracket.
RUBBLE_HD_INLINE Real eos_internal_energy_from_pressure(const EosParams& e, Real rho, Real p) {
  switch (e.kind) {
    case EosKind::Murnaghan: {
      const Real pm = eos_evaluate(e, rho, Real(0)).p;
      const Real diff = pm > p ? pm - p : p - pm;
      return diff <= Real(1e-12) * e.murnaghan.K0 ? Real(0) : Real(-1);
    }
    case EosKind::Tillotson: {
      Real lo = 0, hi = e.tillotson.E_cv;
      const Real p_lo = eos_evaluate(e, rho, lo).p;
      if (p_lo == p) return Real(0);
      if (p_lo > p) return Real(-1);
      int doublings = 0;
      while (eos_evaluate(e, rho, hi).p < p) {
        lo = hi;
        hi *= Real(2);
        if (++doublings > 200) return Real(-1);
      }
      // p(lo) < p <= p(hi): halve until the bracket stops shrinking
      for (int it = 0; it < 200; ++it) {
        const Real mid = Real(0.5) * (lo + hi);
        if (!(mid > lo && mid < hi)) break;
        if (eos_evaluate(e, rho, mid).p < p) lo = mid;
        else hi = mid;
      }
      return hi;
    }
    case EosKind::IdealGas: break;
  }
  return p / ((e.ideal_gas.gamma - Real(1)) * rho);  // the ideal gas
}

// Host helper: the EOS kind's name as scenes write it (`eos = "..."`).
inline const char* eos_kind_name(EosKind k) {
  switch (k) {  // no default: a new kind is a compiler warning here
    case EosKind::IdealGas: return "ideal_gas";
    case EosKind::Murnaghan: return "murnaghan";
    case EosKind::Tillotson: return "tillotson";
  }
  return "unknown";
}

// Host helper: the regime's name as `rubble eos` prints it.
inline const char* eos_regime_name(EosRegime r) {
  switch (r) {
    case EosRegime::IdealGas: return "ideal_gas";
    case EosRegime::Murnaghan: return "murnaghan";
    case EosRegime::TillotsonCompressed: return tillotson_regime_name(TillotsonRegime::Compressed);
    case EosRegime::TillotsonExpandedCold: return tillotson_regime_name(TillotsonRegime::ExpandedCold);
    case EosRegime::TillotsonPartialVaporisation: return tillotson_regime_name(TillotsonRegime::PartialVaporisation);
    case EosRegime::TillotsonExpandedHot: return tillotson_regime_name(TillotsonRegime::ExpandedHot);
  }
  return "unknown";
}

}  // namespace rubble
