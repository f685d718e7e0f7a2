// Scene -> physics, built once per run (rubble/drivers/run_physics.hpp).
#include "rubble/drivers/run_physics.hpp"

#include <cmath>
#include <numbers>

#include "rubble/drivers/particle_rates.hpp"
#include "rubble/physics/kernels.hpp"

namespace rubble {

Features features_of_scene(const Scene& scene) {
  const SimulationConfig& sim = scene.simulation;
  Features on;
  on.summation_density = sim.density == DensityForm::Summation;
  on.continuity_density = sim.density == DensityForm::Continuity;
  on.gravity = scene.gravity.mode != GravityMode::Off;
  for (const MaterialConfig& m : scene.materials) {
    const bool solid = m.shear_modulus > 0;
    on.solid = on.solid || solid;
    on.porosity = on.porosity || m.porosity.enabled;
    on.plasticity = on.plasticity || m.plasticity.model != PlasticityModel::None;
    // every Drucker-Prager material stores eps_v: its tension-cracking
    // opening persists (and so does dilatant flow, psi > 0)
    on.inelastic_volume = on.inelastic_volume || m.plasticity.model == PlasticityModel::DruckerPrager;
    on.damage = on.damage || m.damage.enabled;
    on.viscosity_switch = on.viscosity_switch || m.viscosity.switch_on;
    on.artificial_stress = on.artificial_stress || (solid && m.artificial_stress.enabled && m.artificial_stress.n > 0);
    on.stress_diffusion = on.stress_diffusion || (solid && m.stress_diffusion > 0);
    on.energy_floor = on.energy_floor || eos_has_energy_floor(eos_params_from_material(m));
  }
  for (const BodyConfig& b : scene.bodies) {
    const bool wall = b.boundary != BoundaryKind::None;
    on.boundary = on.boundary || wall;
    on.free_slip = on.free_slip || b.sliding_wall();
    on.wall_friction = on.wall_friction || b.wall_slip == WallSlip::Coulomb;
    on.wall_extrapolation = on.wall_extrapolation || (wall && b.boundary_state == BoundaryState::Extrapolated);
    on.rigid_tools = on.rigid_tools || b.rigid_tool();
  }
  on.xsph = sim.xsph > 0;
  on.kernel_correction = on.solid && sim.kernel_correction;
  for (int k = 0; k < 3; ++k) on.body_force = on.body_force || sim.gravity[k] != 0;
  on.shifting = sim.shifting > 0;
  on.staggered = on.solid && sim.stress_update == StressUpdate::Staggered;
  return on;
}

double smoothing_factor(const SimulationConfig& sim) {
  return sim.hfact > 0 ? sim.hfact : kernel_default_hfact(sim.kernel);
}

EosParams eos_params_from_material(const MaterialConfig& m) {
  EosParams e;
  e.kind = m.eos;
  // the scene holds the EOS's own parameters; only the kind's are used
  switch (m.eos) {  // no default: a new EOS kind is a compiler warning here
    case EosKind::Murnaghan: e.murnaghan = m.murnaghan; break;
    case EosKind::Tillotson: e.tillotson = m.tillotson; break;
    case EosKind::IdealGas: e.ideal_gas.gamma = Real(m.gamma); break;
  }
  e.limits = m.eos_options;
  return e;
}

PlasticityParams plasticity_params_from_config(const PlasticityConfig& c) {
  switch (c.model) {  // no default: a new model is a compiler warning here
    case PlasticityModel::VonMises: return von_mises_params(Real(c.yield_stress));
    case PlasticityModel::Collins:
      return collins_params(Real(c.cohesion), Real(c.friction_intact), Real(c.strength_limit),
                            Real(c.cohesion_damaged), Real(c.friction_damaged), Real(c.melt_energy));
    case PlasticityModel::DruckerPrager:
      return drucker_prager_params(Real(c.friction_angle), Real(c.cohesion), Real(c.dilatancy_angle), c.cone);
    case PlasticityModel::None: break;
  }
  return PlasticityParams{};
}

std::vector<MaterialParams> material_params_from_scene(const Scene& scene) {
  std::vector<MaterialParams> out;
  for (const auto& m : scene.materials) {
    MaterialParams p{};
    p.eos = eos_params_from_material(m);  // EOS and its add-on options (issue #3)
    p.av = {Real(m.viscosity.alpha), Real(m.viscosity.beta)};
    p.av_switch.enabled = m.viscosity.switch_on;
    p.av_switch.alpha_min = Real(m.viscosity.alpha_min);
    p.av_switch.decay = Real(m.viscosity.decay);
    p.alpha_u = m.conductivity.enabled ? Real(m.conductivity.alpha_u) : Real(0);
    p.shear_modulus = Real(m.shear_modulus);
    const bool as = m.artificial_stress.enabled && m.shear_modulus > 0;
    p.as_epsilon = as ? Real(m.artificial_stress.epsilon) : Real(0);
    p.as_exponent = as ? Real(m.artificial_stress.n) : Real(0);
    const bool clumping = m.artificial_stress.form == ArtificialStressForm::Clumping;
    p.as_clump_onset = clumping ? Real(m.artificial_stress.clump_onset) : Real(0);
    p.as_clump_full = clumping ? Real(m.artificial_stress.clump_full) : Real(0);
    p.porosity = m.porosity;  // the scene holds the model's own parameters
    p.plasticity = plasticity_params_from_config(m.plasticity);
    p.damage = m.damage;  // the model's own parameters (the flaw draw stays with the scene)
    p.stress_diffusion = Real(m.stress_diffusion);
    // Jaky's (1944) K0 = 1 - sin phi for a granular material (Feng et al.
    // 2021); other solids get no geostatic correction of the deviator
    p.k0 = m.plasticity.model == PlasticityModel::DruckerPrager
               ? Real(1 - std::sin(m.plasticity.friction_angle * std::numbers::pi / 180))
               : Real(1);
    // dp: the lattice spacing of the first body of this material (the
    // artificial stress's W(dp); Gray, Monaghan & Swift 2001)
    p.dp = 0;
    const int id = static_cast<int>(out.size());
    for (const auto& b : scene.bodies)
      if (b.material_id == id && b.spacing > 0) {
        p.dp = Real(b.spacing);
        break;
      }
    out.push_back(p);
  }
  return out;
}

RunPhysics run_physics(const Scene& scene) {
  const SimulationConfig& sim = scene.simulation;
  RunPhysics r;
  r.on = features_of_scene(scene);
  r.materials = material_params_from_scene(scene);
  r.kernel = sim.kernel;
  r.hfact = Real(smoothing_factor(sim));
  r.courant = Real(sim.courant);
  r.force_factor = Real(sim.force_factor);
  r.h_tolerance = h_iteration_tolerance(sim.h_tolerance);
  r.xsph_epsilon = Real(sim.xsph);
  r.shifting = Real(sim.shifting);
  r.density_step_fraction = Real(sim.density_step_fraction);
  r.geometric_force = sim.pressure_force == PressureForce::Geometric;
  r.energy_step_tolerance = sim.energy_step_tolerance >= 0 ? sim.energy_step_tolerance : sim.courant * sim.courant;
  for (int k = 0; k < 3; ++k) r.body_force[k] = Real(sim.gravity[k]);
  r.gravity = scene.gravity;
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) {
    const BodyConfig& b = scene.bodies[k];
    if (!b.rigid_tool()) continue;
    RigidToolSpec t;
    t.body = int(k);
    t.driven = b.boundary == BoundaryKind::Driven;
    t.centre = b.rotation_center;
    t.velocity = b.velocity;
    t.axis = b.rotation_axis;
    t.angular_velocity = b.angular_velocity;
    t.applied_force = b.applied_force;
    t.applied_torque = b.applied_torque;
    t.free_axis = b.driven_axes;
    t.free_rotation = b.driven_rotation;
    t.mass = b.tool_mass;
    t.inertia = b.tool_inertia;
    r.tools.push_back(t);
  }
  return r;
}

}  // namespace rubble
