#pragma once
// Which feature set the right-hand side runs (DESIGN.md principle 2),
// decided once from the scene's materials and checked against the fields
// the store allocated; both drivers (hydro_cpu.cpp, cuda_stepper.cu) ask here.
#include <vector>

#include "rubble/core/error.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

struct RhsFeatures {
  bool solid = false;              // a material has a shear modulus: feature set Solid
  bool artificial_stress = false;  // a solid material has artificial stress
  bool kernel_correction = false;  // solids: corrected velocity gradient
  bool stress_diffusion = false;   // a solid material diffuses its deviatoric stress
  bool porosity = false;           // a material is porous: d alpha/dt with the rates, end-of-step envelope return
  bool plasticity = false;         // a solid material yields: return mapping in each evaluation and step
  bool damage = false;             // a solid material has tensile damage: its growth rate, end-of-step cap
  bool body_force = false;         // simulation.gravity is not zero
  bool wall_extrapolation = false; // a boundary body has boundary_state = "extrapolated"
  bool viscosity_switch = false;   // a material's viscosity alpha is per particle: its rate, end-of-step bounds
};

// Throws RunError when the store lacks a field the features need.
template <int D>
RhsFeatures rhs_features(const Scene& scene, const std::vector<MaterialParams>& materials, const ParticleStore<D>& ps) {
  RhsFeatures f;
  for (const MaterialParams& m : materials) {
    f.solid = f.solid || m.shear_modulus > Real(0);
    f.artificial_stress = f.artificial_stress || m.as_exponent > Real(0);
    f.stress_diffusion = f.stress_diffusion || (m.shear_modulus > Real(0) && m.stress_diffusion > Real(0));
    f.porosity = f.porosity || m.porosity.enabled;
    f.plasticity = f.plasticity || m.plasticity.model != PlasticityModel::None;
    f.damage = f.damage || m.damage.enabled;
    f.viscosity_switch = f.viscosity_switch || m.av_switch.enabled;
  }
  for (int k = 0; k < D; ++k) f.body_force = f.body_force || scene.simulation.gravity[k] != 0;
  for (const BodyConfig& b : scene.bodies)
    f.wall_extrapolation = f.wall_extrapolation ||
                           (b.boundary != BoundaryKind::None && b.boundary_state == BoundaryState::Extrapolated);
  if (f.porosity && (ps.alpha.size() != ps.n || ps.dalphadt.size() != ps.n))
    throw RunError("porous materials need the alpha and dalphadt fields allocated");
  if (f.viscosity_switch && (ps.av_alpha.size() != ps.n || ps.dav_alpha_dt.size() != ps.n))
    throw RunError("the viscosity switch needs the av_alpha and dav_alpha_dt fields allocated");
  if (f.plasticity && (!f.solid || ps.eps_p.size() != ps.n))
    throw RunError("plasticity needs a solid with the eps_p field allocated");
  if (f.damage && (!f.solid || ps.damage_root.size() != ps.n || ps.flaw_count.size() != ps.n))
    throw RunError("damage needs a solid with the damage and flaw fields allocated");
  if (f.solid) {
    if (scene.simulation.density == DensityForm::Summation || ps.S.size() != ps.n || ps.dSdt.size() != ps.n)
      throw RunError("solids need continuity density with the S and dSdt fields allocated");
    f.kernel_correction = scene.simulation.kernel_correction;
    if (f.kernel_correction && ps.corr_K.size() != ps.n)
      throw RunError("the kernel-gradient correction needs the corr_K field allocated");
  }
  if (scene.simulation.xsph > 0 && ps.xsph_v.size() != ps.n) throw RunError("XSPH needs the xsph_v field allocated");
  return f;
}

}  // namespace rubble
