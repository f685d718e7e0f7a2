#include "hydro_cpu.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rubble/core/error.hpp"
#include "rubble/neighbors/spatial_order.hpp"
#include "rubble/physics/artificial_stress.hpp"
#include "rubble/physics/hydro.hpp"
#include "rubble/physics/jaumann_rate.hpp"
#include "rubble/physics/kernel_gradient_correction.hpp"
#include "rubble/physics/solid.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/smoothing_length.hpp"
#include "rubble/physics/timestep.hpp"
#include "rubble/physics/xsph.hpp"
#include "rubble/scene/materials.hpp"

namespace rubble {

std::vector<MaterialParams> material_params_from_scene(const Scene& scene) {
  std::vector<MaterialParams> out;
  for (const auto& m : scene.materials) {
    MaterialParams p{};
    p.eos = eos_params_from_material(m);  // EOS and its add-on options (issue #3)
    p.av = {Real(m.viscosity.alpha), Real(m.viscosity.beta)};
    p.alpha_u = m.conductivity.enabled ? Real(m.conductivity.alpha_u) : Real(0);
    p.shear_modulus = Real(m.shear_modulus);
    const bool as = m.artificial_stress.enabled && m.shear_modulus > 0;
    p.as_epsilon = as ? Real(m.artificial_stress.epsilon) : Real(0);
    p.as_exponent = as ? Real(m.artificial_stress.n) : Real(0);
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
      summation_(scene.simulation.density == DensityForm::Summation),
      gravity_(scene.gravity, scene.simulation.kernel) {
  if (gravity_.enabled() && (D != 3 || ps_.a_grav.size() != ps_.n || ps_.phi.size() != ps_.n))
    throw RunError("self-gravity needs a 3-D scene with the a_grav and phi fields allocated");
  for (const MaterialParams& m : materials_) {
    solid_ = solid_ || m.shear_modulus > Real(0);
    artificial_stress_ = artificial_stress_ || m.as_exponent > Real(0);
  }
  if (solid_) {
    if (summation_ || ps_.S.size() != ps_.n || ps_.dSdt.size() != ps_.n)
      throw RunError("solids need continuity density with the S and dSdt fields allocated");
    kernel_correction_ = scene.simulation.kernel_correction;
    grad_v_.assign(ps_.n, Mat<D>::zero());
    if (artificial_stress_) art_R_.assign(ps_.n, Mat<D>::zero());
  }
  xsph_epsilon_ = Real(scene.simulation.xsph);
  if (xsph_epsilon_ > Real(0) && ps_.xsph_v.size() != ps_.n)
    throw RunError("XSPH needs the xsph_v field allocated");
}

template <int D>
void HydroCpu<D>::sort_particles() {
  const Box<D> box = bounding_box<D>(ps_.x.data(), ps_.n, domain_);
  ps_.permute(spatial_sort_permutation<D>(ps_.x.data(), ps_.n, box));
}

template <int D>
void HydroCpu<D>::build_neighbors(const std::vector<Real>& search_radius) {
  const Box<D> box = bounding_box<D>(ps_.x.data(), ps_.n, domain_);
  try {
    cells_.build(ps_.x.data(), search_radius.data(), ps_.n, box);
  } catch (const std::invalid_argument& e) {
    // e.g. a smoothing length that grew past half a periodic length
    throw RunError(e.what());
  }
  cells_.find_neighbors(nbrs_);
  ++rebuilds_;
}

// Summation density with h and rho solved together (smoothing_length.hpp).
// The neighbour lists are built with a search radius 15 % above the current
// h; a particle whose h grows past its search radius triggers a rebuild.
template <int D>
void HydroCpu<D>::summation_density_and_h() {
  const std::size_t n = ps_.n;
  constexpr Real kSkin = Real(1.15);
  constexpr int kMaxNewton = 50;
  const Real tol = sizeof(Real) == 8 ? Real(1e-10) : Real(1e-5);
  search_radius_.resize(n);
  for (std::size_t i = 0; i < n; ++i) search_radius_[i] = kSkin * ps_.h[i];

  for (int attempt = 0; attempt < 8; ++attempt) {
    build_neighbors(search_radius_);
    int outgrown = 0;
#pragma omp parallel reduction(+ : outgrown)
    {
      std::vector<Real> r_nb;  // neighbour distances and masses, gathered once
      std::vector<Real> m_nb;
#pragma omp for schedule(dynamic, 256)
      for (std::size_t a = 0; a < n; ++a) {
        r_nb.clear();
        m_nb.clear();
        for (std::uint32_t k = nbrs_.offset[a]; k < nbrs_.offset[a + 1]; ++k) {
          const std::uint32_t b = nbrs_.index[k];
          r_nb.push_back(norm(domain_.separation(ps_.x[a], ps_.x[b])));
          m_nb.push_back(ps_.m[b]);
        }
        // rho(h) and sum_b m_b dW/dh at h, self term included
        auto sums = [&](Real h, Real& rho, Real& dwdh) {
          rho = ps_.m[a] * kernel_w<D>(kernel_, Real(0), h);
          dwdh = ps_.m[a] * kernel_dwdh<D>(kernel_, Real(0), h);
          for (std::size_t k = 0; k < r_nb.size(); ++k) {
            if (r_nb[k] >= h) continue;
            rho += m_nb[k] * kernel_w<D>(kernel_, r_nb[k], h);
            dwdh += m_nb[k] * kernel_dwdh<D>(kernel_, r_nb[k], h);
          }
        };
        Real h = std::min(ps_.h[a], search_radius_[a]);
        Real rho = 0, dwdh = 0;
        bool converged = false;
        for (int it = 0; it < kMaxNewton && !converged; ++it) {
          sums(h, rho, dwdh);
          const Real h_new = newton_h_step<D>(h, rho, dwdh, hfact_, ps_.m[a]);
          converged = std::fabs(h_new - h) <= tol * h;
          h = h_new;
          if (h > search_radius_[a]) break;  // needs more neighbours than listed
        }
        if (h > search_radius_[a]) {
          search_radius_[a] = kSkin * h;
          ps_.h[a] = h;
          ++outgrown;
          continue;
        }
        sums(h, rho, dwdh);  // density and Omega at the converged h
        ps_.h[a] = h;
        ps_.rho[a] = rho;
        ps_.omega[a] = grad_h_omega<D>(h, rho, dwdh);
      }
    }
    // The force loop needs all pairs within max(h_a, h_b): the lists hold
    // all pairs within max(search_a, search_b), which is at least that.
    if (outgrown == 0) return;
  }
  throw RunError("smoothing-length iteration did not settle after 8 neighbour rebuilds");
}

template <int D>
void HydroCpu<D>::h_from_continuity_density() {
  const std::size_t n = ps_.n;
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) ps_.h[a] = h_from_density<D>(hfact_, ps_.m[a], ps_.rho[a]);
  build_neighbors(ps_.h);
}

template <int D>
void HydroCpu<D>::equation_of_state() {
  const std::size_t n = ps_.n;
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) {
    const EosState s = eos_evaluate(materials_[ps_.material_id[a]].eos, ps_.rho[a], ps_.u[a]);
    ps_.p[a] = s.p;
    ps_.cs[a] = std::sqrt(std::max(s.c2, Real(0)));
  }
}

template <int D>
void HydroCpu<D>::rates() {
  const std::size_t n = ps_.n;
  auto particle = [&](std::size_t i) {
    const MaterialParams& mat = materials_[ps_.material_id[i]];
    return HydroParticle<D>{ps_.x[i], ps_.v[i], ps_.m[i], ps_.rho[i], ps_.p[i], ps_.u[i], ps_.h[i],
                            summation_ ? ps_.omega[i] : Real(1), ps_.cs[i], mat.av, mat.alpha_u};
  };
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    const HydroParticle<D> pa = particle(a);
    Vec<D> dvdt = Vec<D>::zero();
    Real dudt = 0, drhodt = 0, mu_max = 0;
    for (std::uint32_t k = nbrs_.offset[a]; k < nbrs_.offset[a + 1]; ++k) {
      const std::uint32_t b = nbrs_.index[k];
      const HydroPairRates<D> r = hydro_pair<D>(kernel_, pa, particle(b), domain_.separation(ps_.x[a], ps_.x[b]), !summation_);
      dvdt += r.dvdt;
      dudt += r.dudt;
      drhodt += r.drhodt;
      mu_max = std::max(mu_max, r.mu);
    }
    ps_.dvdt[a] = dvdt;
    ps_.dudt[a] = dudt;
    if (!summation_) ps_.drhodt[a] = drhodt;
    ps_.mu_max[a] = mu_max;
  }
}

// Feature set Solid (any material with a shear modulus; continuity density).
// Pass 1, per particle: the velocity gradient L_a (optionally with the
// kernel-gradient correction), the Jaumann stress rate and the artificial
// stress tensor R_a. Pass 2, per pair: solid_pair (full stress).
template <int D>
void HydroCpu<D>::solid_rates() {
  const std::size_t n = ps_.n;
  std::int64_t fallbacks = 0;
  constexpr Real kMinDet = Real(1e-3);  // kernel_gradient_correction.hpp
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : fallbacks)
  for (std::size_t a = 0; a < n; ++a) {
    Mat<D> L = Mat<D>::zero(), M = Mat<D>::zero();
    for (std::uint32_t k = nbrs_.offset[a]; k < nbrs_.offset[a + 1]; ++k) {
      const std::uint32_t b = nbrs_.index[k];
      const Vec<D> dx = domain_.separation(ps_.x[a], ps_.x[b]);
      const Real r = norm(dx);
      if (r <= Real(0) || (r >= ps_.h[a] && r >= ps_.h[b])) continue;
      const Vec<D> g = Real(0.5) * (kernel_grad<D>(kernel_, dx, ps_.h[a]) + kernel_grad<D>(kernel_, dx, ps_.h[b]));
      L += velocity_gradient_pair_term<D>(ps_.m[b], ps_.rho[b], ps_.v[b] - ps_.v[a], g);
      if (kernel_correction_) M += correction_pair_term<D>(ps_.m[b], ps_.rho[b], -dx, g);
    }
    if (kernel_correction_) {
      Mat<D> C;
      if (!correction_matrix<D>(M, kMinDet, C)) ++fallbacks;
      L = L * C;  // M is symmetric for radial kernels, so C^T = C
    }
    grad_v_[a] = L;
    const MaterialParams& mat = materials_[ps_.material_id[a]];
    ps_.dSdt[a] = mat.shear_modulus > Real(0) ? deviatoric_stress_rate<D>(ps_.S[a], L, mat.shear_modulus)
                                              : Mat<D>::zero();
    if (artificial_stress_) {
      Mat<D> sigma = ps_.S[a];
      for (int i = 0; i < D; ++i) sigma.m[i][i] -= ps_.p[a];
      art_R_[a] = mat.as_exponent > Real(0) ? artificial_stress_tensor<D>(sigma, ps_.rho[a], mat.as_epsilon)
                                            : Mat<D>::zero();
    }
  }
  fallbacks_last_ = fallbacks;
  fallbacks_total_ += fallbacks;

  auto particle = [&](std::size_t i) {
    const MaterialParams& mat = materials_[ps_.material_id[i]];
    return SolidParticle<D>{ps_.x[i],   ps_.v[i],  ps_.m[i],  ps_.rho[i],
                            ps_.p[i],   ps_.h[i],  ps_.cs[i], ps_.S[i],
                            artificial_stress_ ? art_R_[i] : Mat<D>::zero(),
                            mat.av,     mat.dp,    mat.as_exponent};
  };
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    const SolidParticle<D> pa = particle(a);
    Vec<D> dvdt = Vec<D>::zero();
    Real dudt = 0, drhodt = 0, mu_max = 0;
    for (std::uint32_t k = nbrs_.offset[a]; k < nbrs_.offset[a + 1]; ++k) {
      const std::uint32_t b = nbrs_.index[k];
      const SolidPairRates<D> r = solid_pair<D>(kernel_, pa, particle(b), domain_.separation(ps_.x[a], ps_.x[b]));
      dvdt += r.dvdt;
      dudt += r.dudt;
      drhodt += r.drhodt;
      mu_max = std::max(mu_max, r.mu);
    }
    ps_.dvdt[a] = dvdt;
    ps_.dudt[a] = dudt;
    ps_.drhodt[a] = drhodt;
    ps_.mu_max[a] = mu_max;
  }
}

// XSPH: the smoothed-velocity correction to dx/dt (physics/xsph.hpp).
// Boundary particles move with their own velocity (no correction).
template <int D>
void HydroCpu<D>::xsph_velocity() {
  const std::size_t n = ps_.n;
  const bool has_boundary = !ps_.boundary.empty();
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t a = 0; a < n; ++a) {
    Vec<D> sum = Vec<D>::zero();
    if (!(has_boundary && ps_.boundary[a])) {
      for (std::uint32_t k = nbrs_.offset[a]; k < nbrs_.offset[a + 1]; ++k) {
        const std::uint32_t b = nbrs_.index[k];
        // velocity is smoothed within a material only, not across an
        // interface between bodies of different materials (contact)
        if (ps_.material_id[b] != ps_.material_id[a]) continue;
        const Real r = norm(domain_.separation(ps_.x[a], ps_.x[b]));
        const Real w = Real(0.5) * (kernel_w<D>(kernel_, r, ps_.h[a]) + kernel_w<D>(kernel_, r, ps_.h[b]));
        if (w > Real(0)) sum += xsph_pair_term<D>(ps_.m[b], ps_.rho[a], ps_.rho[b], ps_.v[b] - ps_.v[a], w);
      }
    }
    ps_.xsph_v[a] = xsph_epsilon_ * sum;
  }
}

// Boundary particles are not integrated: their rates are zero, so they keep
// their velocity (0 when fixed) and state, and move with it.
template <int D>
void HydroCpu<D>::hold_boundaries() {
  const std::size_t n = ps_.n;
#pragma omp parallel for if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) {
    if (!ps_.boundary[a]) continue;
    ps_.dvdt[a] = Vec<D>::zero();
    ps_.dudt[a] = 0;
    if (!ps_.drhodt.empty()) ps_.drhodt[a] = 0;
    if (!ps_.dSdt.empty()) ps_.dSdt[a] = Mat<D>::zero();
  }
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
  equation_of_state();
  if (solid_) solid_rates();  // the feature set is fixed for the run
  else rates();
  if (gravity_.enabled()) self_gravity();
  if (!ps_.boundary.empty()) hold_boundaries();
  if (xsph_epsilon_ > Real(0)) xsph_velocity();
}

template <int D>
Real HydroCpu<D>::dt_limit() const {
  const std::size_t n = ps_.n;
  Real dt = Real(1e30);
#pragma omp parallel for reduction(min : dt) if (n > 4096)
  for (std::size_t a = 0; a < n; ++a) {
    const MaterialParams& mat = materials_[ps_.material_id[a]];
    const Real hM = monaghan_h(ps_.h[a]);
    // solids: the longitudinal wave speed sqrt(c^2 + 4 mu / (3 rho))
    const Real c = mat.shear_modulus > Real(0) ? elastic_signal_speed(ps_.cs[a], mat.shear_modulus, ps_.rho[a])
                                               : ps_.cs[a];
    const Real dt_c = courant_dt(courant_, hM, c, mat.av.alpha, mat.av.beta, ps_.mu_max[a]);
    const Real dt_f = force_dt(force_factor_, hM, norm(ps_.dvdt[a]));
    dt = std::min(dt, std::min(dt_c, dt_f));
  }
  return dt;
}

template class HydroCpu<1>;
template class HydroCpu<2>;
template class HydroCpu<3>;

}  // namespace rubble
