// Unit tests of the hydrodynamic physics functions (rubble/physics/):
// ideal-gas EOS, artificial viscosity, smoothing length, and the pair
// interaction's conservation properties.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/artificial_conductivity.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/hydro.hpp"
#include "rubble/physics/smoothing_length.hpp"
#include "rubble/physics/timestep.hpp"

using namespace rubble;

// Tolerances scale with the precision of Real (double by default; the float
// build runs the same tests): round-off bounds in units of epsilon, and
// central differences with step eps^(1/3), accurate to ~eps^(2/3).
namespace {
const double kEps = std::numeric_limits<Real>::epsilon();
const double kFdStep = std::cbrt(kEps);
const double kFdTol = 100 * std::pow(kEps, 2.0 / 3.0);
}  // namespace

// c^2 = dp/drho|_u + (p/rho^2) dp/du|_rho (PHYSICS.md §3), by central
// differences (step and bound: see kFdStep, kFdTol).
TEST(IdealGas, SoundSpeedMatchesFiniteDifferences) {
  EosParams e;
  e.kind = EosKind::IdealGas;
  for (double gamma : {1.4, 5.0 / 3.0, 2.0}) {
    e.ideal_gas.gamma = gamma;
    for (double rho : {0.125, 1.0, 2700.0})
      for (double u : {1e-3, 2.5, 1e6}) {
        const double dr = kFdStep * rho, du = kFdStep * u;
        const double dpdrho = (eos_evaluate(e, rho + dr, u).p - eos_evaluate(e, rho - dr, u).p) / (2 * dr);
        const double dpdu = (eos_evaluate(e, rho, u + du).p - eos_evaluate(e, rho, u - du).p) / (2 * du);
        const EosState s = eos_evaluate(e, rho, u);
        const double c2_fd = dpdrho + s.p / (rho * rho) * dpdu;
        EXPECT_NEAR(s.c2, c2_fd, kFdTol * s.c2) << "gamma " << gamma << " rho " << rho << " u " << u;
        EXPECT_NEAR(eos_internal_energy_from_pressure(e, rho, s.p), u, 10 * kEps * u);
      }
  }
}

TEST(ArtificialViscosity, ActsOnlyOnApproachingPairs) {
  EXPECT_EQ(viscosity_mu(0.5, 1.0, 0.1), 0.0);   // receding
  EXPECT_EQ(viscosity_mu(0.0, 1.0, 0.1), 0.0);   // sliding
  const double mu = viscosity_mu(-0.5, 0.04, 0.1);
  EXPECT_NEAR(mu, 0.1 * -0.5 / (0.04 + 0.01 * 0.01), 10 * kEps);
  const ViscosityParams av{1.0, 2.0};
  // Pi = (-alpha c mu + beta mu^2)/rho > 0 for mu < 0
  EXPECT_NEAR(viscosity_pi(av, mu, 1.5, 2.0), (-1.0 * 1.5 * mu + 2.0 * mu * mu) / 2.0, 10 * kEps);
  EXPECT_GT(viscosity_pi(av, mu, 1.5, 2.0), 0.0);
}

// Price (2008) conductivity: v_sig^u = sqrt(|p_a - p_b|/rhobar), zero
// between equal pressures (a contact in pressure equilibrium is where it
// must act on u alone through the other pairs, and a uniform gas gets
// none); the pair term carries heat from the hotter particle to the colder
// (F_ab <= 0, so du_a/dt < 0 when u_a > u_b), is antisymmetric in (a, b),
// and is linear in alpha_u and in u_a - u_b.
TEST(ArtificialConductivity, SignalSpeedAndDirectionOfHeatFlow) {
  EXPECT_NEAR(conductivity_signal_speed(3.0, 1.0, 0.5), 2.0, 10 * kEps);
  EXPECT_NEAR(conductivity_signal_speed(1.0, 3.0, 0.5), 2.0, 10 * kEps);
  EXPECT_EQ(conductivity_signal_speed(2.0, 2.0, 0.5), 0.0);
  const double F = -0.7, rhobar = 1.3, vsig = 0.9;
  const double hot_to_cold = conductivity_dudt(1.0, vsig, 5.0, 2.0, rhobar, F);
  EXPECT_LT(hot_to_cold, 0.0);
  EXPECT_NEAR(hot_to_cold, 1.0 * vsig * 3.0 / rhobar * F, 10 * kEps);
  EXPECT_NEAR(conductivity_dudt(1.0, vsig, 2.0, 5.0, rhobar, F), -hot_to_cold, 10 * kEps);  // antisymmetric
  EXPECT_NEAR(conductivity_dudt(0.5, vsig, 5.0, 2.0, rhobar, F), 0.5 * hot_to_cold, 10 * kEps);
  EXPECT_EQ(conductivity_dudt(1.0, vsig, 2.0, 2.0, rhobar, F), 0.0);
}

TEST(SmoothingLength, DensityAndHAreInverse) {
  for (double hfact : {1.2, 2.4}) {
    EXPECT_NEAR(density_from_h<1>(hfact, 0.01, h_from_density<1>(hfact, 0.01, 3.0)), 3.0, 100 * kEps);
    EXPECT_NEAR(density_from_h<2>(hfact, 0.01, h_from_density<2>(hfact, 0.01, 3.0)), 3.0, 100 * kEps);
    EXPECT_NEAR(density_from_h<3>(hfact, 0.01, h_from_density<3>(hfact, 0.01, 3.0)), 3.0, 100 * kEps);
  }
}

// On a uniform 1-D lattice the Newton iteration for h converges to
// h = hfact dx, where the summed density is the lattice density to within
// the kernel's discretisation error, and Omega is close to 1.
TEST(SmoothingLength, NewtonIterationOnLattice) {
  const double dx = 0.01, m = 0.01, hfact = 2.4;  // rho = 1
  double h = 1.7 * hfact * dx;                     // poor start
  double rho = 0, dwdh = 0;
  for (int it = 0; it < 50; ++it) {
    rho = m * kernel_w<1>(KernelType::CubicSpline, 0.0, h);
    dwdh = m * kernel_dwdh<1>(KernelType::CubicSpline, 0.0, h);
    for (int b = 1; b < 20; ++b) {  // neighbours on both sides
      rho += 2 * m * kernel_w<1>(KernelType::CubicSpline, b * dx, h);
      dwdh += 2 * m * kernel_dwdh<1>(KernelType::CubicSpline, b * dx, h);
    }
    h = newton_h_step<1>(h, rho, dwdh, hfact, m);
  }
  EXPECT_NEAR(rho, density_from_h<1>(hfact, m, h), 1000 * kEps);  // consistent pair (h, rho)
  EXPECT_NEAR(rho, 1.0, 5e-3);      // lattice density (kernels.hpp: <= 4.5e-3)
  EXPECT_NEAR(h / dx, hfact, 0.02); // follows from the two above
  // Omega = 1 + h/(D rho) d(rho_sum)/dh, checked against a central
  // difference of the lattice sum.
  auto rho_sum = [&](double hh) {
    double r = m * kernel_w<1>(KernelType::CubicSpline, 0.0, hh);
    for (int b = 1; b < 20; ++b) r += 2 * m * kernel_w<1>(KernelType::CubicSpline, b * dx, hh);
    return r;
  };
  const double dh = kFdStep * h;
  const double omega_fd = 1 + h / rho * (rho_sum(h + dh) - rho_sum(h - dh)) / (2 * dh);
  EXPECT_NEAR(grad_h_omega<1>(h, rho, dwdh), omega_fd, kFdTol);
}

TEST(Timestep, CourantAndForceLimits) {
  // dt = C hM / (c + 1.2 (alpha c + beta mu))
  EXPECT_NEAR(courant_dt(0.3, 0.01, 2.0, 1.0, 2.0, 0.5), 0.3 * 0.01 / (2.0 + 0.6 * (2.0 + 1.0)), 10 * kEps);
  EXPECT_NEAR(force_dt(0.25, 0.01, 4.0), 0.25 * std::sqrt(0.01 / 4.0), 10 * kEps);
  EXPECT_GT(force_dt(0.25, 0.01, 0.0), 1e20);  // no force: no limit
}

// A random cloud of particles with random states: summed over all ordered
// pairs, the pair interaction must conserve linear momentum and total
// (kinetic + thermal) energy to round-off, whatever the states are, because
// the pair force is antisymmetric and du/dt is the matching work term.
// A particle with a random state in the unit box (ideal gas, gamma 1.4),
// h in [h_min, h_min + 0.4).
template <int D>
HydroParticle<D> random_particle(std::mt19937& gen, bool conductivity, double h_min) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  HydroParticle<D> p{};
  for (int k = 0; k < D; ++k) {
    p.x[k] = U(gen);
    p.v[k] = U(gen) - 0.5;
  }
  p.m = 0.5 + U(gen);
  p.rho = 0.5 + U(gen);
  p.u = 1 + U(gen);
  p.p = 0.4 * p.rho * p.u;
  p.h = h_min + 0.4 * U(gen);
  p.omega = 0.8 + 0.4 * U(gen);
  p.cs = std::sqrt(1.4 * 0.4 * p.u);
  p.av = {Real(0.5 + U(gen)), Real(1.0 + U(gen))};
  p.alpha_u = conductivity ? 0.5 + U(gen) : 0.0;
  return p;
}

template <int D>
void check_pair_conservation(bool conductivity) {
  std::mt19937 gen(42 + D);
  const int n = 60;
  std::vector<HydroParticle<D>> P(n);
  for (auto& p : P) p = random_particle<D>(gen, conductivity, 0.3);
  Vec<D> momentum = Vec<D>::zero();
  double energy = 0, scale = 0;
  for (int a = 0; a < n; ++a) {
    Vec<D> acc = Vec<D>::zero();
    double dudt = 0;
    for (int b = 0; b < n; ++b) {
      if (a == b) continue;
      const auto r = hydro_pair<D>(KernelType::CubicSpline, P[a], P[b], P[a].x - P[b].x);
      acc += r.dvdt;
      dudt += r.dudt;
    }
    momentum += P[a].m * acc;
    energy += P[a].m * (dot(P[a].v, acc) + dudt);
    scale += P[a].m * (norm(acc) * (1 + norm(P[a].v)) + std::fabs(dudt));
  }
  ASSERT_GT(scale, 1.0);  // the cloud interacts
  EXPECT_LT(norm(momentum), 500 * kEps * scale);  // ~1e-13 in double
  EXPECT_LT(std::fabs(energy), 500 * kEps * scale);
}

// The geometric pressure force (physics/hydro.hpp; continuity density, so
// symmetric gradients and Omega = 1): momentum and energy conserved by the
// pair sums like the standard form's; drho/dt is rho_a times the
// volume-weighted divergence and du/dt = p_a/rho_a^2 drho/dt pair by pair.
template <int D>
void check_geometric_conservation() {
  std::mt19937 gen(142 + D);
  const int n = 60;
  std::vector<HydroParticle<D>> P(n);
  for (auto& p : P) {
    p = random_particle<D>(gen, false, 0.3);
    p.omega = 1;
  }
  Vec<D> momentum = Vec<D>::zero();
  double energy = 0, scale = 0;
  for (int a = 0; a < n; ++a) {
    Vec<D> acc = Vec<D>::zero();
    double dudt = 0;
    for (int b = 0; b < n; ++b) {
      if (a == b) continue;
      const auto r = hydro_pair<D>(KernelType::CubicSpline, P[a], P[b], P[a].x - P[b].x, true, true);
      acc += r.dvdt;
      dudt += r.dudt;
      // the pressure part of du/dt is p/rho^2 drho/dt (viscosity off: Pi = 0 for receding pairs only)
      HydroParticle<D> qa = P[a], qb = P[b];
      qa.av = qb.av = ViscosityParams{Real(0), Real(0)};
      const auto r0 = hydro_pair<D>(KernelType::CubicSpline, qa, qb, qa.x - qb.x, true, true);
      EXPECT_NEAR(r0.dudt, qa.p / (qa.rho * qa.rho) * r0.drhodt, 100 * kEps * (std::fabs(r0.dudt) + 1e-300));
    }
    momentum += P[a].m * acc;
    energy += P[a].m * (dot(P[a].v, acc) + dudt);
    scale += P[a].m * (norm(acc) * (1 + norm(P[a].v)) + std::fabs(dudt));
  }
  ASSERT_GT(scale, 1.0);
  EXPECT_LT(norm(momentum), 500 * kEps * scale);
  EXPECT_LT(std::fabs(energy), 500 * kEps * scale);
}

TEST(HydroPairGeometric, ConservesMomentumAndEnergy) {
  check_geometric_conservation<1>();
  check_geometric_conservation<2>();
  check_geometric_conservation<3>();
}

TEST(HydroPairGeometric, IsTheStandardFormWhereTheDensitiesAreEqual) {
  std::mt19937 gen(3);
  for (int trial = 0; trial < 50; ++trial) {
    HydroParticle<3> a = random_particle<3>(gen, false, 0.4), b = random_particle<3>(gen, false, 0.4);
    a.omega = b.omega = 1;
    b.rho = a.rho;
    const auto std_form = hydro_pair<3>(KernelType::CubicSpline, a, b, a.x - b.x, true, false);
    const auto geo_form = hydro_pair<3>(KernelType::CubicSpline, a, b, a.x - b.x, true, true);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(geo_form.dvdt[k], std_form.dvdt[k], 100 * kEps * (norm(std_form.dvdt) + 1e-300));
    EXPECT_NEAR(geo_form.dudt, std_form.dudt, 100 * kEps * (std::fabs(std_form.dudt) + 1e-300));
    EXPECT_NEAR(geo_form.drhodt, std_form.drhodt, 100 * kEps * (std::fabs(std_form.drhodt) + 1e-300));
  }
}

// A contact discontinuity at rest: a 1-D lattice of uniform spacing, the
// left half 3x denser than the right (particle masses 3:1), uniform
// pressure. In equilibrium every acceleration vanishes. The geometric form
// has sum_b (m_b/rho_b) g_ab = dx sum_b g_ab = 0 on the uniform lattice, so
// it holds the jump to round-off; the standard form leaves the particles
// next to the jump a spurious push p sum_b m_b (1/rho_a^2 + 1/rho_b^2) g_ab,
// the force that spreads the layer boundaries of a planet
// (verification/layered_equilibrium/README.md).
TEST(HydroPairGeometric, HoldsADensityJumpUnderUniformPressure) {
  const double dx = 0.01, p = 1e5;
  std::vector<HydroParticle<1>> P;
  for (int i = -20; i < 20; ++i) {
    HydroParticle<1> q{};
    q.x[0] = (i + 0.5) * dx;
    q.rho = i < 0 ? 3000.0 : 1000.0;
    q.m = q.rho * dx;
    q.p = p;
    q.u = 1;
    q.h = 2.4 * dx;
    q.omega = 1;
    q.cs = 1000;
    q.av = {Real(1), Real(2)};
    P.push_back(q);
  }
  double worst_std = 0, worst_geo = 0;
  for (std::size_t a = 15; a < 25; ++a) {  // the particles within a support of the jump
    double acc_std = 0, acc_geo = 0;
    for (std::size_t b = 0; b < P.size(); ++b) {
      if (a == b) continue;
      acc_std += hydro_pair<1>(KernelType::CubicSpline, P[a], P[b], P[a].x - P[b].x, true, false).dvdt[0];
      acc_geo += hydro_pair<1>(KernelType::CubicSpline, P[a], P[b], P[a].x - P[b].x, true, true).dvdt[0];
    }
    worst_std = std::max(worst_std, std::fabs(acc_std));
    worst_geo = std::max(worst_geo, std::fabs(acc_geo));
  }
  const double scale = p / (1000.0 * dx);  // |grad p| / rho of a pressure jump of p over one spacing
  std::printf("largest acceleration next to the jump: standard %.3g, geometric %.3g (scale p/(rho dx) = %.3g)\n",
              worst_std, worst_geo, scale);
  EXPECT_GT(worst_std, 0.1 * scale);
  EXPECT_LT(worst_geo, 1e3 * kEps * scale);
}

TEST(HydroPair, ConservesMomentumAndEnergy1D) { check_pair_conservation<1>(false); }
TEST(HydroPair, ConservesMomentumAndEnergy2D) { check_pair_conservation<2>(false); }
TEST(HydroPair, ConservesMomentumAndEnergy3D) { check_pair_conservation<3>(true); }

// The CPU force loop computes each pair once and takes b's rates from the
// pair's shared terms (hydro_pair_rates_b). They must be exactly what the
// pair computed from b's side gives, bit for bit, for any pair: random
// states, h differing by up to 2x, both density forms (`symmetric`), with
// and without conductivity, pairs outside the supports included.
template <int D>
void check_two_sides_of_a_pair(bool symmetric, bool conductivity) {
  std::mt19937 gen(7 + D + 10 * symmetric + 100 * conductivity);
  auto particle = [&] { return random_particle<D>(gen, conductivity, 0.4); };
  int active = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const HydroParticle<D> a = particle(), b = particle();
    const Vec<D> dx = a.x - b.x;
    const HydroSide<D> sa = hydro_side<D>(KernelType::CubicSpline, a), sb = hydro_side<D>(KernelType::CubicSpline, b);
    const HydroPairTerms<D> t = hydro_pair_terms<D>(sa, sb, dx, symmetric);
    const HydroPairRates<D> ra = hydro_pair_rates_a<D>(t, sa, sb), rb = hydro_pair_rates_b<D>(t, sa, sb);
    const HydroPairRates<D> want_a = hydro_pair<D>(sa, hydro_side<D>(KernelType::CubicSpline, b, true), dx, symmetric);
    const HydroPairRates<D> want_b = hydro_pair<D>(sb, hydro_side<D>(KernelType::CubicSpline, a, true), -dx, symmetric);
    active += t.active;
    for (int k = 0; k < D; ++k) {
      EXPECT_EQ(ra.dvdt[k], want_a.dvdt[k]) << trial;
      EXPECT_EQ(rb.dvdt[k], want_b.dvdt[k]) << trial;
    }
    EXPECT_EQ(ra.dudt, want_a.dudt) << trial;
    EXPECT_EQ(rb.dudt, want_b.dudt) << trial;
    EXPECT_EQ(ra.drhodt, want_a.drhodt) << trial;
    EXPECT_EQ(rb.drhodt, want_b.drhodt) << trial;
    EXPECT_EQ(ra.mu, want_a.mu) << trial;
    EXPECT_EQ(rb.mu, want_b.mu) << trial;
  }
  EXPECT_GT(active, 50);   // many pairs interact ...
  EXPECT_LT(active, 400);  // ... and some lie outside both supports
}

TEST(HydroPair, BothSidesFromOneEvaluationAreThePairSeenFromEachSide) {
  for (bool symmetric : {false, true})
    for (bool conductivity : {false, true}) {
      check_two_sides_of_a_pair<1>(symmetric, conductivity);
      check_two_sides_of_a_pair<2>(symmetric, conductivity);
      check_two_sides_of_a_pair<3>(symmetric, conductivity);
    }
}

// Two particles at rest with equal pressure push each other apart along
// their separation, equally and oppositely.
TEST(HydroPair, PressurePushesApart) {
  HydroParticle<2> a{}, b{};
  a.x = Vec<2>{{0.0, 0.0}};
  b.x = Vec<2>{{0.3, 0.4}};
  a.v = b.v = Vec<2>::zero();
  a.m = b.m = 1;
  a.rho = b.rho = 1;
  a.p = b.p = 1;
  a.u = b.u = 2.5;
  a.h = b.h = 1;
  a.omega = b.omega = 1;
  a.cs = b.cs = 1;
  a.av = b.av = {1, 2};
  const auto ra = hydro_pair<2>(KernelType::WendlandC2, a, b, a.x - b.x);
  const auto rb = hydro_pair<2>(KernelType::WendlandC2, b, a, b.x - a.x);
  EXPECT_LT(dot(ra.dvdt, b.x - a.x), 0.0);  // a pushed away from b
  EXPECT_NEAR(ra.dvdt[0], -rb.dvdt[0], 10 * kEps);
  EXPECT_NEAR(ra.dvdt[1], -rb.dvdt[1], 10 * kEps);
  EXPECT_EQ(ra.mu, 0.0);                    // at rest: no viscosity
}

// Fields a hydro-only scene does not need are never allocated.
TEST(ParticleStore, AllocatesOnlyWhatTheSceneNeeds) {
  ParticleStore<2> ps;
  Features needs;
  needs.summation_density = true;
  ps.allocate(10, needs);
  const auto f = ps.allocated_fields();
  EXPECT_NE(std::find(f.begin(), f.end(), "omega"), f.end());
  EXPECT_EQ(std::find(f.begin(), f.end(), "drhodt"), f.end());

  ParticleStore<2> pc;
  Features cont;
  cont.continuity_density = true;
  pc.allocate(10, cont);
  const auto g = pc.allocated_fields();
  EXPECT_EQ(std::find(g.begin(), g.end(), "omega"), g.end());
  EXPECT_NE(std::find(g.begin(), g.end(), "drhodt"), g.end());
}

TEST(ParticleStore, PermuteMovesEveryField) {
  ParticleStore<1> ps;
  ps.allocate(3, Features{});
  for (int i = 0; i < 3; ++i) {
    ps.x[i][0] = i;
    ps.m[i] = 10 + i;
    ps.material_id[i] = i;
  }
  ps.permute({2, 0, 1});
  EXPECT_EQ(ps.x[0][0], 2);
  EXPECT_EQ(ps.m[1], 10);
  EXPECT_EQ(ps.material_id[2], 1);
}
