#include "rubble/scene/initial_conditions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <variant>
#include <numbers>
#include <string>

#include "rubble/core/error.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/physics/rigid_body.hpp"
#include "rubble/neighbors/cell_list.hpp"
#include "rubble/neighbors/spatial_order.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/smoothing_length.hpp"
#include "rubble/reference/lane_emden.hpp"
#include "rubble/scene/flaws.hpp"
#include "rubble/scene/layered_body.hpp"

namespace rubble {

template <int D>
double lattice_cell_volume(Lattice lattice, double dx) {
  if (lattice == Lattice::HexagonalClosePacked) {
    if constexpr (D == 2) return std::sqrt(3.0) / 2.0 * dx * dx;
    if constexpr (D == 3) return dx * dx * dx / std::sqrt(2.0);
  }
  double v = 1;
  for (int k = 0; k < D; ++k) v *= dx;
  return v;
}

// Whether x belongs to the body's own shape: a box's min..max, a sphere's
// or ring's radii, a polygon's or cylinder's region (core/region.hpp); the
// unit lattice of a polytrope keeps its whole box.
template <int D>
static bool inside_shape(const BodyConfig& b, const Vec<D>& x) {
  double p[3] = {0, 0, 0};
  for (int k = 0; k < D; ++k) p[k] = double(x[k]);
  switch (b.shape) {
    case BodyShape::Sphere:
    case BodyShape::Ring: {
      double r2 = 0;
      for (int k = 0; k < D; ++k) r2 += (p[k] - b.center[k]) * (p[k] - b.center[k]);
      const double r = std::sqrt(r2);
      return b.shape == BodyShape::Ring ? r >= b.inner_radius && r < b.radius : r < b.radius;
    }
    case BodyShape::Polygon:
    case BodyShape::Cylinder: return b.region.contains<D>(p);
    case BodyShape::Box:
    case BodyShape::Polytrope:
    case BodyShape::Layered: break;
  }
  for (int k = 0; k < D; ++k)
    if (!(p[k] >= b.min[k] && p[k] < b.max[k])) return false;
  return true;
}

// Whether x belongs to the body: its shape or a region it adds, and none it
// subtracts (scene keys `add`, `subtract`).
template <int D>
static bool inside_body(const BodyConfig& b, const Vec<D>& x) {
  double p[3] = {0, 0, 0};
  for (int k = 0; k < D; ++k) p[k] = double(x[k]);
  bool in = inside_shape<D>(b, x);
  for (const Region& r : b.add) in = in || r.contains<D>(p);
  if (!in) return false;
  for (const Region& r : b.subtract)
    if (r.contains<D>(p)) return false;
  return true;
}

// Lattice points of the body (inside_body). A sphere or ring uses the box
// centre +- radius, with the lattice centred on the body's centre so the
// shape is symmetric; regions it adds extend the lattice by whole cells,
// so one lattice fills the composed shape. Cubic: cell centres.
// Hexagonal / HCP: rows offset by dx/2, layers (3-D) in the A-B stacking
// of close packing.
template <int D>
std::vector<Vec<D>> lattice_points(BodyConfig b) {  // declared in initial_conditions.hpp
  if (b.shape == BodyShape::Sphere || b.shape == BodyShape::Ring) {
    for (int k = 0; k < D; ++k) {
      // a whole number of cells on each side of the centre, so that the
      // lattice is symmetric about it
      const double half = (std::floor(b.radius / b.spacing) + 1) * b.spacing;
      b.min[k] = b.center[k] - half;
      b.max[k] = b.center[k] + half;
    }
  }
  std::vector<Vec<D>> pts;
  const double dx = b.spacing;
  const bool hex = b.lattice == Lattice::HexagonalClosePacked && D >= 2;
  // spacing between rows (y) and layers (z)
  const double dy = hex ? dx * std::sqrt(3.0) / 2.0 : dx;
  const double dz = hex ? dx * std::sqrt(2.0 / 3.0) : dx;
  const double step[3] = {dx, dy, dz};
  // the lattice's extent: the shape's box, grown by whole steps over the
  // regions added (the same lattice continues into them)
  double lo[3] = {b.min[0], b.min[1], b.min[2]}, hi[3] = {b.max[0], b.max[1], b.max[2]};
  for (const Region& r : b.add)
    for (int k = 0; k < D; ++k) {
      if (r.min[k] < lo[k]) lo[k] -= std::ceil((lo[k] - r.min[k]) / step[k] - 1e-9) * step[k];
      if (r.max[k] > hi[k]) hi[k] += std::ceil((r.max[k] - hi[k]) / step[k] - 1e-9) * step[k];
    }
  long count[3] = {1, 1, 1};
  for (int k = 0; k < D; ++k) count[k] = std::lround(std::floor((hi[k] - lo[k]) / step[k] + 1e-9));
  for (long k2 = 0; k2 < count[2]; ++k2)
    for (long k1 = 0; k1 < count[1]; ++k1)
      for (long k0 = 0; k0 < count[0]; ++k0) {
        const long idx[3] = {k0, k1, k2};
        Vec<D> x;
        for (int k = 0; k < D; ++k) x[k] = Real(lo[k] + (idx[k] + 0.5) * step[k]);
        if (hex) {
          // odd rows shift by dx/2; odd layers shift by (dx/2, dy/3). A point
          // shifted past the box wraps to its far side, so a box whose sides
          // are whole lattice periods tiles periodically.
          x[0] += Real(0.5 * dx * ((k1 + k2) % 2));
          if constexpr (D == 3) x[1] += Real(dy / 3.0 * (k2 % 2));
          for (int k = 0; k < 2; ++k)
            if (x[k] >= hi[k]) x[k] -= Real(hi[k] - lo[k]);
        }
        if (inside_body<D>(b, x)) pts.push_back(x);
      }
  return pts;
}

namespace {

// shape = "polytrope" (3-D): a lattice filling the unit ball with about
// b.particles points, stretched radially so that the point at radius r_u
// lands at the radius enclosing mass fraction r_u^3 of the polytrope: equal
// masses then follow the Lane-Emden density profile.
template <int D>
std::vector<Vec<D>> polytrope_points(const BodyConfig& b, const Polytrope& model) {
  std::vector<Vec<D>> pts;
  if constexpr (D == 3) {
    BodyConfig unit = b;
    const double volume = 4.0 / 3.0 * std::numbers::pi / double(b.particles);  // per particle
    unit.spacing = b.lattice == Lattice::HexagonalClosePacked ? std::cbrt(std::sqrt(2.0) * volume) : std::cbrt(volume);
    for (int k = 0; k < 3; ++k) {
      unit.min[k] = -1;
      unit.max[k] = 1;
    }
    for (const Vec<3>& p : lattice_points<3>(unit)) {
      const double ru = norm(p);
      if (ru >= 1) continue;
      const double r = model.radius_of_mass_fraction(ru * ru * ru);
      Vec<3> x;
      for (int k = 0; k < 3; ++k) x[k] = Real(b.center[k] + (ru > 0 ? p[k] / ru * r : 0.0));
      pts.push_back(x);
    }
  }
  return pts;
}

}  // namespace

// [[energy_deposits]] (scene.hpp): add E to the free particles within the
// radius, weighted by w_a (the cubic spline of support `radius`, or 1), as
// specific energy E w_a / sum_b m_b w_b, so that sum_a m_a du_a = E exactly
// (up to rounding).
template <int D>
void apply_energy_deposits(const Scene& scene, ParticleStore<D>& ps) {
  const Box<D> domain = domain_from_scene<D>(scene);
  for (std::size_t k = 0; k < scene.energy_deposits.size(); ++k) {
    const EnergyDepositConfig& e = scene.energy_deposits[k];
    Vec<D> c;
    for (int a = 0; a < D; ++a) c[a] = Real(e.center[a]);
    std::vector<double> w(ps.n, 0.0);
    double mass_weight = 0;
    for (std::size_t i = 0; i < ps.n; ++i) {
      if (!ps.boundary.empty() && ps.boundary[i] != kFreeParticle) continue;
      const double r = double(norm(domain.separation(ps.x[i], c)));
      if (r >= e.radius) continue;
      w[i] = e.profile == DepositProfile::Kernel ? double(kernel_w<D>(KernelType::CubicSpline, Real(r), Real(e.radius)))
                                                 : 1.0;
      mass_weight += double(ps.m[i]) * w[i];
    }
    const std::string key = "energy_deposits[" + std::to_string(k) + "]";
    if (!(mass_weight > 0))
      throw InputError(scene.file, key + ".radius",
                       "is " + fmt_g(e.radius) + ", but no free particle lies closer than that to the centre: "
                       "the energy would go nowhere (make the radius at least the particle spacing)");
    for (std::size_t i = 0; i < ps.n; ++i)
      if (w[i] > 0) ps.u[i] += Real(e.energy * w[i] / mass_weight);
  }
}

// Weibull flaws (scene/flaws.hpp) for every free body whose material has
// tensile damage; the body's volume is the sum of its particles' m/rho
// (times a unit depth in 1-D and 2-D, physics/damage.hpp), its stream the
// body's index. A layered body draws per layer (its particles are stored
// layer by layer): the layer's own material and volume, stream body index +
// 2^32 x layer. Walls and other materials keep 0 flaws (no damage).
template <int D>
void draw_body_flaws(const Scene& scene, const std::vector<std::int64_t>& first, ParticleStore<D>& ps) {
  if (ps.flaw_count.empty()) return;
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) {
    const BodyConfig& b = scene.bodies[k];
    if (b.boundary != BoundaryKind::None) continue;
    std::uint64_t run = 0;  // runs of one material within the body
    for (std::size_t i0 = std::size_t(first[k]); i0 < std::size_t(first[k + 1]); ++run) {
      std::size_t i1 = i0;
      while (i1 < std::size_t(first[k + 1]) && ps.material_id[i1] == ps.material_id[i0]) ++i1;
      const DamageConfig& dc = scene.materials[std::size_t(ps.material_id[i0])].damage;
      if (dc.enabled) {
        double volume = 0;
        for (std::size_t i = i0; i < i1; ++i) volume += double(ps.m[i]) / double(ps.rho[i]);
        const FlawSet f = draw_weibull_flaws(i1 - i0, dc.weibull_k, dc.weibull_m, volume, std::uint64_t(dc.seed),
                                             k + (run << 32), dc.min_flaws_per_particle);
        for (std::size_t j = 0; j < i1 - i0; ++j) {
          ps.flaw_count[i0 + j] = f.count[j];
          ps.flaw_eps_min[i0 + j] = Real(f.eps_min[j]);
          ps.flaw_eps_max[i0 + j] = Real(f.eps_max[j]);
        }
      }
      i0 = i1;
    }
  }
}

// The viscosity switch starts at its floor (a body at rest or in uniform
// motion has no shock to damp); other materials' particles hold their
// constant alpha in av_alpha (unused).
static Real initial_viscosity_alpha(const MaterialParams& mp) {
  return mp.av_switch.enabled ? mp.av_switch.alpha_min : mp.av.alpha;
}

template <int D>
std::vector<std::int64_t> generate_bodies(const Scene& scene, double hfact, const Features& needs,
                                          ParticleStore<D>& ps, CollisionSetup* collision) {
  check_resources<D>(scene, needs, hfact);  // before any particle is made
  const auto materials = material_params_from_scene(scene);
  std::vector<std::vector<Vec<D>>> body_points;
  // layered bodies: their structure and shells (the particles' layers and masses)
  std::vector<HydrostaticProfile> profiles(scene.bodies.size());
  std::vector<ShellParticles> shells(scene.bodies.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodyConfig& b = scene.bodies[i];
    if (b.shape == BodyShape::Layered) {
      profiles[i] = layered_profile(layered_spec(scene.materials, b), scene.gravity.G);
      shells[i] = place_on_shells(profiles[i], b.particles, b.seed);
      std::vector<Vec<D>> pts;
      for (const auto& x : shells[i].x) {
        Vec<D> y;
        for (int k = 0; k < D; ++k) y[k] = Real(b.center[k] + x[k]);
        pts.push_back(y);
      }
      body_points.push_back(std::move(pts));
    } else {
      body_points.push_back(b.shape == BodyShape::Polytrope
                                ? polytrope_points<D>(b, Polytrope(b.polytropic_index, b.mass, b.radius, scene.gravity.G))
                                : lattice_points<D>(b));
    }
    if (body_points.back().empty())
      throw InputError(scene.file, "bodies[" + std::to_string(i) + "].spacing",
                       "the body holds no particle: spacing is larger than the box");
    total += body_points.back().size();
  }
  if (total > std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw InputError(scene.file, "bodies", "the bodies hold " + std::to_string(total) +
                                               " particles, more than a 32-bit particle id can number");
  ps.allocate(total, needs);

  std::vector<std::int64_t> first{0};
  for (const auto& points : body_points) first.push_back(first.back() + std::int64_t(points.size()));
  std::size_t next = 0;
  std::int32_t tool_index = 0;  // rigid tools are numbered in body order (RunPhysics::tools)
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodyConfig& b = scene.bodies[i];
    const std::string key = "bodies[" + std::to_string(i) + "]";
    if (b.shape == BodyShape::Polytrope) {
      // Equal masses; density and pressure from the Lane-Emden profile at
      // each particle's radius, internal energy from the pressure through
      // the material's EOS. Near the surface the profile's density tends to
      // 0: the first guess of h uses at least 5 % of the central density
      // (summation density then finds h).
      const Polytrope model(b.polytropic_index, b.mass, b.radius, scene.gravity.G);
      const double m = b.mass / double(body_points[i].size());
      const EosParams& eos = materials[b.material_id].eos;
      for (const Vec<D>& x : body_points[i]) {
        double r2 = 0;
        for (int k = 0; k < D; ++k) r2 += (double(x[k]) - b.center[k]) * (double(x[k]) - b.center[k]);
        const double rho = std::max(model.density(std::sqrt(r2)), 1e-300);
        const double u = eos_internal_energy_from_pressure(eos, Real(rho), Real(model.pressure(std::sqrt(r2))));
        if (!std::isfinite(u) || u < 0)
          throw InputError(scene.file, key, "initial internal energy is not finite and non-negative");
        ps.x[next] = x;
        for (int k = 0; k < D; ++k) ps.v[next][k] = Real(b.velocity[k]);
        ps.m[next] = Real(m);
        ps.material_id[next] = b.material_id;
        ps.id[next] = static_cast<std::int32_t>(next);
        ps.rho[next] = Real(rho);
        ps.u[next] = Real(u);
        ps.h[next] = h_from_density<D>(Real(hfact), Real(m), Real(std::max(rho, 0.05 * model.rho_c)));
        if (!ps.av_alpha.empty()) ps.av_alpha[next] = initial_viscosity_alpha(materials[b.material_id]);
        ++next;
      }
      continue;
    }
    if (b.shape == BodyShape::Layered) {
      // each particle's mass and layer from its shell; density, pressure and
      // internal energy from the profile on its layer's side of any boundary
      const ShellParticles& sp = shells[i];
      for (std::size_t j = 0; j < sp.x.size(); ++j) {
        const double r = std::sqrt(sp.x[j][0] * sp.x[j][0] + sp.x[j][1] * sp.x[j][1] + sp.x[j][2] * sp.x[j][2]);
        const HydrostaticState st = hydrostatic_in_layer(profiles[i], r, sp.layer[j]);
        const int material = b.layers[std::size_t(sp.layer[j])].material_id;
        ps.x[next] = body_points[i][j];
        for (int k = 0; k < D; ++k) ps.v[next][k] = Real(b.velocity[k]);
        ps.m[next] = Real(sp.m[j]);
        ps.material_id[next] = material;
        ps.id[next] = static_cast<std::int32_t>(next);
        ps.rho[next] = Real(st.rho);
        ps.u[next] = Real(st.u);
        ps.h[next] = h_from_density<D>(Real(hfact), Real(sp.m[j]), Real(st.rho));
        if (!ps.av_alpha.empty()) ps.av_alpha[next] = initial_viscosity_alpha(materials[material]);
        if (!ps.boundary.empty()) ps.boundary[next] = kFreeParticle;
        ++next;
      }
      continue;
    }
    const double m = b.density * lattice_cell_volume<D>(b.lattice, b.spacing);
    const EosParams& eos = materials[b.material_id].eos;
    // A porous body's density is the bulk density rho; its matrix is at
    // rho_s = alpha0 rho with p_s = alpha0 p (p = p_s(alpha rho, u)/alpha).
    const PorosityParams& por = materials[b.material_id].porosity;
    const double alpha0 = por.enabled ? double(por.alpha_e) : 1.0;
    const double u = b.pressure >= 0 ? eos_internal_energy_from_pressure(eos, Real(alpha0 * b.density),
                                                                         Real(alpha0 * b.pressure))
                                     : b.internal_energy;
    if (!std::isfinite(u) || u < 0)
      throw b.pressure >= 0
          ? InputError(scene.file, key + ".density",
                       "the initial internal energy that gives pressure = " + fmt_g(b.pressure) + " at density = " +
                           fmt_g(b.density) + " is " + fmt_g(u) + ", not finite and >= 0: is the density physical?")
          : InputError(scene.file, key + ".internal_energy", "is " + fmt_g(u) + ", must be finite and >= 0");
    for (const Vec<D>& x : body_points[i]) {
      ps.x[next] = x;
      for (int k = 0; k < D; ++k) {
        double v = b.velocity[k];
        for (int l = 0; l < D; ++l) v += b.velocity_gradient[k][l] * double(x[l]);
        ps.v[next][k] = Real(v);
      }
      ps.m[next] = Real(m);
      ps.material_id[next] = b.material_id;
      ps.id[next] = static_cast<std::int32_t>(next);
      ps.rho[next] = Real(b.density);
      ps.u[next] = Real(u);
      ps.h[next] = h_from_density<D>(Real(hfact), Real(m), Real(b.density));
      if (!ps.alpha.empty()) ps.alpha[next] = Real(alpha0);
      if (!ps.av_alpha.empty()) ps.av_alpha[next] = initial_viscosity_alpha(materials[b.material_id]);
      if (!ps.wall_normal.empty() && b.sliding_wall())
        for (int k = 0; k < D; ++k) ps.wall_normal[next][k] = Real(b.wall_normal[k]);
      if (!ps.wall_friction.empty()) ps.wall_friction[next] = Real(b.wall_friction);
      if (!ps.boundary.empty())
        ps.boundary[next] = b.boundary == BoundaryKind::None                   ? kFreeParticle
                            : b.boundary_state == BoundaryState::Evolving     ? kBoundaryEvolving
                            : b.boundary_state == BoundaryState::Extrapolated ? kBoundaryExtrapolated
                                                                              : kBoundaryFrozen;
      if (b.rigid_tool()) {
        // a rigid tool: its offset from the rotation centre, and the velocity
        // of its rigid motion (physics/rigid_body.hpp)
        Vec<D> r0, V;
        for (int k = 0; k < D; ++k) {
          r0[k] = Real(double(x[k]) - b.rotation_center[k]);
          V[k] = Real(b.velocity[k]);
        }
        const Vec<3> n{{Real(b.rotation_axis[0]), Real(b.rotation_axis[1]), Real(b.rotation_axis[2])}};
        ps.tool[next] = tool_index;
        ps.tool_offset[next] = r0;
        ps.v[next] = V + turning_velocity<D>(n, Real(b.angular_velocity), r0);
      }
      for (int k = 0; k < D; ++k)
        if (!std::isfinite(ps.x[next][k]) || !std::isfinite(ps.v[next][k]))
          throw InputError(scene.file, key, "initial position or velocity is not finite");
      ++next;
    }
    if (b.rigid_tool() && b.boundary == BoundaryKind::Driven) {
      // a driven tool turns about its centre of mass (physics/rigid_body.hpp):
      // its offsets from there, its velocity V + omega n x r0 about it
      const std::size_t lo = std::size_t(first[i]), hi = next;
      double M = 0, mx[3] = {0, 0, 0};
      for (std::size_t j = lo; j < hi; ++j) {
        M += double(ps.m[j]);
        for (int k = 0; k < D; ++k) mx[k] += double(ps.m[j]) * double(ps.x[j][k]);
      }
      const Vec<3> n{{Real(b.rotation_axis[0]), Real(b.rotation_axis[1]), Real(b.rotation_axis[2])}};
      for (std::size_t j = lo; j < hi; ++j) {
        Vec<D> V;
        for (int k = 0; k < D; ++k) {
          ps.tool_offset[j][k] = Real(double(ps.x[j][k]) - mx[k] / M);
          V[k] = Real(b.velocity[k]);
        }
        ps.v[j] = V + turning_velocity<D>(n, Real(b.angular_velocity), ps.tool_offset[j]);
      }
    }
    if (b.rigid_tool()) ++tool_index;
  }
  // [collision]: the bodies moved onto their orbit (before the wall
  // anchors, which start where the particles are)
  const CollisionSetup placed = place_collision<D>(scene, ps, first);
  if (collision) *collision = placed;
  // Coulomb walls: every friction spring starts relaxed (wall_friction.hpp)
  if (!ps.wall_anchor.empty()) ps.wall_anchor = ps.x;
  apply_energy_deposits<D>(scene, ps);
  draw_body_flaws<D>(scene, first, ps);
  return first;
}

template <int D>
double estimated_particle_count(const Scene& scene) {
  const double pi = std::numbers::pi;
  double total = 0;
  for (const BodyConfig& b : scene.bodies) {
    if (b.shape == BodyShape::Polytrope || b.shape == BodyShape::Layered) {
      total += double(b.particles);
      continue;
    }
    double volume = 1;
    if (b.shape == BodyShape::Box) {
      for (int k = 0; k < D; ++k) volume *= std::max(b.max[k] - b.min[k], 0.0);
    } else {
      const double ball = D == 1 ? 2 : D == 2 ? pi : 4 * pi / 3;
      volume = ball * std::pow(b.radius, D);
      if (b.shape == BodyShape::Ring) volume -= ball * std::pow(b.inner_radius, D);
    }
    total += volume / lattice_cell_volume<D>(b.lattice, b.spacing);
  }
  return total;
}

template <int D>
std::size_t bytes_per_particle(const Scene& scene, const Features& needs, double hfact) {
  ParticleStore<D> one;
  one.allocate(1, needs);
  std::size_t store = 0, snapshot = 0;
  for (const auto& f : field_table<D>())
    std::visit(
        [&](auto member) {
          const auto& arr = one.*member;
          if (arr.empty()) return;
          store += sizeof(arr[0]);
          if (f.snapshot && f.role != FieldRole::Constant) snapshot += sizeof(arr[0]);  // the last good state
        },
        f.member);
  const std::size_t integrator = scene.simulation.integrator == Integrator::RK2Adaptive ? 2 * store : store / 2;
  // neighbours within the search radius kSearchSkin h (h = hfact spacings)
  const double r = kSearchSkin * hfact, pi = std::numbers::pi;
  const double neighbours = D == 1 ? 2 * r : D == 2 ? pi * r * r : 4 * pi / 3 * r * r * r;
  // two bytes per entry (NeighborLists: 16-bit differences), an eighth
  // spare in the blocks, and the per-particle index (begin, count, block)
  const std::size_t lists = std::size_t(2 * 1.125 * neighbours) + 3 * sizeof(std::uint32_t);
  const std::size_t cells = sizeof(Vec<D>) + sizeof(Real) + sizeof(std::uint64_t) + 2 * sizeof(std::uint32_t);
  // continuity density keeps its lists across evaluations: the positions
  // at the search (CpuBackend::search_still_holds); the search radius is in
  // `cells`; solids add 1/H and 1/rho^2 (SolidInverses) and the sums of
  // the first pass (GradientSums: L, the correction's M, the nearest r^2)
  const std::size_t kept = needs.continuity_density ? sizeof(Vec<D>) : 0;
  const std::size_t solid = needs.solid ? 2 * sizeof(Real) + 2 * sizeof(Mat<D>) + sizeof(Real) : 0;
  return store + integrator + snapshot + lists + cells + kept + solid;
}

double available_memory_bytes() {
  if (const char* env = std::getenv("RUBBLE_MEMORY_LIMIT"); env && *env) {
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end && *end == '\0' && v > 0) return v;
  }
  double avail = 0;
  if (std::ifstream in("/proc/meminfo"); in) {
    std::string key;
    double kb = 0;
    std::string unit;
    while (in >> key >> kb >> unit)
      if (key == "MemAvailable:") {
        avail = kb * 1024;
        break;
      }
  }
  if (std::ifstream in("/sys/fs/cgroup/memory.max"); in) {
    std::string text;
    in >> text;
    char* end = nullptr;
    const double limit = std::strtod(text.c_str(), &end);
    if (end && *end == '\0' && limit > 0) avail = avail > 0 ? std::min(avail, limit) : limit;
  }
  return avail;
}

std::string format_bytes(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
  int u = 0;
  while (bytes >= 1024 && u < 5) {
    bytes /= 1024;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return buf;
}

template <int D>
void check_resources(const Scene& scene, const Features& needs, double hfact) {
  const double n = estimated_particle_count<D>(scene);
  if (n > double(std::numeric_limits<std::int32_t>::max()))
    throw InputError(scene.file, "bodies",
                     "the bodies would hold about " + fmt_g(n) + " particles, more than the " +
                         std::to_string(std::numeric_limits<std::int32_t>::max()) +
                         " a 32-bit particle id can number: use a coarser spacing");
  const double per = double(bytes_per_particle<D>(scene, needs, hfact));
  const double need = n * per, have = available_memory_bytes();
  if (have > 0 && need > have)
    throw InputError(scene.file, "bodies",
                     "the run needs about " + format_bytes(need) + " (" + fmt_g(n) + " particles x " + fmt_g(per) +
                         " bytes), more than the " + format_bytes(have) +
                         " of memory available (MemAvailable, the cgroup limit, or RUBBLE_MEMORY_LIMIT): use a "
                         "coarser spacing or a larger machine");
}

template <int D>
std::vector<std::string> check_overlap(const Scene& scene, const ParticleStore<D>& ps,
                                       const std::vector<std::int64_t>& body_first, const Box<D>& domain,
                                       double hfact) {
  if (scene.simulation.allow_overlap || scene.bodies.size() < 2) return {};
  const std::size_t n = ps.n;
  // one search to the kernel support: pairs closer than half a spacing are an
  // overlap (an error), pairs of free bodies within a support interact at once
  CellList<D> cells;
  cells.build(ps.x.data(), ps.h.data(), n, bounding_box<D>(ps.x.data(), n, domain));
  NeighborLists nb;
  cells.find_neighbors(nb);
  auto body_of = [&](std::size_t i) { return body_of_id(body_first, ps.id[i]); };
  auto free_particle = [&](std::size_t i) { return ps.boundary.empty() || ps.boundary[i] == kFreeParticle; };
  const std::size_t nbodies = scene.bodies.size();
  std::vector<Real> closest(nbodies * nbodies, Real(-1));  // per pair of free bodies in contact, -1: none
  for (std::size_t a = 0; a < n; ++a)
    nb.for_each(a, [&](std::size_t b) {
      if (b <= a) return;
      const std::size_t ka = body_of(a), kb = body_of(b);
      if (ka == kb) return;
      const Real r = norm(domain.separation(ps.x[a], ps.x[b]));
      const Real half_a = Real(0.5) * ps.h[a] / Real(hfact), half_b = Real(0.5) * ps.h[b] / Real(hfact);
      if (r < std::min(half_a, half_b)) {
        const std::size_t first = std::min(ka, kb), second = std::max(ka, kb);
        throw InputError(scene.file, "bodies[" + std::to_string(second) + "]",
                         "overlaps bodies[" + std::to_string(first) + "]: particles " +
                             std::to_string(ps.id[a] - body_first[ka]) + " of bodies[" + std::to_string(ka) +
                             "] and " + std::to_string(ps.id[b] - body_first[kb]) + " of bodies[" +
                             std::to_string(kb) + "] are " + fmt_g(r) +
                             " m apart, less than half their spacing; move the bodies apart, or set "
                             "simulation.allow_overlap = true if they are meant to overlap");
      }
      if (!free_particle(a) || !free_particle(b) || !(r < std::max(ps.h[a], ps.h[b]))) return;
      Real& c = closest[std::min(ka, kb) * nbodies + std::max(ka, kb)];
      if (c < 0 || r < c) c = r;
    });
  std::vector<std::string> warnings;
  for (std::size_t i = 0; i < nbodies; ++i)
    for (std::size_t j = i + 1; j < nbodies; ++j) {
      const Real r = closest[i * nbodies + j];
      if (r < 0) continue;
      warnings.push_back(scene.file + ": bodies[" + std::to_string(i) + "] and bodies[" + std::to_string(j) +
                         "] start within a kernel support of each other (closest particles " + fmt_g(r) +
                         " m apart): they interact from the first step. Intended for bodies in contact; move "
                         "them apart by a support radius if they should meet later");
    }
  return warnings;
}

template <int D>
Box<D> domain_from_scene(const Scene& scene) {
  Box<D> box;
  for (int k = 0; k < D; ++k) {
    box.periodic[k] = scene.domain.periodic[k];
    box.lo[k] = Real(scene.domain.min[k]);
    box.hi[k] = Real(scene.domain.max[k]);
  }
  return box;
}

#define RUBBLE_INSTANTIATE(D)                                                                      \
  template double lattice_cell_volume<D>(Lattice, double);                                         \
  template std::vector<Vec<D>> lattice_points<D>(BodyConfig);                                      \
  template std::vector<std::int64_t> generate_bodies<D>(const Scene&, double, const Features&, ParticleStore<D>&,  \
                                                       CollisionSetup*);                                   \
  template Box<D> domain_from_scene<D>(const Scene&);                                              \
  template double estimated_particle_count<D>(const Scene&);                                       \
  template std::size_t bytes_per_particle<D>(const Scene&, const Features&, double);              \
  template void check_resources<D>(const Scene&, const Features&, double);                        \
  template std::vector<std::string> check_overlap<D>(const Scene&, const ParticleStore<D>&, const std::vector<std::int64_t>&, \
                                 const Box<D>&, double);
RUBBLE_INSTANTIATE(1)
RUBBLE_INSTANTIATE(2)
RUBBLE_INSTANTIATE(3)
#undef RUBBLE_INSTANTIATE

}  // namespace rubble
