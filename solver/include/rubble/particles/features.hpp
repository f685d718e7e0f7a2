#pragma once
// Which physics a run has on: decided once from the scene
// (features_of_scene, rubble/drivers/run_physics.hpp), then read by the
// particle store to allocate its fields (ParticleStore::allocate: a field
// no feature needs is never allocated) and by the step sequence to pick
// its passes (rubble/drivers/step_sequence.hpp: a pass no feature needs is
// never run). DESIGN.md principle 2: one struct for both, so that what is
// stored and what is computed cannot disagree.
namespace rubble {

struct Features {
  // ---- each allocates fields (ParticleStore::allocate) and selects passes
  bool continuity_density = false;  // rho is evolved (d rho/dt stored); else summation
  bool summation_density = false;   // grad-h factor omega is stored
  bool gravity = false;             // self-gravity (3-D): a_grav and phi are stored
  bool solid = false;               // a material has a shear modulus: S and dSdt; feature set Solid
  bool boundary = false;            // a body is made of boundary particles: held each evaluation; wall_force
  bool rigid_tools = false;         // a boundary body turns or is driven (physics/rigid_body.hpp): tool, tool_offset
  bool xsph = false;                // XSPH: the position-rate correction is stored
  bool kernel_correction = false;   // solids with simulation.kernel_correction: K = C^T is stored
  bool porosity = false;            // a material is porous (p-alpha): alpha and dalphadt; envelope return
  bool plasticity = false;          // a solid material yields: eps_p; return mapping each evaluation and step
  bool free_slip = false;           // a wall slides (free-slip or Coulomb): wall_normal is stored
  bool wall_friction = false;       // a wall has Coulomb friction: wall_friction, wall_anchor, wall_grip; anchors
  bool inelastic_volume = false;    // a Drucker-Prager material (tension cracking, dilatancy): eps_v is stored
  bool damage = false;              // a solid material has tensile damage: damage and flaw fields; its cap
  bool viscosity_switch = false;    // a material has the viscosity switch: av_alpha and dav_alpha_dt; its bounds
  // ---- passes only (no field of their own)
  bool artificial_stress = false;   // a solid material has artificial stress (R_a, scratch)
  bool stress_diffusion = false;    // a solid material diffuses its deviatoric stress
  bool body_force = false;          // simulation.gravity is not zero
  bool wall_extrapolation = false;  // a boundary body has boundary_state = "extrapolated"
  bool shifting = false;            // simulation.shifting > 0: particle shifting after each step
  bool staggered = false;           // solids, simulation.stress_update = "staggered" (leapfrog.hpp)
  bool energy_floor = false;        // a material's EOS has the internal-energy floor (eos.hpp): raised to it after each step
};

}  // namespace rubble
