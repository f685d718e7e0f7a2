// MaterialConfig (validated, double precision) -> EosParams (Real, POD,
// device-ready). The TOML side of materials lives in scene_parser.cpp.
#include "rubble/scene/materials.hpp"

namespace rubble {

EosParams eos_params_from_material(const MaterialConfig& m) {
  EosParams e;
  switch (m.eos) {
    case EosType::Murnaghan:
      e.kind = EosKind::Murnaghan;
      e.murnaghan = {Real(m.murnaghan.rho0), Real(m.murnaghan.K0), Real(m.murnaghan.n)};
      break;
    case EosType::Tillotson: {
      const TillotsonConfig& t = m.tillotson;
      e.kind = EosKind::Tillotson;
      e.tillotson = {Real(t.rho0), Real(t.A),  Real(t.B), Real(t.E0),    Real(t.E_iv),
                     Real(t.E_cv), Real(t.a),  Real(t.b), Real(t.alpha), Real(t.beta)};
      break;
    }
    case EosType::IdealGas:
    default:
      e.kind = EosKind::IdealGas;
      e.ideal_gas.gamma = Real(m.gamma);
      break;
  }
  e.limits.rho_limit = Real(m.eos_options.rho_limit);
  e.limits.p_min_enabled = m.eos_options.p_min_enabled;
  e.limits.p_min = Real(m.eos_options.p_min);
  e.limits.cs_min = Real(m.eos_options.cs_min);
  e.limits.cs_floor = m.eos_options.cs_floor;
  return e;
}

}  // namespace rubble
