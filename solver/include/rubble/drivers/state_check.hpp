#pragma once
// The state check (issue #13): after every step, and on the initial state
// before anything is written, each particle's evolved, derived and rate
// fields must be usable numbers. particle_fault names the first field of
// particle a that is not (kStateOk if none); both backends call it, the
// CUDA one inside a device reduction, so a step returns only an index.
//
//   u                                     finite, and >= u_min: the EOS's
//                                         internal-energy floor where it has
//                                         one (eos.hpp; after each step the
//                                         floor is applied, so this catches
//                                         initial and resumed states)
//   x, v, dv/dt, du/dt, d rho/dt, dS/dt, d alpha/dt,
//   S, eps_v, phi, a_grav, Omega          finite
//   rho, h                                finite and > 0
//   p                                     finite
//   c_s, eps_p                            finite and >= 0
//   alpha                                 finite and >= 1
#include <cmath>
#include <cstdint>

#include "rubble/core/hd.hpp"
#include "rubble/particles/store_view.hpp"

namespace rubble {

enum StateFault : int {
  kStateOk = 0,
  kFaultPosition,
  kFaultVelocity,
  kFaultDensity,
  kFaultSmoothingLength,
  kFaultInternalEnergy,
  kFaultPressure,
  kFaultSoundSpeed,
  kFaultStress,
  kFaultDistention,
  kFaultPlasticStrain,
  kFaultInelasticVolume,
  kFaultAcceleration,
  kFaultEnergyRate,
  kFaultDensityRate,
  kFaultStressRate,
  kFaultDistentionRate,
  kFaultGravity,
  kFaultGradH,
};

// The snapshot field a fault is in, and what it must be.
inline const char* state_fault_field(int fault) {
  switch (fault) {
    case kFaultPosition: return "x";
    case kFaultVelocity: return "v";
    case kFaultDensity: return "rho";
    case kFaultSmoothingLength: return "h";
    case kFaultInternalEnergy: return "u";
    case kFaultPressure: return "p";
    case kFaultSoundSpeed: return "cs";
    case kFaultStress: return "S";
    case kFaultDistention: return "alpha";
    case kFaultPlasticStrain: return "eps_p";
    case kFaultInelasticVolume: return "eps_v";
    case kFaultAcceleration: return "dvdt";
    case kFaultEnergyRate: return "dudt";
    case kFaultDensityRate: return "drhodt";
    case kFaultStressRate: return "dSdt";
    case kFaultDistentionRate: return "dalphadt";
    case kFaultGravity: return "a_grav/phi";
    case kFaultGradH: return "omega";
    default: return "none";
  }
}
inline const char* state_fault_requirement(int fault) {
  switch (fault) {
    case kFaultDensity:
    case kFaultSmoothingLength: return "finite and > 0";
    case kFaultSoundSpeed:
    case kFaultPlasticStrain: return "finite and >= 0";
    case kFaultInternalEnergy: return "finite, and >= 0 where the EOS has the internal-energy floor";
    case kFaultDistention: return "finite and >= 1";
    default: return "finite";
  }
}

template <int D>
RUBBLE_HD_INLINE bool finite_vec(const Vec<D>& v) {
  bool ok = true;
  for (int k = 0; k < D; ++k) ok = ok && std::isfinite(v[k]);
  return ok;
}

template <int D>
RUBBLE_HD_INLINE bool finite_mat(const Mat<D>& m) {
  bool ok = true;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) ok = ok && std::isfinite(m[i][j]);
  return ok;
}

// The first faulty field of particle a (kStateOk if none), in the order
// of the table above: the evolved state before what is derived from it.
// u_min: the floor of a's EOS (-infinity: none).
template <int D>
RUBBLE_HD_INLINE int particle_fault(const StoreView<D>& s, std::uint32_t a, Real u_min = -INFINITY) {
  if (!finite_vec<D>(s.x[a])) return kFaultPosition;
  if (!finite_vec<D>(s.v[a])) return kFaultVelocity;
  if (!(std::isfinite(s.rho[a]) && s.rho[a] > Real(0))) return kFaultDensity;
  if (!(std::isfinite(s.h[a]) && s.h[a] > Real(0))) return kFaultSmoothingLength;
  if (!(std::isfinite(s.u[a]) && s.u[a] >= u_min)) return kFaultInternalEnergy;
  if (s.S && !finite_mat<D>(s.S[a])) return kFaultStress;
  if (s.alpha && !(std::isfinite(s.alpha[a]) && s.alpha[a] >= Real(1))) return kFaultDistention;
  if (s.eps_p && !(std::isfinite(s.eps_p[a]) && s.eps_p[a] >= Real(0))) return kFaultPlasticStrain;
  if (s.eps_v && !std::isfinite(s.eps_v[a])) return kFaultInelasticVolume;
  if (!std::isfinite(s.p[a])) return kFaultPressure;
  if (!(std::isfinite(s.cs[a]) && s.cs[a] >= Real(0))) return kFaultSoundSpeed;
  if (s.omega && !std::isfinite(s.omega[a])) return kFaultGradH;
  if (!finite_vec<D>(s.dvdt[a])) return kFaultAcceleration;
  if (!std::isfinite(s.dudt[a])) return kFaultEnergyRate;
  if (s.drhodt && !std::isfinite(s.drhodt[a])) return kFaultDensityRate;
  if (s.dSdt && !finite_mat<D>(s.dSdt[a])) return kFaultStressRate;
  if (s.dalphadt && !std::isfinite(s.dalphadt[a])) return kFaultDistentionRate;
  if (s.a_grav && !(finite_vec<D>(s.a_grav[a]) && std::isfinite(s.phi[a]))) return kFaultGravity;
  return kStateOk;
}

// Whether particle a passes the state check (the run stops otherwise).
template <int D>
RUBBLE_HD_INLINE bool finite_particle(const StoreView<D>& s, std::uint32_t a, Real u_min = -INFINITY) {
  return particle_fault<D>(s, a, u_min) == kStateOk;
}

}  // namespace rubble
