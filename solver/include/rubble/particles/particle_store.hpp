#pragma once
// Particles as a structure of arrays: one std::vector per field.
//
// Which fields exist, their units, whether they are evolved in time or
// derived, and whether snapshots carry them is described once, in the field
// table below (kFieldTable). Fields a scene does not need stay empty
// (size 0): `allocate()` sizes only the fields the run's feature set asks for,
// and `allocated_fields()` lists them so tests can check that nothing else
// was allocated.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/particles/features.hpp"
#include "rubble/particles/store_view.hpp"

namespace rubble {


template <int D>
struct ParticleStore {
  std::size_t n = 0;

  // constants of each particle
  std::vector<Real> m;                    // mass [kg]
  std::vector<std::int32_t> material_id;  // index into the scene's materials
  std::vector<std::int32_t> id;           // the particle's index when generated: follows it through every sort

  // evolved state
  std::vector<Vec<D>> x;  // position [m]
  std::vector<Vec<D>> v;  // velocity [m/s]
  std::vector<Real> u;    // specific internal energy [J/kg]
  std::vector<Real> rho;  // density [kg/m^3] (evolved or summed)
  std::vector<Real> h;    // smoothing length = kernel support radius [m]

  // derived each evaluation
  std::vector<Real> p;      // pressure [Pa]
  std::vector<Real> cs;     // sound speed [m/s]
  std::vector<Real> omega;  // grad-h correction factor Omega (summation density)

  // time derivatives
  std::vector<Vec<D>> dvdt;   // acceleration [m/s^2]
  std::vector<Real> dudt;     // [J/kg/s]
  std::vector<Real> drhodt;   // [kg/m^3/s] (continuity density only)
  std::vector<Real> mu_max;   // largest viscous approach speed |mu_ab| seen [m/s]

  // self-gravity (allocated only when gravity is on)
  std::vector<Vec<D>> a_grav;  // gravitational acceleration [m/s^2] (included in dvdt)
  std::vector<Real> phi;       // gravitational potential [J/kg]; energy = 1/2 Σ m phi

  // solids (allocated only when a material has a shear modulus)
  std::vector<Mat<D>> S;     // deviatoric stress [Pa] (evolved; symmetric, in-plane block in 2-D)
  std::vector<Mat<D>> dSdt;  // [Pa/s]

  // boundary particles (allocated only when a body is a boundary): one of
  // the flags below (kFreeParticle ... kBoundaryExtrapolated)
  std::vector<std::int32_t> boundary;
  // ... and on them the force the other particles exert on each, m (dv/dt - g)
  // of its rates before they are held (boundary_forces.csv sums it by body)
  std::vector<Vec<D>> wall_force;  // [N] (2-D: N/m)

  // rigid tools (allocated only when a boundary body turns or is driven;
  // physics/rigid_body.hpp): the particle's tool (-1: none) and its offset
  // from the tool's rotation centre at t = 0, from which it is placed
  std::vector<std::int32_t> tool;  // [1]
  std::vector<Vec<D>> tool_offset;  // [m]

  // XSPH (allocated only when simulation.xsph > 0): dx/dt = v + xsph_v
  std::vector<Vec<D>> xsph_v;  // [m/s]

  // kernel-gradient correction (allocated only for solids with
  // simulation.kernel_correction): K = C^T of each particle, set by the
  // velocity-gradient pass and read by the pair pass and the time-step
  // limit (drivers/particle_rates.hpp, physics/solid.hpp); a store field so
  // that a sort carries it with its particle
  std::vector<Mat<D>> corr_K;  // [1]

  // p-alpha porosity (allocated only when a material is porous): the
  // distention alpha = rho_matrix / rho >= 1 (1 for particles of non-porous
  // materials) and its rate (physics/porosity.hpp)
  std::vector<Real> alpha;     // [1] (evolved)
  std::vector<Real> dalphadt;  // [1/s]

  // plasticity (allocated only when a solid material has a yield criterion):
  // the accumulated equivalent plastic strain (physics/plasticity.hpp),
  // updated by the return mapping at the end of each step
  std::vector<Real> eps_p;  // [1]
  // Drucker-Prager materials (allocated only when one is in the scene): the
  // accumulated inelastic volumetric strain, the opening of tension cracking
  // plus dilatant plastic flow (psi > 0); the EOS sees the elastic density
  // rho exp(eps_v) (physics.md, "Plasticity")
  std::vector<Real> eps_v;  // [1]

  // tensile damage (allocated only when a solid material has a damage
  // table; physics/damage.hpp): delta = D^(1/d), its rate, the particle's
  // Weibull flaws (count, smallest and largest activation strain; 0 flaws
  // for particles of other materials and walls) and the most flaws it has
  // had active (the cap D <= n_active/n_flaws)
  std::vector<Real> damage_root;          // [1] (evolved)
  std::vector<Real> ddamage_root_dt;      // [1/s]
  std::vector<std::int32_t> flaw_count;   // [1]
  std::vector<Real> flaw_eps_min;         // [1]
  std::vector<Real> flaw_eps_max;         // [1]
  std::vector<Real> flaws_active;         // [1] (updated at the end of each step; never falls)

  // the viscosity switch (allocated only when a material has one;
  // physics/viscosity_switch.hpp): each particle's alpha of the artificial
  // viscosity and its rate (particles of other materials keep their
  // material's constant alpha here, unused)
  std::vector<Real> av_alpha;      // [1] (evolved)
  std::vector<Real> dav_alpha_dt;  // [1/s]

  // sliding walls (allocated only when a boundary body is free-slip or
  // Coulomb): the wall's unit normal on its particles, zero on every other
  // particle; and, only when a wall is Coulomb, its friction coefficient
  // (0 on every other particle)
  std::vector<Vec<D>> wall_normal;  // [1]
  std::vector<Real> wall_friction;  // [1]
  // ... and, with a Coulomb wall, on free particles: where each would sit
  // with its friction spring relaxed (physics/wall_friction.hpp; x itself
  // off the walls), and the walls' grip mu N along their push's direction
  // in the last evaluation (0 off the walls)
  std::vector<Vec<D>> wall_anchor;  // [m]
  std::vector<Vec<D>> wall_grip;    // [m/s^2]

  void allocate(std::size_t count, const Features& needs);
  // Apply a permutation: new particle i is old particle perm[i].
  void permute(const std::vector<std::uint32_t>& perm);
  std::vector<std::string> allocated_fields() const;
  // The allocated fields as plain pointers (rubble/particles/store_view.hpp).
  StoreView<D> view();
};

// ---- the field table -----------------------------------------------------

enum class FieldRole { Constant, Evolved, Derived, Rate };

template <int D>
using FieldMember = std::variant<std::vector<Real> ParticleStore<D>::*,
                                 std::vector<Vec<D>> ParticleStore<D>::*,
                                 std::vector<std::int32_t> ParticleStore<D>::*,
                                 std::vector<Mat<D>> ParticleStore<D>::*>;

template <int D>
struct FieldInfo {
  std::string_view name;  // dataset name in snapshots
  FieldMember<D> member;
  std::string_view unit;
  FieldRole role;
  bool snapshot;  // written to snapshots when allocated
};

// dx/dt of particle i: its velocity, plus the XSPH correction when the run
// uses XSPH (physics/xsph.hpp). Both integrators drift with this.
template <int D>
inline Vec<D> position_rate(const ParticleStore<D>& ps, std::size_t i) {
  return ps.xsph_v.empty() ? ps.v[i] : ps.v[i] + ps.xsph_v[i];
}

template <int D>
inline const std::vector<FieldInfo<D>>& field_table() {
  using PS = ParticleStore<D>;
  static const std::vector<FieldInfo<D>> table = {
      {"x", &PS::x, "m", FieldRole::Evolved, true},
      {"v", &PS::v, "m/s", FieldRole::Evolved, true},
      {"m", &PS::m, "kg", FieldRole::Constant, true},
      {"rho", &PS::rho, "kg/m^3", FieldRole::Evolved, true},
      {"p", &PS::p, "Pa", FieldRole::Derived, true},
      {"u", &PS::u, "J/kg", FieldRole::Evolved, true},
      {"h", &PS::h, "m", FieldRole::Evolved, true},
      {"cs", &PS::cs, "m/s", FieldRole::Derived, true},
      {"material_id", &PS::material_id, "1", FieldRole::Constant, true},
      {"id", &PS::id, "1", FieldRole::Constant, true},
      {"omega", &PS::omega, "1", FieldRole::Derived, false},
      {"dvdt", &PS::dvdt, "m/s^2", FieldRole::Rate, false},
      {"dudt", &PS::dudt, "J/kg/s", FieldRole::Rate, false},
      {"drhodt", &PS::drhodt, "kg/m^3/s", FieldRole::Rate, false},
      {"mu_max", &PS::mu_max, "m/s", FieldRole::Derived, false},
      {"a_grav", &PS::a_grav, "m/s^2", FieldRole::Derived, true},
      {"phi", &PS::phi, "J/kg", FieldRole::Derived, false},
      {"S", &PS::S, "Pa", FieldRole::Evolved, true},
      {"dSdt", &PS::dSdt, "Pa/s", FieldRole::Rate, false},
      {"boundary", &PS::boundary, "1", FieldRole::Constant, true},
      {"wall_force", &PS::wall_force, "N", FieldRole::Derived, true},
      {"tool", &PS::tool, "1", FieldRole::Constant, true},
      {"tool_offset", &PS::tool_offset, "m", FieldRole::Constant, true},
      {"xsph_v", &PS::xsph_v, "m/s", FieldRole::Derived, false},
      {"corr_K", &PS::corr_K, "1", FieldRole::Derived, false},
      {"alpha", &PS::alpha, "1", FieldRole::Evolved, true},
      {"dalphadt", &PS::dalphadt, "1/s", FieldRole::Rate, false},
      {"eps_p", &PS::eps_p, "1", FieldRole::Evolved, true},
      {"eps_v", &PS::eps_v, "1", FieldRole::Evolved, true},
      {"wall_normal", &PS::wall_normal, "1", FieldRole::Constant, false},
      {"wall_friction", &PS::wall_friction, "1", FieldRole::Constant, false},
      {"wall_anchor", &PS::wall_anchor, "m", FieldRole::Evolved, true},
      {"wall_grip", &PS::wall_grip, "m/s^2", FieldRole::Derived, false},
      {"damage_root", &PS::damage_root, "1", FieldRole::Evolved, true},
      {"ddamage_root_dt", &PS::ddamage_root_dt, "1/s", FieldRole::Rate, false},
      {"flaw_count", &PS::flaw_count, "1", FieldRole::Constant, true},
      {"flaw_eps_min", &PS::flaw_eps_min, "1", FieldRole::Constant, true},
      {"flaw_eps_max", &PS::flaw_eps_max, "1", FieldRole::Constant, true},
      {"flaws_active", &PS::flaws_active, "1", FieldRole::Evolved, true},
      {"av_alpha", &PS::av_alpha, "1", FieldRole::Evolved, true},
      {"dav_alpha_dt", &PS::dav_alpha_dt, "1/s", FieldRole::Rate, false},
  };
  return table;
}

// ---- implementation -------------------------------------------------------

template <int D>
void ParticleStore<D>::allocate(std::size_t count, const Features& needs) {
  n = count;
  m.assign(n, 0);
  material_id.assign(n, 0);
  id.assign(n, 0);
  x.assign(n, Vec<D>::zero());
  v.assign(n, Vec<D>::zero());
  u.assign(n, 0);
  rho.assign(n, 0);
  h.assign(n, 0);
  p.assign(n, 0);
  cs.assign(n, 0);
  dvdt.assign(n, Vec<D>::zero());
  dudt.assign(n, 0);
  mu_max.assign(n, 0);
  if (needs.summation_density) omega.assign(n, 1);
  if (needs.continuity_density) {
    drhodt.assign(n, 0);
  }
  if (needs.gravity) {
    a_grav.assign(n, Vec<D>::zero());
    phi.assign(n, 0);
  }
  if (needs.solid) {
    S.assign(n, Mat<D>::zero());
    dSdt.assign(n, Mat<D>::zero());
  }
  if (needs.boundary) {
    boundary.assign(n, 0);
    wall_force.assign(n, Vec<D>::zero());
  }
  if (needs.rigid_tools) {
    tool.assign(n, -1);
    tool_offset.assign(n, Vec<D>::zero());
  }
  if (needs.xsph) xsph_v.assign(n, Vec<D>::zero());
  if (needs.kernel_correction) corr_K.assign(n, Mat<D>::identity());
  if (needs.porosity) {
    alpha.assign(n, 1);
    dalphadt.assign(n, 0);
  }
  if (needs.plasticity) eps_p.assign(n, 0);
  if (needs.inelastic_volume) eps_v.assign(n, 0);
  if (needs.free_slip) wall_normal.assign(n, Vec<D>::zero());
  if (needs.wall_friction) {
    wall_friction.assign(n, 0);
    wall_anchor.assign(n, Vec<D>::zero());
    wall_grip.assign(n, Vec<D>::zero());
  }
  if (needs.damage) {
    damage_root.assign(n, 0);
    ddamage_root_dt.assign(n, 0);
    flaw_count.assign(n, 0);
    flaw_eps_min.assign(n, 0);
    flaw_eps_max.assign(n, 0);
    flaws_active.assign(n, 0);
  }
  if (needs.viscosity_switch) {
    av_alpha.assign(n, 0);
    dav_alpha_dt.assign(n, 0);
  }
}

template <int D>
void ParticleStore<D>::permute(const std::vector<std::uint32_t>& perm) {
  for (const auto& f : field_table<D>()) {
    std::visit(
        [&](auto member) {
          auto& arr = this->*member;
          if (arr.empty()) return;
          auto old = arr;
          for (std::size_t i = 0; i < n; ++i) arr[i] = old[perm[i]];
        },
        f.member);
  }
}

template <int D>
std::vector<std::string> ParticleStore<D>::allocated_fields() const {
  std::vector<std::string> names;
  for (const auto& f : field_table<D>())
    std::visit([&](auto member) { if (!(this->*member).empty()) names.emplace_back(f.name); }, f.member);
  return names;
}

}  // namespace rubble

namespace rubble {

template <int D>
StoreView<D> ParticleStore<D>::view() {
  StoreView<D> s;
  s.n = n;
  for (const auto& f : field_table<D>())
    std::visit([&](auto member) {
      auto& arr = this->*member;
      if (!arr.empty()) s.bind(f.name, arr.data());
    }, f.member);
  return s;
}

}  // namespace rubble
