#include "rubble/drivers/cpu_stepper.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "rubble/core/error.hpp"
#include "rubble/neighbors/spatial_order.hpp"
#include "rubble/physics/kernels.hpp"

namespace rubble {

// ---- CpuBackend -------------------------------------------------------------

template <int D>
CpuBackend<D>::CpuBackend(const RunPhysics& physics, ParticleStore<D>& ps, const Box<D>& domain)
    : HostLoops<D>(ps), ps_(ps), materials_(physics.materials), domain_(domain), gravity_(physics.gravity, physics.kernel) {
  require_fields<D>(physics.on, ps);
}

template <int D>
void CpuBackend<D>::sort(const Box<D>& domain) {
  const Box<D> box = bounding_box<D>(ps_.x.data(), ps_.n, domain);
  ps_.permute(spatial_sort_permutation<D>(ps_.x.data(), ps_.n, box));
  lists_in_order_ = false;  // the lists index the particles in the old order
}

template <int D>
void CpuBackend<D>::search(const Real* R, bool keepable) {
  const std::size_t n = ps_.n;
  if (keepable) {
    x_at_search_.resize(n);
#pragma omp parallel for if (n > 4096)
    for (std::size_t a = 0; a < n; ++a) x_at_search_[a] = ps_.x[a];
  }
  const Box<D> box = bounding_box<D>(ps_.x.data(), n, domain_);
  try {
    cells_.build(ps_.x.data(), R, n, box);
  } catch (const std::invalid_argument& e) {
    // e.g. a smoothing length that grew past half a periodic length
    throw RunError(std::string("the neighbour search failed (") + e.what() + ")");
  }
  cells_.find_neighbors(nbrs_);
  ++searches_;
  lists_in_order_ = keepable;
}

template <int D>
bool CpuBackend<D>::search_still_holds(const Real* R) const {
  const std::size_t n = ps_.n;
  if (!keep_lists_ || !lists_in_order_ || x_at_search_.size() != n) return false;
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
    if (!(ps_.h[a] + reach <= R[a])) ++broken;
  return broken == 0;
}

// Self-gravity (3-D only): direct summation or the octree (SelfGravity).
template <int D>
void CpuBackend<D>::self_gravity(const StoreView<D>& s) {
  if constexpr (D == 3) {
    gravity_.compute(s.x, s.m, s.h, ps_.n, s.a_grav, s.phi);
  } else {
    (void)s;
    throw RunError("self-gravity needs a 3-D scene");
  }
}

template <int D>
void CpuBackend<D>::release_work_memory() {
  nbrs_ = NeighborLists{};
  cells_ = CellList<D>{};
  std::vector<Vec<D>>().swap(x_at_search_);
  lists_in_order_ = false;
  std::vector<GradientSums<D>>().swap(grad_sums_);
  std::vector<Mat<D>>().swap(sd_sums_);
  this->release_integrator_scratch();
}

// The pair-once loops (hydro_pair_once, both solid passes): inside a parallel region, the
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
bool CpuBackend<D>::hydro_pair_once(const RhsContext<D>& c) {
  const std::size_t n = ps_.n;
  const StoreView<D>& s = c.s;
  if (s.wall_normal || s.dalphadt || s.dav_alpha_dt) return false;
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
      const HydroSide<D> sa = hydro_side<D>(c.kernel, hydro_particle<D>(c, ia), false, c.geometric_force);
      Vec<D> dvdt = Vec<D>::zero();
      Real dudt = 0, drhodt = 0, mu_max = 0;
      nbrs_.for_each(a, [&](std::uint32_t b) {
        const bool mine = b >= lo && b < hi;
        if (mine && b < a) return;  // done from b's side
        const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
        const Real h_max = sa.q.h > s.h[b] ? sa.q.h : s.h[b];
        if (norm2(dx) >= h_max * h_max) return;  // in the search skin only
        const HydroSide<D> sb = hydro_side<D>(c.kernel, hydro_particle<D>(c, b), !mine, c.geometric_force);
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
  return true;
}

// Feature set Solid (any material with a shear modulus; continuity density).
// Pass 1: the velocity gradient L_a (optionally with the kernel-gradient
// correction), the Jaumann stress rate and the artificial stress tensor
// R_a. Pass 2: the pair forces from the full stress (solid_pair). Both
// passes take each pair once within a thread's range, as hydro_pair_once does,
// except with free-slip walls (the gather loops the CUDA backend runs).
// Both passes divide by every neighbour's H (kernel) and pass 2 by its
// rho^2 (stress term): these inverses are taken once per particle first
// (solid_inverses; the same values as computed at each pair, so the
// results are bit for bit those of the per-pair form, which the CUDA
// backend keeps). Measured on the oscillating plate: see docs/performance.md.
template <int D>
bool CpuBackend<D>::solid_gradients_pair_once(const RhsContext<D>& c, unsigned long long* fallback_count) {
  // free-slip walls: the velocity seen of a wall particle depends on who looks
  if (c.s.wall_normal) return false;
  const std::size_t n = ps_.n;
  const StoreView<D>& s = c.s;
  unsigned long long fallbacks = 0;
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
  *fallback_count += fallbacks;
  return true;
}

template <int D>
bool CpuBackend<D>::solid_forces_pair_once(const RhsContext<D>& c) {
  if (c.s.wall_normal) return false;
  const std::size_t n = ps_.n;
  const StoreView<D>& s = c.s;
  // Pass 2 each pair once, as hydro_pair_once: a contiguous Morton range
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
        porosity_rates_particle<D>(c, static_cast<std::uint32_t>(a), s.drhodt[a], s.dudt[a]);
  }
  return true;
}

// ---- CpuStepper -------------------------------------------------------------

template <int D>
CpuStepper<D>::CpuStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain, bool resumed,
                          bool keep_lists)
    : ps_(ps), physics_(run_physics(scene)), backend_(physics_, ps, domain), steps_(physics_, backend_, domain) {
  backend_.keep_neighbour_lists(keep_lists);
  for (int k = 0; k < D; ++k) g_[k] = Real(scene.simulation.gravity[k]);
  if (resumed) return;
  steps_.sort_particles();
  steps_.evaluate();
}

template <int D>
void CpuStepper<D>::keep_good() {
  good_.n = ps_.n;
  for (const auto& f : field_table<D>())
    if (f.snapshot && f.role != FieldRole::Constant)
      std::visit([&](auto member) { good_.*member = ps_.*member; }, f.member);
}

template <int D>
const ParticleStore<D>& CpuStepper<D>::last_good() {
  for (const auto& f : field_table<D>())
    if (f.snapshot && f.role == FieldRole::Constant)
      std::visit([&](auto member) { good_.*member = ps_.*member; }, f.member);
  return good_;
}

template <int D>
void CpuStepper<D>::release_work_memory() {
  good_ = ParticleStore<D>{};
  steps_.release_work_memory();
  backend_.release_work_memory();
}

template class CpuBackend<1>;
template class CpuBackend<2>;
template class CpuBackend<3>;
template class CpuStepper<1>;
template class CpuStepper<2>;
template class CpuStepper<3>;

}  // namespace rubble
