#include "hydro_cpu.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "rubble/core/error.hpp"
#include "rubble/neighbors/spatial_order.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/rhs_features.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/scene/materials.hpp"

namespace rubble {

namespace {
// Adds the wall time of its scope to `sum`.
class ScopedSeconds {
 public:
  explicit ScopedSeconds(double& sum) : sum_(sum), start_(std::chrono::steady_clock::now()) {}
  ~ScopedSeconds() { sum_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  ScopedSeconds(const ScopedSeconds&) = delete;
  ScopedSeconds& operator=(const ScopedSeconds&) = delete;

 private:
  double& sum_;
  std::chrono::steady_clock::time_point start_;
};
}  // namespace

PorosityParams porosity_params_from_config(const PorosityConfig& c) {
  PorosityParams p{};
  p.enabled = c.enabled;
  if (!c.enabled) return p;
  p.curve = c.crush_curve == CrushCurveType::Steep ? CrushCurve::Steep : CrushCurve::Quadratic;
  p.alpha_e = Real(c.alpha0);
  p.p_e = Real(c.p_e);
  p.p_s = Real(c.p_s);
  p.p_t = Real(c.p_t);
  p.alpha_t = Real(c.alpha_t);
  p.n1 = Real(c.n1);
  p.n2 = Real(c.n2);
  p.c_e = Real(c.c_e);
  p.c_s0 = Real(c.c_s0);
  return p;
}

// The scene's cone name as the physics' fit (a switch, so that a new fit
// the scene offers without one here is a compiler warning).
static DpConeFit dp_cone_fit(ConeFit cone) {
  switch (cone) {
    case ConeFit::Compression: return DpConeFit::Compression;
    case ConeFit::Extension: return DpConeFit::Extension;
    case ConeFit::PlaneStrain: break;
  }
  return DpConeFit::PlaneStrain;
}

PlasticityParams plasticity_params_from_config(const PlasticityConfig& c) {
  switch (c.model) {
    case PlasticityType::VonMises: return von_mises_params(Real(c.yield_stress));
    case PlasticityType::DruckerPrager:
      return drucker_prager_params(Real(c.friction_angle), Real(c.cohesion), Real(c.dilatancy_angle),
                                   dp_cone_fit(c.cone));
    case PlasticityType::None:
    default: return PlasticityParams{};
  }
}

DamageParams damage_params_from_config(const DamageConfig& c) {
  DamageParams d{};
  d.enabled = c.enabled;
  if (!c.enabled) return d;
  d.weibull_k = Real(c.weibull_k);
  d.weibull_m = Real(c.weibull_m);
  d.crack_speed = Real(c.crack_speed);
  d.deviatoric = c.deviatoric;
  d.capped = c.capped;
  return d;
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
    p.porosity = porosity_params_from_config(m.porosity);
    p.plasticity = plasticity_params_from_config(m.plasticity);
    p.damage = damage_params_from_config(m.damage);
    p.stress_diffusion = Real(m.stress_diffusion);
    // Jaky's (1944) K0 = 1 - sin phi for a granular material (Feng et al.
    // 2021); other solids get no geostatic correction of the deviator
    p.k0 = m.plasticity.model == PlasticityType::DruckerPrager
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

template <int D>
HydroCpu<D>::HydroCpu(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain)
    : ps_(ps),
      domain_(domain),
      materials_(material_params_from_scene(scene)),
      kernel_(scene.simulation.kernel),
      hfact_(Real(scene.simulation.hfact > 0 ? scene.simulation.hfact
                                              : kernel_default_hfact(scene.simulation.kernel))),
      courant_(Real(scene.simulation.courant)),
      force_factor_(Real(scene.simulation.force_factor)),
      h_tolerance_(h_iteration_tolerance(scene.simulation.h_tolerance)),
      summation_(scene.simulation.density == DensityForm::Summation),
      gravity_(scene.gravity, scene.simulation.kernel) {
  if (gravity_.enabled() && (D != 3 || ps_.a_grav.size() != ps_.n || ps_.phi.size() != ps_.n))
    throw RunError("self-gravity needs a 3-D scene with the a_grav and phi fields allocated");
  const RhsFeatures f = rhs_features<D>(scene, materials_, ps_);
  solid_ = f.solid;
  artificial_stress_ = f.artificial_stress;
  kernel_correction_ = f.kernel_correction;
  stress_diffusion_ = f.stress_diffusion;
  if (solid_ && artificial_stress_) art_R_.assign(ps_.n, Mat<D>::zero());
  porosity_ = f.porosity;
  plasticity_ = f.plasticity;
  damage_ = f.damage;
  viscosity_switch_ = f.viscosity_switch;
  coulomb_walls_ = !ps_.wall_anchor.empty();
  body_force_ = f.body_force;
  wall_extrapolation_ = f.wall_extrapolation;
  for (int k = 0; k < D; ++k) g_[k] = Real(scene.simulation.gravity[k]);
  xsph_epsilon_ = Real(scene.simulation.xsph);
  shifting_ = Real(scene.simulation.shifting);
  if (shifting_ > Real(0)) shift_.assign(ps_.n, Vec<D>::zero());
}

template <int D>
void HydroCpu<D>::sort_particles() {
  const Box<D> box = bounding_box<D>(ps_.x.data(), ps_.n, domain_);
  ps_.permute(spatial_sort_permutation<D>(ps_.x.data(), ps_.n, box));
  lists_in_order_ = false;  // the lists index the particles in the old order
}

template <int D>
void HydroCpu<D>::build_neighbors(const std::vector<Real>& search_radius) {
  const ScopedSeconds timer(phases_.neighbours);
  const Box<D> box = bounding_box<D>(ps_.x.data(), ps_.n, domain_);
  try {
    cells_.build(ps_.x.data(), search_radius.data(), ps_.n, box);
  } catch (const std::invalid_argument& e) {
    // e.g. a smoothing length that grew past half a periodic length
    throw RunError(std::string("the neighbour search failed (") + e.what() + ")");
  }
  cells_.find_neighbors(nbrs_);
  ++rebuilds_;
}

// The neighbour lists as the `each` of rubble/drivers/particle_rates.hpp.
struct ListNeighbors {
  const NeighborLists& nbrs;
  std::uint32_t a;
  template <class F>
  void operator()(F&& f) const {
    nbrs.for_each(a, f);
  }
};

// The pair-once loops (rates, solid_rates): inside a parallel region, the
// contiguous range [lo, hi) of the n particles (Morton order) that this
// thread owns.
namespace {
std::pair<std::size_t, std::size_t> own_range(std::size_t n) {
#if defined(_OPENMP)
  const std::size_t threads = std::size_t(omp_get_num_threads()), t = std::size_t(omp_get_thread_num());
#else
  const std::size_t threads = 1, t = 0;
#endif
  return {n * t / threads, n * (t + 1) / threads};
}
}  // namespace

template <int D>
RhsContext<D> HydroCpu<D>::context() {
  RhsContext<D> c;
  c.s = ps_.view();
  c.mat = materials_.data();
  c.domain = domain_;
  c.kernel = kernel_;
  c.hfact = hfact_;
  c.summation = summation_;
  c.kernel_correction = kernel_correction_;
  c.stress_diffusion = stress_diffusion_;
  c.art_R = art_R_.empty() ? nullptr : art_R_.data();
  c.xsph_epsilon = xsph_epsilon_;
  c.courant = courant_;
  c.force_factor = force_factor_;
  c.h_tolerance = h_tolerance_;
  c.body_force = g_;
  c.has_body_force = body_force_;
  c.stagger_dt = stagger_dt_;
  return c;
}

// Summation density with h and rho solved together (smoothing_length.hpp).
// The neighbour lists are built with a search radius 5 % above the current
// h; a particle whose h grows past its search radius triggers a rebuild, in
// which that particle searches 30 % beyond the h it had reached.
// Issue #14: with 15 % the lists held 88 entries per particle in 3-D for
// 58 inside the support, and the density and force loops walked them all;
// at 5 % they hold ~67, the 3-D Sedov blast needs no extra rebuild (48
// searches in 48 evaluations at 32^3), and the results are those of a
// wider search (entries outside the support add exact zeros).
template <int D>
void HydroCpu<D>::summation_density_and_h() {
  const std::size_t n = ps_.n;
  constexpr Real kSkin = Real(kSearchSkin);
  constexpr Real kRegrowSkin = Real(1.3);
  search_radius_.resize(n);
  for (std::size_t i = 0; i < n; ++i) search_radius_[i] = kSkin * ps_.h[i];

  for (int attempt = 0; attempt < 8; ++attempt) {
    build_neighbors(search_radius_);
    const RhsContext<D> c = context();
    int outgrown = 0;
    {
      const ScopedSeconds timer(phases_.density);
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : outgrown)
      for (std::size_t a = 0; a < n; ++a) {
        const std::uint32_t ia = static_cast<std::uint32_t>(a);
        if (!summation_density_particle<D>(c, ia, search_radius_[a], ListNeighbors{nbrs_, ia})) {
          search_radius_[a] = kRegrowSkin * ps_.h[a];
          ++outgrown;
        }
      }
    }
    // The force loop needs all pairs within max(h_a, h_b): the lists hold
    // all pairs within max(search_a, search_b), which is at least that.
    if (outgrown == 0) return;
  }
  throw RunError("smoothing-length iteration did not settle after 8 neighbour rebuilds");
}

// Continuity density: h follows rho, and the lists are searched with the
// radius kSearchSkin h and kept across evaluations while they still hold
// every pair that can interact (lists_still_hold). Entries beyond both
// supports add nothing (every pair function skips them, as it skips the
// GPU's cell candidates), and a list keeps its ascending order, so a kept
// list gives the same sums, bit for bit, as a new search would
// (Run.KeptNeighbourListsGiveTheSameRun). Solids move a small fraction of
// h per step, so a search is then needed only after each sort (every 16
// steps; docs/performance.md).
template <int D>
void HydroCpu<D>::h_from_continuity_density() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
  {
    const ScopedSeconds timer(phases_.density);
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) h_from_density_particle<D>(c, static_cast<std::uint32_t>(a));
  }
  if (keep_lists_ && lists_still_hold()) return;
  constexpr Real kSkin = Real(kSearchSkin);
  search_radius_.resize(n);
  x_at_search_.resize(n);
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) {
    search_radius_[a] = kSkin * ps_.h[a];
    x_at_search_[a] = ps_.x[a];
  }
  build_neighbors(search_radius_);
  lists_in_order_ = true;
}

// The last search listed every pair closer than max(S_a, S_b), S the search
// radii. A pair that interacts now is closer than max(h_a, h_b) and was at
// most d_a + d_b <= 2 d farther apart at the search (d: the largest
// distance any particle has moved since), so it is listed if every particle
// has h + 2 d <= S.
template <int D>
bool HydroCpu<D>::lists_still_hold() const {
  const std::size_t n = ps_.n;
  if (!lists_in_order_ || x_at_search_.size() != n) return false;
  Real d2 = 0;
#pragma omp parallel for if (n > 4096) reduction(max : d2)
  for (std::size_t a = 0; a < n; ++a) {
    const Real m = norm2(domain_.separation(ps_.x[a], x_at_search_[a]));
    d2 = m > d2 ? m : d2;
  }
  const Real reach = Real(2) * std::sqrt(d2);
  int broken = 0;
#pragma omp parallel for if (n > 4096) reduction(+ : broken)
  for (std::size_t a = 0; a < n; ++a)
    if (!(ps_.h[a] + reach <= search_radius_[a])) ++broken;
  return broken == 0;
}

template <int D>
void HydroCpu<D>::equation_of_state() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) eos_particle<D>(c, static_cast<std::uint32_t>(a));
}

// Feature set Hydro: pressure, viscosity, conductivity.
//
// Each pair once (issue #14: the force loop was ~45 % of a hydro step, each
// pair computed from both sides). The particles, in Morton order, are cut
// into one contiguous range per thread. A thread computes a pair of two of
// its own particles once, from the lower index, and adds both sides
// (hydro_pair_rates_a and _b: the same floating-point operations as the
// pair computed from each side); a pair whose other particle belongs to
// another thread it computes for its own particle only, as that thread
// does for its own. Every write goes to the thread's own particles, so no
// two threads write one particle, and the results differ from the gather
// loop (hydro_rates_particle, which the CUDA backend runs) only in the
// order of each particle's sum. Scenes with free-slip walls (the velocity a
// particle sees of a wall particle depends on who looks), porous scenes
// (dalpha/dt needs the complete sums) and the viscosity switch (a
// particle's d alpha_AV/dt likewise) keep the gather loop.
template <int D>
void HydroCpu<D>::rates() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
  const StoreView<D>& s = c.s;
  if (s.wall_normal || s.dalphadt || s.dav_alpha_dt) {
#pragma omp parallel for schedule(dynamic, 256)
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      hydro_rates_particle<D>(c, ia, ListNeighbors{nbrs_, ia});
    }
    return;
  }
  const bool continuity = !c.summation;
#pragma omp parallel
  {
    // plain variables, not a structured binding: clang before 16 cannot
    // capture a binding into the lambdas and OpenMP regions below
    const auto range = own_range(n);
    const std::size_t lo = range.first, hi = range.second;
    for (std::size_t a = lo; a < hi; ++a) {
      s.dvdt[a] = Vec<D>::zero();
      s.dudt[a] = Real(0);
      s.mu_max[a] = Real(0);
      if (continuity) s.drhodt[a] = Real(0);
    }
    for (std::size_t a = lo; a < hi; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      const HydroSide<D> sa = hydro_side<D>(c.kernel, hydro_particle<D>(c, ia));
      Vec<D> dvdt = Vec<D>::zero();
      Real dudt = 0, drhodt = 0, mu_max = 0;
      nbrs_.for_each(a, [&](std::uint32_t b) {
        const bool mine = b >= lo && b < hi;
        if (mine && b < a) return;  // done from b's side
        const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
        const Real h_max = sa.q.h > s.h[b] ? sa.q.h : s.h[b];
        if (norm2(dx) >= h_max * h_max) return;  // in the search skin only
        const HydroSide<D> sb = hydro_side<D>(c.kernel, hydro_particle<D>(c, b), !mine);
        const HydroPairTerms<D> terms = hydro_pair_terms<D>(sa, sb, dx, continuity);
        const HydroPairRates<D> ra = hydro_pair_rates_a<D>(terms, sa, sb);
        dvdt += ra.dvdt;
        dudt += ra.dudt;
        drhodt += ra.drhodt;
        mu_max = ra.mu > mu_max ? ra.mu : mu_max;
        if (!mine) return;
        const HydroPairRates<D> rb = hydro_pair_rates_b<D>(terms, sa, sb);
        s.dvdt[b] += rb.dvdt;
        s.dudt[b] += rb.dudt;
        if (continuity) s.drhodt[b] += rb.drhodt;
        if (rb.mu > s.mu_max[b]) s.mu_max[b] = rb.mu;
      });
      s.dvdt[a] += dvdt;
      s.dudt[a] += dudt;
      if (continuity) s.drhodt[a] += drhodt;
      if (mu_max > s.mu_max[a]) s.mu_max[a] = mu_max;
    }
  }
}

// Feature set Solid (any material with a shear modulus; continuity density).
// Pass 1: the velocity gradient L_a (optionally with the kernel-gradient
// correction), the Jaumann stress rate and the artificial stress tensor
// R_a. Pass 2: the pair forces from the full stress (solid_pair). Both
// passes take each pair once within a thread's range, as rates() does,
// except with free-slip walls (the gather loops the CUDA backend runs).
// Both passes divide by every neighbour's H (kernel) and pass 2 by its
// rho^2 (stress term): these inverses are taken once per particle first
// (solid_inverses; the same values as computed at each pair, so the
// results are bit for bit those of the per-pair form, which the CUDA
// backend keeps). Measured on the oscillating plate: see docs/performance.md.
template <int D>
void HydroCpu<D>::solid_rates() {
  const std::size_t n = ps_.n;
  RhsContext<D> c = context();
  solid_inv_.resize(n);
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) solid_inv_[a] = solid_inverses(ps_.h[a], ps_.rho[a]);
  c.solid_inv = solid_inv_.data();
  const bool staggered = c.stagger_dt > Real(0);
  if (staggered) {
    stagger_Lm_.resize(n);
    stagger_du_.resize(n);
    c.stagger_Lm = stagger_Lm_.data();
    c.stagger_du = stagger_du_.data();
    if (c.art_R) {
      as_chi_.resize(n);
      c.as_chi = as_chi_.data();
    }
  }
  const StoreView<D>& s = c.s;
  std::int64_t fallbacks = 0;
  // the staggered stress update, between the passes (leapfrog.hpp); pass 2
  // then divides by the new densities
  auto staggered_update = [&] {
    if (!staggered) return;
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) {
      staggered_update_particle<D>(c, static_cast<std::uint32_t>(a), plasticity_);
      solid_inv_[a] = solid_inverses(ps_.h[a], ps_.rho[a]);
    }
  };
  auto staggered_energy = [&] {
    if (!staggered) return;
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) staggered_energy_particle<D>(c, static_cast<std::uint32_t>(a));
  };
  if (s.wall_normal) {  // free-slip walls: the velocity seen of a wall particle depends on who looks
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : fallbacks)
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      if (!solid_gradient_particle<D>(c, ia, ListNeighbors{nbrs_, ia})) ++fallbacks;
    }
    fallbacks_last_ = fallbacks;
    fallbacks_total_ += fallbacks;
    staggered_update();
#pragma omp parallel for schedule(dynamic, 256)
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      solid_rates_particle<D>(c, ia, ListNeighbors{nbrs_, ia});
    }
    staggered_energy();
    return;
  }
  // Pass 1 each pair once (the ranges of the force loops below): a pair
  // inside the thread's range adds its terms to both particles' sums, b's
  // with the vectors seen from b (other_side); a pair across ranges is
  // taken from each side for the thread's own particle. A particle's sums
  // are complete when its thread has walked its range, and the thread then
  // finishes its own particles (solid_gradient_finish).
  grad_sums_.resize(n);
  if (c.stress_diffusion) sd_sums_.resize(n);  // only a scene whose material diffuses holds it
#pragma omp parallel reduction(+ : fallbacks)
  {
    // plain variables, not a structured binding: clang before 16 cannot
    // capture a binding into the lambdas and OpenMP regions below
    const auto range = own_range(n);
    const std::size_t lo = range.first, hi = range.second;
    for (std::size_t a = lo; a < hi; ++a) grad_sums_[a] = GradientSums<D>{};
    if (c.stress_diffusion)
      for (std::size_t a = lo; a < hi; ++a) sd_sums_[a] = Mat<D>::zero();
    for (std::size_t a = lo; a < hi; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      const KernelAt<D> ka = kernel_at_inv<D>(c.kernel, c.solid_inv[a].inv_h);
      GradientSums<D> sums;
      Mat<D> sd = Mat<D>::zero();
      nbrs_.for_each(a, [&](std::uint32_t b) {
        const bool mine = b >= lo && b < hi;
        if (mine && b < a) return;  // done from b's side
        const GradientPairTerms<D> terms = gradient_pair_terms<D>(c, ia, b, ka, c.domain.separation(s.x[a], s.x[b]));
        if (terms.r2 > Real(0) && terms.r2 < sums.r2_min) sums.r2_min = terms.r2;
        if (mine && terms.r2 > Real(0) && terms.r2 < grad_sums_[b].r2_min) grad_sums_[b].r2_min = terms.r2;
        if (!terms.active) return;
        add_gradient_pair<D>(c, ia, b, terms, sums);
        if (mine) add_gradient_pair<D>(c, b, ia, other_side<D>(terms), grad_sums_[b]);
        if (!c.stress_diffusion) return;
        add_stress_diffusion_pair<D>(c, ia, b, terms, sd);
        if (mine) add_stress_diffusion_pair<D>(c, b, ia, other_side<D>(terms), sd_sums_[b]);
      });
      GradientSums<D>& own = grad_sums_[a];
      own.L += sums.L;
      own.M += sums.M;
      if (c.stress_diffusion) sd_sums_[a] += sd;
      if (sums.r2_min < own.r2_min) own.r2_min = sums.r2_min;
    }
    for (std::size_t a = lo; a < hi; ++a)
      if (!solid_gradient_finish<D>(c, static_cast<std::uint32_t>(a), grad_sums_[a],
                                    c.stress_diffusion ? &sd_sums_[a] : nullptr))
        ++fallbacks;
  }
  fallbacks_last_ = fallbacks;
  fallbacks_total_ += fallbacks;
  staggered_update();
  // Pass 2 each pair once, as HydroCpu::rates: a contiguous Morton range
  // per thread, a pair inside the range computed once from its lower index
  // (solid_pair_rates_a and _b), a pair across ranges from each side for
  // the thread's own particle only; every write goes to the thread's own
  // particles. A particle's sums are complete when its thread has walked
  // its range, so the thread then takes its porous particles' dalpha/dt.
#pragma omp parallel
  {
    // plain variables, not a structured binding: clang before 16 cannot
    // capture a binding into the lambdas and OpenMP regions below
    const auto range = own_range(n);
    const std::size_t lo = range.first, hi = range.second;
    for (std::size_t a = lo; a < hi; ++a) {
      s.dvdt[a] = Vec<D>::zero();
      s.dudt[a] = Real(0);
      s.drhodt[a] = Real(0);
      s.mu_max[a] = Real(0);
    }
    for (std::size_t a = lo; a < hi; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      const SolidParticle<D> pa = solid_particle<D>(c, ia);
      const SolidInverses inv_a = c.solid_inv[a];
      Vec<D> dvdt = Vec<D>::zero();
      Real dudt = 0, drhodt = 0, mu_max = 0;
      nbrs_.for_each(a, [&](std::uint32_t b) {
        const bool mine = b >= lo && b < hi;
        if (mine && b < a) return;  // done from b's side
        const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
        const Real h_max = pa.h > s.h[b] ? pa.h : s.h[b];
        if (norm2(dx) >= h_max * h_max) return;  // in the search skin only
        const SolidPairTerms<D> terms =
            solid_pair_terms<D>(c.kernel, pa, inv_a, solid_particle<D>(c, b), c.solid_inv[b], dx);
        if (!terms.active) return;
        const SolidPairRates<D> ra = solid_pair_rates_a<D>(terms, s.m[b]);
        dvdt += ra.dvdt;
        dudt += ra.dudt;
        drhodt += ra.drhodt;
        mu_max = ra.mu > mu_max ? ra.mu : mu_max;
        if (!mine) return;
        const SolidPairRates<D> rb = solid_pair_rates_b<D>(terms, s.m[a]);
        s.dvdt[b] += rb.dvdt;
        s.dudt[b] += rb.dudt;
        s.drhodt[b] += rb.drhodt;
        if (rb.mu > s.mu_max[b]) s.mu_max[b] = rb.mu;
      });
      s.dvdt[a] += dvdt;
      s.dudt[a] += dudt;
      s.drhodt[a] += drhodt;
      if (mu_max > s.mu_max[a]) s.mu_max[a] = mu_max;
    }
    if (s.dalphadt)
      for (std::size_t a = lo; a < hi; ++a)
        s.dalphadt[a] = porosity_rate_particle<D>(c, static_cast<std::uint32_t>(a), s.drhodt[a], s.dudt[a]);
  }
  staggered_energy();
}

// XSPH: the smoothed-velocity correction to dx/dt (physics/xsph.hpp).
template <int D>
void HydroCpu<D>::xsph_velocity() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t ia = static_cast<std::uint32_t>(a);
    xsph_particle<D>(c, ia, ListNeighbors{nbrs_, ia});
  }
}

template <int D>
void HydroCpu<D>::plastic_return(bool accumulate) {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) plastic_return_particle<D>(c, static_cast<std::uint32_t>(a), accumulate);
}

// Extrapolated walls: p, S, rho, c_s of the wall particles from the free
// particles' state of this evaluation (after their EOS and plastic return).
template <int D>
void HydroCpu<D>::wall_extrapolation() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t ia = static_cast<std::uint32_t>(a);
    wall_extrapolation_particle<D>(c, ia, ListNeighbors{nbrs_, ia});
  }
}

template <int D>
void HydroCpu<D>::body_force() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) body_force_particle<D>(c, static_cast<std::uint32_t>(a));
}

template <int D>
void HydroCpu<D>::end_step(const Real* alpha_start, Real dt) {
  if (!(porosity_ || plasticity_ || damage_ || viscosity_switch_ || coulomb_walls_ || shifting_ > Real(0))) return;
  const ScopedSeconds timer(phases_.end_step);
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
  if (porosity_) {
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) porosity_end_step_particle<D>(c, static_cast<std::uint32_t>(a), alpha_start);
  }
  if (damage_) {
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) damage_end_step_particle<D>(c, static_cast<std::uint32_t>(a));
  }
  if (viscosity_switch_) {
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) viscosity_switch_end_step_particle<D>(c, static_cast<std::uint32_t>(a));
  }
  if (plasticity_ || porosity_ || damage_) {
    // The pressure of the final state: the plastic return works at fixed p,
    // and the stored p, c_s of a leapfrog step then belong to the state it
    // returns (snapshots, the next step limit), not to its predicted state.
    equation_of_state();
    if (plasticity_) plastic_return(true);
  }
  if (shifting_ > Real(0)) shift_particles(dt);
  if (coulomb_walls_) {  // after the shift: a shift along a wall stretches the friction spring like any motion
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) wall_anchor_end_step_particle<D>(c, static_cast<std::uint32_t>(a));
  }
}

// Particle shifting (physics/particle_shifting.hpp) with the neighbour
// lists of the last evaluation: exact for leapfrog, whose last evaluation
// is at the final positions; for rk2_adaptive the final positions differ by
// the step's last correction, and a pair that has just entered the support
// is missed (its kernel terms vanish at the support's edge).
template <int D>
void HydroCpu<D>::shift_particles(Real dt) {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
  Vec<D>* out = shift_.data();
  const Real A = shifting_;
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t ia = static_cast<std::uint32_t>(a);
    shifting_particle<D>(c, ia, A, dt, out, ListNeighbors{nbrs_, ia});
  }
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) ps_.x[a] = domain_.wrap(ps_.x[a] + out[a]);
}

template <int D>
void HydroCpu<D>::hold_boundaries() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) hold_boundary_particle<D>(c, static_cast<std::uint32_t>(a));
}

// Self-gravity (3-D only): a_grav and phi from direct summation or the
// octree, softened with h (or a fixed length); a_grav is added to dv/dt.
template <int D>
void HydroCpu<D>::self_gravity() {
  if constexpr (D == 3) {
    const std::size_t n = ps_.n;
    gravity_.compute(ps_.x.data(), ps_.m.data(), ps_.h.data(), n, ps_.a_grav.data(), ps_.phi.data());
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) ps_.dvdt[a] += ps_.a_grav[a];
  }
}

template <int D>
void HydroCpu<D>::evaluate() {
  ++evaluations_;
  if (summation_) summation_density_and_h();
  else h_from_continuity_density();
  {
    const ScopedSeconds timer(phases_.eos);
    equation_of_state();
    if (plasticity_) plastic_return(false);
  }
  const ScopedSeconds timer(phases_.forces);
  if (wall_extrapolation_) wall_extrapolation();
  if (solid_) solid_rates();  // the feature set is fixed for the run
  else rates();
  if (gravity_.enabled()) self_gravity();
  if (body_force_) body_force();
  if (!ps_.boundary.empty()) hold_boundaries();
  if (xsph_epsilon_ > Real(0)) xsph_velocity();
}

template <int D>
void HydroCpu<D>::evaluate_staggered(Real dt) {
  struct Reset {
    Real& v;
    ~Reset() { v = Real(0); }
  } reset{stagger_dt_};
  stagger_dt_ = solid_ ? dt : Real(0);
  evaluate();
}

template <int D>
Real HydroCpu<D>::dt_limit() {
  const std::size_t n = ps_.n;
  const RhsContext<D> c = context();
  Real dt = Real(1e30);
#pragma omp parallel for reduction(min : dt) if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) dt = std::min(dt, dt_limit_particle<D>(c, static_cast<std::uint32_t>(a)));
  return dt;
}

template class HydroCpu<1>;
template class HydroCpu<2>;
template class HydroCpu<3>;

}  // namespace rubble
