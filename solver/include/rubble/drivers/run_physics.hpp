#pragma once
// Scene -> physics, built once per run (DESIGN.md principle 2): which
// physics is on (Features: drives what the store allocates and which
// passes the step runs), each material's device-ready coefficients
// (MaterialParams) and the run-wide constants of the right-hand side. Both
// backends, the initial conditions and `rubble eos` read them from here;
// nothing else converts a scene's configuration into physics parameters.
// Implemented in solver/src/run_physics.cpp.
#include <array>
#include <string>
#include <vector>

#include "rubble/core/error.hpp"
#include "rubble/core/real.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/particles/features.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Which physics the scene has on.
Features features_of_scene(const Scene& scene);

// The smoothing-length factor h = hfact dx: simulation.hfact, or the
// kernel's default when it is 0.
double smoothing_factor(const SimulationConfig& sim);

// The device-ready parameters of a validated material's parts (the scene
// holds porosity's and damage's own; plasticity's constants are derived).
EosParams eos_params_from_material(const MaterialConfig& m);
PlasticityParams plasticity_params_from_config(const PlasticityConfig& c);

// One entry per scene material, in material_id order.
std::vector<MaterialParams> material_params_from_scene(const Scene& scene);

// A rigid tool as the scene gives it (physics/rigid_body.hpp; scene keys
// in docs/scene.md): tool k is the k-th body with BodyConfig::rigid_tool().
struct RigidToolSpec {
  int body = 0;                       // its index in scene.bodies
  bool driven = false;                // driven by forces; else its motion is prescribed
  std::array<double, 3> centre{};     // rotation centre at t = 0 [m]
  std::array<double, 3> velocity{};   // (initial) velocity [m/s]
  std::array<double, 3> axis{0, 0, 1};
  double angular_velocity = 0;        // (initial) [rad/s]
  std::array<double, 3> applied_force{};
  double applied_torque = 0;
  std::array<bool, 3> free_axis{true, true, true};
  bool free_rotation = true;
  double mass = 0, inertia = 0;       // 0: the particles' own
};

// Everything the step needs to know of the scene, fixed for the run.
struct RunPhysics {
  Features on;
  std::vector<MaterialParams> materials;  // by material_id
  KernelType kernel = KernelType::CubicSpline;
  Real hfact = 0;
  Real courant = 0, force_factor = 0;
  Real h_tolerance = 0;   // summation density: |dh|/h of the Newton iteration
  Real xsph_epsilon = 0;  // 0: off
  Real shifting = 0;      // particle shifting coefficient A (0: off)
  // the energy watchdog's bound per step, a fraction of the energy scale
  // (simulation.energy_step_tolerance; its default courant^2; 0: off)
  double energy_step_tolerance = 0;
  Real density_step_fraction = 0;  // continuity density: simulation.density_step_fraction (0: no limit)
  bool geometric_force = false;     // simulation.pressure_force = "geometric" (physics/hydro.hpp)
  Real body_force[3] = {0, 0, 0};  // simulation.gravity
  GravityConfig gravity;  // self-gravity ([gravity]; mode Off: none)
  std::vector<RigidToolSpec> tools;  // rigid tools, in body order (none: empty)
};

RunPhysics run_physics(const Scene& scene);

// Throws RunError when the store lacks a field the features need (a store
// not allocated from these features, e.g. a test's or a snapshot's).
template <int D>
void require_fields(const Features& on, const ParticleStore<D>& ps) {
  auto has = [&](const auto& field) { return field.size() == ps.n; };
  if (on.gravity && (D != 3 || !has(ps.a_grav) || !has(ps.phi)))
    throw RunError("self-gravity needs a 3-D scene with the a_grav and phi fields allocated");
  if (on.porosity && (!has(ps.alpha) || !has(ps.dalphadt)))
    throw RunError("porous materials need the alpha and dalphadt fields allocated");
  if (on.viscosity_switch && (!has(ps.av_alpha) || !has(ps.dav_alpha_dt)))
    throw RunError("the viscosity switch needs the av_alpha and dav_alpha_dt fields allocated");
  if (on.plasticity && (!on.solid || !has(ps.eps_p)))
    throw RunError("plasticity needs a solid with the eps_p field allocated");
  if (on.damage && (!on.solid || !has(ps.damage_root) || !has(ps.flaw_count)))
    throw RunError("damage needs a solid with the damage and flaw fields allocated");
  if (on.solid && (on.summation_density || !has(ps.S) || !has(ps.dSdt)))
    throw RunError("solids need continuity density with the S and dSdt fields allocated");
  if (on.kernel_correction && !has(ps.corr_K))
    throw RunError("the kernel-gradient correction needs the corr_K field allocated");
  if (on.xsph && !has(ps.xsph_v)) throw RunError("XSPH needs the xsph_v field allocated");
  if (on.wall_friction && !has(ps.wall_anchor))
    throw RunError("Coulomb walls need the wall_anchor field allocated");
}

}  // namespace rubble
