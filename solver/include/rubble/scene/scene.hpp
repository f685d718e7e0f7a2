#pragma once
// A scene as read from TOML, validated, with every default filled in.
// The parser (scene_parser.cpp) is the only place that knows TOML; the
// solver sees only this structure. Every key is documented in
// docs/scene.md with its unit and default.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/core/real.hpp"
#include "rubble/core/region.hpp"
#include "rubble/physics/damage.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/gravity.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/physics/plasticity.hpp"
#include "rubble/physics/porosity.hpp"

namespace rubble {

enum class DensityForm : int { Summation = 0, Continuity = 1 };
enum class Integrator : int { RK2Adaptive = 0, Leapfrog = 1 };
// How leapfrog advances a solid's deviatoric stress and density
// (simulation.stress_update; leapfrog.hpp): "predicted" kicks them like the
// velocity, "staggered" advances them a whole step with the strain rate of
// the half-step velocity before the forces (the central-difference scheme).
enum class StressUpdate : int { Predicted = 0, Staggered = 1 };

enum class DampingFrame : int { Global = 0, Body = 1 };
// The hydrodynamic pressure force (physics/hydro.hpp): standard p/rho^2
// terms, or the geometric (p_a + p_b)/(rho_a rho_b) with volume-weighted
// continuity (continuity density, fluids only).
enum class PressureForce : int { Standard = 0, Geometric = 1 };

struct SimulationConfig {
  int dimension = 0;                        // 1, 2 or 3 (required)
  double end_time = 0;                      // [s] (required, > 0)
  Integrator integrator = Integrator::RK2Adaptive;
  KernelType kernel = KernelType::CubicSpline;
  DensityForm density = DensityForm::Summation;
  double hfact = 0;                         // h = hfact * (m/rho)^(1/D); 0 = kernel default
  double courant = 0.3;                     // Courant factor C
  double force_factor = 0.25;               // dt <= force_factor * sqrt(h/|a|)
  // Summation density: relative tolerance of the smoothing-length Newton
  // iteration (|dh|/h); 0 = the precision's default (1e-10 double, 1e-5 float)
  double h_tolerance = 0;
  double rk2_tolerance = 1e-5;              // relative error per step (rk2_adaptive)
  double dt_initial = 0;                    // 0 = from the Courant limit
  double dt_min = 0;                        // a step below this stops the run; 0 = 1e-12 * end_time
  // The energy watchdog (issue #50 item 1, drivers/step_sequence.hpp): the
  // largest change of the booked total energy one step may make, as a
  // fraction of the run's energy scale; < 0 = the default courant^2, 0 = off.
  double energy_step_tolerance = -1;
  // Continuity density: the largest fraction of its density a particle may
  // change in one step (issue #50 item 3); 0 = no such limit.
  double density_step_fraction = 0.1;
  // Quasi-static runs (issue #54 item 5): the longitudinal wave speed every
  // Murnaghan solid is softened to (its K0 and G scaled by one factor, never
  // stiffened); 0 = off. docs/scene.md gives the criterion.
  double quasi_static_sound_speed = 0;  // [m/s]
  std::int64_t max_steps = 10000000;
  // Velocity damping for relaxing initial conditions: while t < damping_end,
  // every step multiplies v by exp(-dt / damping_time). 0 = off.
  double damping_time = 0;                  // [s]
  double damping_end = 0;                   // [s]
  // damping_frame: "global" damps every velocity; "body" damps each body's
  // velocities about its own mean velocity (its motion as a whole is kept).
  // With [collision] it is "body" and the colliding bodies are held in place
  // while damped, then launched onto their orbit at damping_end.
  DampingFrame damping_frame = DampingFrame::Global;
  PressureForce pressure_force = PressureForce::Standard;
  // Solids: kernel-gradient correction of the velocity gradient
  // (Randles & Libersky 1996); off by default.
  bool kernel_correction = false;
  // Solids with leapfrog: how S and rho are advanced (StressUpdate above).
  StressUpdate stress_update = StressUpdate::Predicted;
  // XSPH (Monaghan 1989): particles drift with v + eps * (smoothed v_b - v_a);
  // eps in [0, 1], 0 = off (physics/xsph.hpp).
  double xsph = 0;
  // Particle shifting after each accepted step (physics/particle_shifting.hpp):
  // the coefficient A of the diffusion A h |v| dt; 0 = off.
  double shifting = 0;
  // A uniform external acceleration g [m/s^2] (D entries; all zero = off),
  // e.g. [0, -9.81] in 2-D; its potential energy -m g.x is in conserved.csv.
  std::array<double, 3> gravity{};
  bool allow_overlap = false;               // bodies may overlap (else an error, docs/scene.md)
};

struct ArtificialViscosity {
  double alpha = 1.0;  // Monaghan (1992) linear term (alpha_max with the switch)
  double beta = 2.0;   // quadratic term (at alpha_max with the switch)
  bool switch_on = false;  // switch = "morris_monaghan": per-particle alpha (physics/viscosity_switch.hpp)
  double alpha_min = 0.1;  // the switch's floor
  double decay = 0.1;      // the switch's decay constant l: tau = h/(l c)
};

struct ArtificialConductivity {
  bool enabled = false;
  double alpha_u = 1.0;  // Price (2008)
};


// Artificial stress against the tensile instability (Monaghan 2000; Gray,
// Monaghan & Swift 2001); solids only, off by default.
// The clumping form (default since issue #17 item 3) scales R by a weight
// that is 0 on a regular lattice and 1 where a neighbour has come closer
// than clump_full times the local spacing (artificial_stress.hpp).
enum class ArtificialStressForm { Monaghan, Clumping };
// The scene's name of a form (for records and messages).
inline const char* artificial_stress_form_name(ArtificialStressForm f) {
  return f == ArtificialStressForm::Monaghan ? "monaghan" : "clumping";
}

struct ArtificialStressConfig {
  bool enabled = false;
  double epsilon = 0.3;  // R' = -epsilon sigma'/rho^2 for tensile sigma'
  double n = 4;          // exponent of f_ab = W(r)/W(dp)
  ArtificialStressForm form = ArtificialStressForm::Clumping;
  double clump_onset = 1.0;  // nearest neighbour / local spacing where it starts
  double clump_full = 0.95;  // ... and where it acts in full
};


// Plasticity of a solid (shear_modulus > 0): von Mises or Drucker-Prager
// (Bui, Fukagawa, Sako & Ohno 2008); plasticity = { model = ..., ... }.
struct PlasticityConfig {
  PlasticityModel model = PlasticityModel::None;
  double yield_stress = 0;     // [Pa] von Mises Y (> 0)
  double friction_angle = 0;   // [deg] Drucker-Prager phi, in [0, 90)
  double cohesion = 0;         // [Pa] c >= 0
  double dilatancy_angle = 0;  // [deg] psi, 0 <= psi <= phi
  DpConeFit cone = DpConeFit::PlaneStrain;
  // Collins et al. 2004 rock strength (model "collins"; physics/plasticity.hpp);
  // cohesion above is its Y_0
  double friction_intact = 0;   // mu_i >= 0
  double strength_limit = 0;    // [Pa] Y_M > Y_0
  double cohesion_damaged = 0;  // [Pa] Y_d0 in [0, Y_0]
  double friction_damaged = 0;  // mu_d >= 0
  double melt_energy = 0;       // [J/kg] u_melt > 0, or 0: no thermal softening
};

// Tensile damage of a solid (Grady & Kipp 1980; Benz & Asphaug 1994, 1995):
// damage = { model = "grady_kipp", weibull_k, weibull_m, ... }. The model's
// own parameters (DamageParams, physics/damage.hpp: weibull_k > 0 [m^-3],
// weibull_m > 0, crack_speed in (0, 1], deviatoric, capped), and the flaw
// draw of the initial conditions (scene/flaws.hpp).
struct DamageConfig : DamageParams {
  std::int64_t seed = 1;    // of the flaw draw (>= 0); each body mixes in its index
  std::int32_t min_flaws_per_particle = 1;  // the draw goes on until every particle has this many
};

struct MaterialConfig {
  std::string name;     // the key under [materials]
  std::string library;       // library material name or file as written ("" = inline)
  std::string library_file;  // the library file it was loaded from
  std::string source;        // library files: where the parameters come from
  std::string units;         // library files: "SI" or "dimensionless"
  EosKind eos = EosKind::IdealGas;
  double gamma = 0;     // ideal gas adiabatic index (> 1)
  // The EOS's own parameters (physics/eos/), as the scene reader validated
  // them: murnaghan = { rho0, K0, n }, tillotson = { rho0, A, B, E0, E_iv,
  // E_cv, a, b, alpha, beta }, and the add-on options (rho_limit, p_min,
  // cs_min, cs_floor), each off unless set; docs/scene.md.
  MurnaghanParams murnaghan;
  TillotsonParams tillotson;
  EosLimits eos_options;
  ArtificialViscosity viscosity;
  ArtificialConductivity conductivity;
  double shear_modulus = 0;  // [Pa] mu; > 0 makes the material an elastic solid
  ArtificialStressConfig artificial_stress;
  double stress_diffusion = 0;  // zeta of the deviatoric stress diffusion (solids; 0 = off)
  // simulation.quasi_static_sound_speed: the factor its K0 and G were
  // scaled by (1: as given)
  double stiffness_scale = 1;
  // p-alpha porosity (Jutzi, Benz & Michel 2008; Jutzi et al. 2009), the
  // model's own parameters (physics/porosity.hpp); Murnaghan and Tillotson
  // matrices only; porosity = { model = "p_alpha", ... }, docs/scene.md.
  PorosityParams porosity;      // off (enabled = false) unless the material has a porosity table
  PlasticityConfig plasticity;  // none unless the material has a plasticity table
  DamageConfig damage;          // off unless the material has a damage table
};

// Box: min..max. Sphere (a disk in 2-D, a segment in 1-D): center, radius.
// Ring (2-D annulus, 3-D spherical shell): center, inner_radius..radius.
// Layered: a differentiated 3-D body in hydrostatic equilibrium, particles
// on nested shells (scene/layered_body.hpp).
// Polygon (2-D): the closed polygon through `vertices`. Cylinder (3-D):
// center (the axis' midpoint), radius, length, axis (core/region.hpp).
enum class BodyShape : int { Box = 0, Polytrope = 1, Sphere = 2, Ring = 3, Layered = 4, Polygon = 5, Cylinder = 6 };
enum class Lattice : int { Cubic = 0, HexagonalClosePacked = 1 };
// Boundary particles (walls, clamps, tools): not integrated, but neighbours
// of the others with their own state. Fixed: at rest; moving: with the
// body's velocity (and angular velocity) for ever; driven: a rigid body
// moved by the forces of the material on it and an applied load
// (physics/rigid_body.hpp).
enum class BoundaryKind : int { None = 0, Fixed = 1, Moving = 2, Driven = 3 };
// What a boundary body's particles do with their state (BodyConfig::boundary_state).
enum class BoundaryState : int { Frozen = 0, Evolving = 1, Extrapolated = 2 };
inline const char* boundary_state_name(BoundaryState s) {
  return s == BoundaryState::Evolving ? "evolving" : s == BoundaryState::Extrapolated ? "extrapolated" : "frozen";
}

// A wall's tangential behaviour (BodyConfig::wall_slip).
enum class WallSlip : int { NoSlip = 0, FreeSlip = 1, Coulomb = 2 };
inline const char* wall_slip_name(WallSlip s) {
  return s == WallSlip::FreeSlip ? "free_slip" : s == WallSlip::Coulomb ? "coulomb" : "no_slip";
}

// One layer of a shape = "layered" body: its material and either its outer
// radius or its mass fraction (the same for every layer of the body).
struct LayerConfig {
  std::string material;
  int material_id = 0;
  double radius = 0;         // [m] outer radius (> 0), or 0 when mass fractions are given
  double mass_fraction = 0;  // (> 0), or 0 when radii are given
};

struct BodyConfig {
  BodyShape shape = BodyShape::Box;
  std::string material;      // name of a [materials] entry
  int material_id = 0;       // its index (filled by the parser)
  std::array<double, 3> min{}, max{};  // box corners [m] (first D used)
  double spacing = 0;        // lattice spacing [m]
  Lattice lattice = Lattice::Cubic;
  double density = 0;        // [kg/m^3] (> 0)
  double pressure = -1;      // [Pa]  one of pressure / internal_energy
  double internal_energy = -1;  // [J/kg]
  std::array<double, 3> velocity{};  // [m/s]
  // velocity_gradient: the initial velocity is velocity + L x (x the
  // particle's position); rows of L, first D used. Free bodies only.
  std::array<std::array<double, 3>, 3> velocity_gradient{};  // [1/s]
  BoundaryKind boundary = BoundaryKind::None;
  // boundary_state: "frozen" (default): the boundary particles keep their
  // initial state. "evolving": their density, internal energy and stress
  // evolve like any particle's, only their motion is prescribed (dynamic
  // boundary particles, Crespo et al. 2007; a clamp that carries stress).
  // "extrapolated": p, S, rho and c_s are set in every evaluation from the
  // free particles around them (Adami, Hu & Adams 2012;
  // physics/wall_extrapolation.hpp); walls and floors that hold granular
  // material or a fluid.
  BoundaryState boundary_state = BoundaryState::Frozen;
  // Walls (boundary bodies), wall_slip: "no_slip" (default): the wall's
  // particles are seen like any neighbour. "free_slip": frictionless: a
  // neighbour sees their velocity only along wall_normal (unit, pointing
  // into the material) and receives only the normal part of their force.
  // "coulomb": the same, plus Coulomb friction wall_friction x the normal
  // push (physics/wall_friction.hpp).
  WallSlip wall_slip = WallSlip::NoSlip;
  std::array<double, 3> wall_normal{};
  double wall_friction = 0;  // Coulomb friction coefficient mu (>= 0)
  bool sliding_wall() const { return wall_slip != WallSlip::NoSlip; }
  // Rigid tools (physics/rigid_body.hpp): a moving body that turns
  // (angular_velocity != 0) or a driven body. It turns about rotation_axis
  // (3-D; z in 2-D) through rotation_center (default: the shape's centre).
  // Driven: applied_force and applied_torque act besides the material's
  // reaction; driven_axes and driven_rotation say which components respond
  // (the others keep their initial value); tool_mass and tool_inertia
  // replace the mass and moment of inertia of its particles when > 0.
  double angular_velocity = 0;                  // [rad/s] about rotation_axis
  std::array<double, 3> rotation_axis{0, 0, 1};  // unit
  std::array<double, 3> rotation_center{};       // [m]
  std::array<double, 3> applied_force{};         // [N] (2-D: N/m)
  double applied_torque = 0;                     // [N m] about rotation_axis (2-D: N m/m)
  std::array<bool, 3> driven_axes{true, true, true};
  bool driven_rotation = true;
  double tool_mass = 0;     // [kg] (2-D: kg/m); 0: the particles' mass
  double tool_inertia = 0;  // [kg m^2] (2-D: kg m^2/m); 0: the particles'
  bool rigid_tool() const {
    return boundary == BoundaryKind::Driven || (boundary == BoundaryKind::Moving && angular_velocity != 0);
  }
  // shape = "polytrope" (3-D only): a self-gravitating polytrope in
  // hydrostatic equilibrium, p = K rho^(1+1/n) with rho from the Lane-Emden
  // solution; K follows from radius, mass, n and gravity.G. The parser
  // fills min/max with centre -/+ radius; spacing, density, pressure and
  // internal_energy are unused.
  std::array<double, 3> center{};  // [m] (polytrope, sphere, ring)
  double radius = 0;               // [m] outer radius R (> 0) (polytrope, sphere, ring)
  double inner_radius = 0;         // [m] (ring)
  double mass = 0;                 // [kg] total mass M (> 0)
  double polytropic_index = 1;     // n, 0 < n < 5
  std::int64_t particles = 0;      // approximate number of particles (polytrope, layered)
  // shape = "layered" (3-D only): the layers from the centre out. The parser
  // computes the structure (scene/layered_body.hpp) and fills radius, mass
  // (the body's, whichever way the layers were given), min/max (centre -/+
  // radius) and material/material_id (the outermost layer's).
  std::vector<LayerConfig> layers;
  std::uint64_t seed = 1;          // the shells' random rotations (layered)
  // Lattice bodies (box, sphere, ring, polygon, cylinder): the shape as a
  // region (core/region.hpp), and the regions added to it and cut out of
  // it (scene keys `add`, `subtract`): one lattice fills
  // (region + add) - subtract.
  Region region;
  std::vector<Region> add, subtract;
};

// [[regions]]: a named measuring region (issue #54 item 3): the mass of
// each material inside it is written to regions.csv. `follow`: the index
// of a rigid-tool body whose motion it follows (its shape is given at the
// tool's position at t = 0), or -1.
struct MeasureRegionConfig {
  std::string name;
  Region region;
  int follow = -1;
};

struct DomainConfig {
  // Periodic axes need both bounds; open axes ignore them.
  std::array<double, 3> min{}, max{};
  std::array<bool, 3> periodic{};
};

struct OutputConfig {
  std::string name = "snapshot";  // snapshot files NAME.NNNN.h5
  double interval = 0;            // [s]; 0 = only initial and final
  bool snapshots = true;
  // [s] time between rows of conserved.csv (plus the last step); 0 = every
  // step; default end_time / 1e4 (set by the parser).
  double conserved_interval = 0;
};

// [gravity]: self-gravity (3-D, open boundaries only); docs/scene.md.
enum class GravityMode : int { Off = 0, Direct = 1, BarnesHut = 2 };
enum class GravitySoftening : int { SmoothingLength = 0, Fixed = 1 };

struct GravityConfig {
  GravityMode mode = GravityMode::Off;
  double theta = 0.5;                                  // Barnes-Hut opening angle, [0, 1]
  MultipoleOrder order = MultipoleOrder::Quadrupole;   // Barnes-Hut expansion order
  double G = kGravitationalConstantSI;                 // [m^3 kg^-1 s^-2]
  GravitySoftening softening = GravitySoftening::SmoothingLength;  // eps = h, or a fixed length
  double softening_length = 0;                         // [m] (softening = a number)
  int leaf_size = 8;                                   // particles per tree leaf (tuning)
  int group_size = 32;                                 // particles sharing one tree walk (tuning)
};

// A library material file as the scene read it: `spec` is the value of
// `library = ...`, `path` the file it resolved to, `text` its content.
// Snapshots carry these, so a resumed run uses the values the run started
// with, whatever the library on disk holds by then.
struct LibraryText {
  std::string spec;
  std::string path;
  std::string text;
};

// [[energy_deposits]]: energy added to the particles' internal energy at
// t = 0, e.g. the point blast of the Sedov-Taylor rung or an explosion
// source (docs/scene.md). profile "kernel": weights W(r, radius/2) of the
// cubic spline, whose support ends at `radius` (the form of Phantom's sedov
// set-up); "uniform": equal specific energy within `radius`. Either way the
// weights are normalised by mass so that exactly `energy` is added.
enum class DepositProfile : int { Kernel = 0, Uniform = 1 };

struct EnergyDepositConfig {
  double energy = 0;                // [J] (> 0)
  std::array<double, 3> center{};   // [m] (first D used; minimum image on periodic axes)
  double radius = 0;                // [m] (> 0)
  DepositProfile profile = DepositProfile::Kernel;
};

// [collision] (issue #52 item 3; scene/collision.hpp): two groups of bodies
// placed on the two-body orbit that brings them into contact at the given
// speed and angle. Exactly one of the three speeds is set (>= 0).
struct CollisionConfig {
  bool enabled = false;
  std::vector<int> target, impactor;  // scene body indices
  double impact_speed = -1;           // relative speed at contact [m/s]
  double impact_speed_vesc = -1;      // ... in units of the mutual escape speed
  double v_infinity = -1;             // relative speed at infinity [m/s]
  double impact_angle = 0;            // [degrees], 0 head-on
  double separation = 0;              // the centres' distance at the start, in touching distances (>= 1)
  std::array<double, 3> spin_target{}, spin_impactor{};  // rigid rotation about each body's centre of mass [rad/s]
};

struct Scene {
  std::string file;     // where it came from (for messages)
  std::string text;     // full scene text after --set overrides (stored in snapshots)
  std::string source_text;               // the scene file as read, before overrides
  std::vector<std::string> overrides;    // the --set overrides, in order
  std::vector<LibraryText> libraries;    // the library files the materials came from
  SimulationConfig simulation;
  std::vector<MaterialConfig> materials;
  std::vector<BodyConfig> bodies;
  std::vector<MeasureRegionConfig> regions;  // [[regions]] (none: empty)
  DomainConfig domain;
  OutputConfig output;
  GravityConfig gravity;
  std::vector<EnergyDepositConfig> energy_deposits;
  CollisionConfig collision;
};

}  // namespace rubble
