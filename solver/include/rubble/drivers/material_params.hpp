#pragma once
// Per-material coefficients in a device-friendly form (plain data, copied to
// the GPU as an array indexed by material_id).
#include "rubble/core/real.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/damage.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/plasticity.hpp"
#include "rubble/physics/porosity.hpp"
#include "rubble/physics/viscosity_switch.hpp"

namespace rubble {

struct MaterialParams {
  EosParams eos;
  ViscosityParams av;   // constant coefficients, or alpha_max and beta with the switch
  ViscositySwitchParams av_switch;  // per-particle alpha (enabled = false: constant)
  Real alpha_u;        // artificial conductivity (0 = off)
  Real shear_modulus;  // mu (0 = no strength)
  Real as_epsilon;     // artificial stress epsilon (0 = off)
  Real as_exponent;    // artificial stress n (0 = off)
  Real as_clump_onset;  // clumping form: chi > 0 below onset * spacing (0 = Monaghan's form)
  Real as_clump_full;   // clumping form: chi = 1 below full * spacing
  Real dp;             // initial particle spacing of the material's bodies
  Real stress_diffusion;  // zeta of the deviatoric stress diffusion (0 = off; physics/stress_diffusion.hpp)
  Real k0;                // its geostatic lateral stress ratio K0 (1 - sin phi for Drucker-Prager, else 1)
  PorosityParams porosity;      // p-alpha (porosity.enabled = false: not porous)
  PlasticityParams plasticity;  // model None: elastic (or fluid)
  DamageParams damage;          // enabled = false: no tensile damage
};

// Built from a scene's materials by material_params_from_scene
// (rubble/drivers/run_physics.hpp).

}  // namespace rubble
