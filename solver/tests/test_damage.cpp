// Tensile damage (issue #18 items 1-3; physics/damage.hpp, scene/flaws.hpp):
//  - the flaw draw follows the Weibull law: the weakest flaw of each
//    particle is Weibull-distributed with shape m and scale (k V_p)^(-1/m)
//    (V_p the particle's volume), fitted by maximum likelihood within the
//    fit's own statistical error; the number of flaws drawn is the
//    coupon-collector count N H_N within its spread; the draw is
//    reproducible and depends on the seed;
//  - the active-flaw count, the principal stress with the implied
//    out-of-plane components, and the growth law: under a constant strain
//    delta = D^(1/d) grows at n_act c_g / R_s, never passes its cap
//    (n_active/n_flaws)^(1/d) or 1, and never falls;
//  - a fully damaged particle transmits no tension (but compression), and
//    the acting stress is continuous in D;
//  - scene keys, defaults and errors; a scene without damage allocates no
//    damage field; a stretched block breaks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

#include "scene_error.hpp"
#include "rubble/core/error.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/flaws.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "rubble/scene/scene.hpp"

using namespace rubble;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Maximum-likelihood fit of F(x) = 1 - exp(-c x^m) to a sample: returns
// (m, c). m solves 1/m + mean(ln x) - sum(x^m ln x)/sum(x^m) = 0 (monotone
// in m: bisection), then c = n / sum(x^m). The sample is scaled by its
// median first (x = eps/eps_ref) so that x^m stays O(1).
struct WeibullFit {
  double m, c;
};
WeibullFit fit_weibull(std::vector<double> x) {
  std::vector<double> sorted = x;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double ref = sorted[sorted.size() / 2];
  double mean_log = 0;
  for (double& v : x) {
    v /= ref;
    mean_log += std::log(v);
  }
  mean_log /= double(x.size());
  auto g = [&](double m) {
    double s = 0, sl = 0;
    for (double v : x) {
      const double p = std::pow(v, m);
      s += p;
      sl += p * std::log(v);
    }
    return 1 / m + mean_log - sl / s;
  };
  double lo = 0.1, hi = 100;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (g(mid) > 0 ? lo : hi) = mid;
  }
  const double m = 0.5 * (lo + hi);
  double s = 0;
  for (double v : x) s += std::pow(v, m);
  const double c_scaled = double(x.size()) / s;  // c for x = eps/ref
  return {m, c_scaled * std::pow(ref, -m)};      // c for eps
}

// A one-particle 3-D store with the fields the damage loop bodies read.
struct OneParticle {
  std::vector<Real> m{1}, u{0}, rho{1}, h{1}, p{0}, cs{0}, damage_root{0}, ddamage{0}, eps_min{0}, eps_max{0},
      active{0};
  std::vector<std::int32_t> mat{0}, flaws{0};
  std::vector<Vec<3>> x{Vec<3>::zero()}, v{Vec<3>::zero()};
  std::vector<Mat<3>> S{Mat<3>::zero()};
  StoreView<3> view() {
    StoreView<3> s;
    s.n = 1;
    s.m = m.data(), s.u = u.data(), s.rho = rho.data(), s.h = h.data(), s.p = p.data(), s.cs = cs.data();
    s.material_id = mat.data(), s.x = x.data(), s.v = v.data(), s.S = S.data();
    s.damage_root = damage_root.data(), s.ddamage_root_dt = ddamage.data(), s.flaw_count = flaws.data();
    s.flaw_eps_min = eps_min.data(), s.flaw_eps_max = eps_max.data(), s.flaws_active = active.data();
    return s;
  }
};

// A linear-elastic solid (Murnaghan n = 1: p = K (rho/rho0 - 1)) with damage.
MaterialParams brittle(Real K, Real mu, Real rho0, Real m_weibull, bool deviatoric = true) {
  MaterialParams mp{};
  mp.eos.kind = EosKind::Murnaghan;
  mp.eos.murnaghan = MurnaghanParams{rho0, K, Real(1)};
  mp.shear_modulus = mu;
  mp.damage.enabled = true;
  mp.damage.weibull_k = Real(1e20);
  mp.damage.weibull_m = m_weibull;
  mp.damage.crack_speed = Real(0.4);
  mp.damage.deviatoric = deviatoric;
  return mp;
}

}  // namespace

// ---- the flaw draw ----------------------------------------------------------

TEST(WeibullFlaws, WeakestFlawPerParticleFollowsTheWeibullLaw) {
  // Particle i gets none of the flaws j <= J with probability (1 - 1/N)^J,
  // so P(eps_min > eps) = (1 - 1/N)^(k V eps^m) -> exp(-k V_p eps^m): a
  // Weibull law with shape m and c = k V_p, to O(1/N). The maximum-likelihood
  // estimates have the asymptotic standard deviations (Cohen 1965,
  // Technometrics 7:579; the Weibull Fisher information)
  //   sd(m_hat) = 0.7797 m / sqrt(N),  sd(lambda_hat)/lambda = 1.053 / (m sqrt(N))
  // for the scale lambda = c^(-1/m); the test allows 4 of them.
  for (const double m : {6.0, 9.0, 16.0}) {
    const std::size_t N = 40000;
    const double k = 4e35, volume = 1e-3;  // basalt-like k [m^-3], a 1-litre body
    const FlawSet f = draw_weibull_flaws(N, k, m, volume, 7, 0);
    const WeibullFit fit = fit_weibull(f.eps_min);
    const double c = k * volume / double(N);
    const double lambda = std::pow(c, -1 / m), lambda_hat = std::pow(fit.c, -1 / fit.m);
    const double sd_m = 0.7797 * m / std::sqrt(double(N));
    const double sd_lambda = 1.053 / (m * std::sqrt(double(N))) * lambda;
    EXPECT_NEAR(fit.m, m, 4 * sd_m) << "m = " << m;
    EXPECT_NEAR(lambda_hat, lambda, 4 * sd_lambda) << "m = " << m;
    // k itself, k_hat = lambda_hat^(-m_hat)/V_p: its error is dominated by
    // m_hat times ln(lambda) (k counts flaws at unit strain, far from the
    // data): |ln k_hat - ln k| <= 4 (|ln lambda| sd_m + m sd_lambda/lambda).
    const double k_hat = std::pow(lambda_hat, -fit.m) * double(N) / volume;
    EXPECT_NEAR(std::log(k_hat), std::log(k), 4 * (std::fabs(std::log(lambda)) * sd_m + m * sd_lambda / lambda))
        << "m = " << m;
    // every particle holds a flaw; the ends are ordered
    for (std::size_t i = 0; i < N; ++i) {
      ASSERT_GE(f.count[i], 1);
      ASSERT_LE(f.eps_min[i], f.eps_max[i]);
    }
  }
}

TEST(WeibullFlaws, NumberDrawnIsTheCouponCollectorCount) {
  // Flaws are drawn until every particle holds one: the count T has mean
  // N H_N (H_N the harmonic number, ~ ln N + 0.5772) and standard deviation
  // < pi N / sqrt(6) (the coupon collector's problem).
  for (const std::size_t N : {1000u, 100000u}) {
    const FlawSet f = draw_weibull_flaws(N, 1e30, 9, 1.0, 11, 3);
    double H = 0;
    for (std::size_t i = 1; i <= N; ++i) H += 1.0 / double(i);
    EXPECT_NEAR(double(f.total), double(N) * H, 4 * kPi * double(N) / std::sqrt(6.0)) << "N = " << N;
    EXPECT_EQ(std::accumulate(f.count.begin(), f.count.end(), std::int64_t(0)), f.total);
    // the largest threshold drawn is that of flaw T
    const double top = *std::max_element(f.eps_max.begin(), f.eps_max.end());
    EXPECT_DOUBLE_EQ(top, std::pow(double(f.total) / 1e30, 1.0 / 9));
  }
}

TEST(WeibullFlaws, AMinimumPerParticleDrawsFurtherUpTheSamePopulation) {
  // min_flaws_per_particle = M: the draw goes on until every particle holds
  // M flaws. Each particle's count is then >= M; the first flaws drawn are
  // those of the default draw (the same sequence, further continued), so the
  // weakest flaw of the body is unchanged; the total T is above N M, and
  // below N lambda where each particle's count (~ Poisson(lambda) after
  // N lambda draws) falls short of M with probability at most
  // exp(-(lambda - M)^2/(2 lambda)) (the Poisson lower-tail Chernoff bound),
  // summed over the N particles 0.01: (lambda - M)^2 = 2 lambda ln(100 N).
  // The largest threshold is that of flaw T.
  const std::size_t N = 2000;
  const FlawSet one = draw_weibull_flaws(N, 1e30, 9, 1.0, 5, 0), many = draw_weibull_flaws(N, 1e30, 9, 1.0, 5, 0, 50);
  EXPECT_EQ(draw_weibull_flaws(N, 1e30, 9, 1.0, 5, 0, 1).count, one.count);  // 1 is the default
  EXPECT_EQ(draw_weibull_flaws(N, 1e30, 9, 1.0, 5, 0, 0).count, one.count);  // below 1 counts as 1
  for (std::size_t i = 0; i < N; ++i) {
    ASSERT_GE(many.count[i], 50);
    EXPECT_EQ(many.eps_min[i], one.eps_min[i]);  // the same first flaw per particle
    EXPECT_GE(many.eps_max[i], one.eps_max[i]);
  }
  EXPECT_EQ(*std::min_element(many.eps_min.begin(), many.eps_min.end()), std::pow(1 / 1e30, 1.0 / 9));
  EXPECT_EQ(std::accumulate(many.count.begin(), many.count.end(), std::int64_t(0)), many.total);
  EXPECT_GT(double(many.total), 50.0 * double(N));
  const double M = 50, b = std::log(100.0 * double(N));
  const double lambda = M + b + std::sqrt(b * b + 2 * M * b);  // the root above M
  EXPECT_LT(double(many.total), double(N) * lambda);
  EXPECT_DOUBLE_EQ(*std::max_element(many.eps_max.begin(), many.eps_max.end()),
                   std::pow(double(many.total) / 1e30, 1.0 / 9));
}

TEST(WeibullFlaws, ReproducibleAndSeeded) {
  const FlawSet a = draw_weibull_flaws(5000, 1e30, 9, 1.0, 42, 1), b = draw_weibull_flaws(5000, 1e30, 9, 1.0, 42, 1);
  EXPECT_EQ(a.count, b.count);
  EXPECT_EQ(a.eps_min, b.eps_min);
  EXPECT_EQ(a.eps_max, b.eps_max);
  EXPECT_NE(draw_weibull_flaws(5000, 1e30, 9, 1.0, 43, 1).count, a.count);  // another seed
  EXPECT_NE(draw_weibull_flaws(5000, 1e30, 9, 1.0, 42, 2).count, a.count);  // another body
}

// ---- per-particle physics ------------------------------------------------------

TEST(DamagePhysics, ActiveFlawsExactAtTheEndsAndMonotone) {
  const Real m = 9, lo = Real(1e-4), hi = Real(3e-4);
  EXPECT_EQ(active_flaws(Real(0.99e-4), 5, lo, hi, m), 0);
  EXPECT_EQ(active_flaws(lo, 5, lo, hi, m), 1);
  EXPECT_EQ(active_flaws(hi, 5, lo, hi, m), 5);
  EXPECT_EQ(active_flaws(Real(1), 5, lo, hi, m), 5);
  EXPECT_EQ(active_flaws(Real(1), 0, 0, 0, m), 0);  // no flaws: never active
  EXPECT_EQ(active_flaws(lo, 1, lo, lo, m), 1);     // a single flaw
  EXPECT_EQ(active_flaws(Real(2e-4), 2, lo, hi, m), 1);  // two flaws: only the weakest below the strongest
  // linear in eps^m between the ends (the flaws' j are spread uniformly):
  // the weakest plus half of the 3 interior flaws halfway up
  const Real mid = std::pow(Real(0.5) * (std::pow(lo, m) + std::pow(hi, m)), 1 / m);
  EXPECT_NEAR(active_flaws(mid, 5, lo, hi, m), 2.5, 1e-12);
  Real last = 0;
  for (int i = 0; i <= 1000; ++i) {
    const Real n = active_flaws(lo * (1 + Real(3) * Real(i) / 1000), 5, lo, hi, m);
    EXPECT_GE(n, last);
    last = n;
  }
}

TEST(DamagePhysics, ActiveFlawsIsTheExpectedCountGivenTheEnds) {
  // A particle's flaws are a uniform random subset of the body's j, and
  // eps_j^m is proportional to j: in the variable y = eps^m the particle's
  // n_f activation points are (to the draw's granularity) independent and
  // uniform. Draw them, keep only the ends as rubble does, and compare the
  // mean of active_flaws at a fixed strain with the mean true count over the
  // draws whose ends bracket it (issue #49 item 5: 1 + (n_f - 2) x, not
  // 1 + (n_f - 1) x). The tolerance is 5 standard errors of the mean.
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> uni(0, 1);
  const Real m = 9;
  for (int n_f : {3, 5, 12}) {
    const double y = 0.5;  // the strain's eps^m
    const Real eps = std::pow(Real(y), 1 / m);
    double sum_true = 0, sum_model = 0, sum_d2 = 0;
    int used = 0;
    for (int draw = 0; draw < 40000; ++draw) {
      std::vector<double> pts(static_cast<std::size_t>(n_f));
      for (double& q : pts) q = uni(gen);
      const double lo = *std::min_element(pts.begin(), pts.end()), hi = *std::max_element(pts.begin(), pts.end());
      if (!(lo <= y && y < hi)) continue;
      const double truth = double(std::count_if(pts.begin(), pts.end(), [&](double q) { return q <= y; }));
      const double model =
          active_flaws(eps, n_f, std::pow(Real(lo), 1 / m), std::pow(Real(hi), 1 / m), m);
      sum_true += truth, sum_model += model, sum_d2 += (truth - model) * (truth - model);
      ++used;
    }
    ASSERT_GT(used, 1000);
    const double mean_diff = (sum_true - sum_model) / used;
    const double se = std::sqrt(sum_d2 / used / used);
    EXPECT_LT(std::fabs(mean_diff), 5 * se) << "n_f = " << n_f << ": mean true " << sum_true / used
                                            << ", mean model " << sum_model / used;
  }
}

TEST(DamagePhysics, LocalStrainOfTheActingStressOverTheIntactFraction) {
  // BA94 eq. 9: eps = sigma_t/((1 - D) E), sigma_t of the acting stress.
  const Real E = 100, Dmg = Real(0.5);
  Mat<3> S = Mat<3>::zero();
  S.m[0][0] = 3, S.m[1][1] = -1.5, S.m[2][2] = -1.5;
  // compression (p = 1 acts in full), deviator scaled by 1 - D: (1.5 - 1)/(0.5 E)
  EXPECT_DOUBLE_EQ(damage_local_strain<3>((1 - Dmg) * S, damaged_pressure(1.0, Dmg), Dmg, E), 0.01);
  // ... less than the intact stress's (3 - 1)/E: a compressed damaged particle needs more shear to crack
  EXPECT_LT(damage_local_strain<3>((1 - Dmg) * S, 1.0, Dmg, E), local_tensile_strain<3>(S, 1.0, E));
  // tension: (1 - D) p and (1 - D) S over (1 - D): the intact stress's strain
  EXPECT_DOUBLE_EQ(damage_local_strain<3>((1 - Dmg) * S, damaged_pressure(-1.0, Dmg), Dmg, E),
                   local_tensile_strain<3>(S, -1.0, E));
  // a deviator that damage spares enters as S/(1 - D): (3 + 0.5)/(0.5 E)
  EXPECT_DOUBLE_EQ(damage_local_strain<3>(S, damaged_pressure(-1.0, Dmg), Dmg, E), 0.07);
  // undamaged: the plain local strain; fully damaged: no further growth
  EXPECT_DOUBLE_EQ(damage_local_strain<3>(S, -1.0, 0.0, E), local_tensile_strain<3>(S, -1.0, E));
  EXPECT_EQ(damage_local_strain<3>(S, -1.0, 1.0, E), 0.0);
}

TEST(DamagePhysics, MaxPrincipalStressCountsTheImpliedComponents) {
  // 3-D: against the largest eigenvalue of a rotated diagonal tensor
  Mat<3> S = Mat<3>::zero();
  S.m[0][0] = 3, S.m[1][1] = -1, S.m[2][2] = -2;
  const double c = std::cos(0.3), s = std::sin(0.3);
  Mat<3> R = Mat<3>::identity();
  R.m[0][0] = c, R.m[0][1] = -s, R.m[1][0] = s, R.m[1][1] = c;
  const Mat<3> Sr = R * S * transpose(R);
  EXPECT_NEAR(max_principal_stress<3>(Sr, 0.5), 2.5, 1e-12);
  // 2-D plane strain: S_zz = -(S_xx + S_yy) can be the largest
  Mat<2> S2 = Mat<2>::zero();
  S2.m[0][0] = -2, S2.m[1][1] = -1;  // S_zz = 3
  EXPECT_DOUBLE_EQ(max_principal_stress<2>(S2, 1.0), 2.0);
  S2.m[0][0] = 1, S2.m[1][1] = -1, S2.m[0][1] = S2.m[1][0] = 1;  // in-plane sqrt(2), S_zz = 0
  EXPECT_NEAR(max_principal_stress<2>(S2, 0.0), std::sqrt(2.0), 1e-15);
  // 1-D uniaxial strain: S_yy = S_zz = -S_xx/2
  Mat<1> S1;
  S1.m[0][0] = -2;
  EXPECT_DOUBLE_EQ(max_principal_stress<1>(S1, -1.0), 2.0);
  S1.m[0][0] = 2;
  EXPECT_DOUBLE_EQ(max_principal_stress<1>(S1, -1.0), 3.0);
  // local strain: only tension counts
  EXPECT_DOUBLE_EQ(local_tensile_strain<1>(S1, 10.0, 100.0), 0.0);
  EXPECT_DOUBLE_EQ(local_tensile_strain<1>(S1, -1.0, 100.0), 0.03);
}

TEST(DamageGrowth, ConstantStrainRateCapAndNeverFalls) {
  // One 3-D particle held at a fixed hydrostatic tension (rho below rho0)
  // beyond its weakest flaw: delta grows at n_act c_g / R_s with c_g =
  // 0.4 c_l, R_s = (3 V_p/(4 pi))^(1/3), until its cap (n_act/n_f)^(1/3);
  // explicit Euler with the step limit is exact for a constant rate up to
  // the step that crosses the cap, where the end-of-step cap holds it.
  const Real K = Real(2e10), mu = Real(1e10), rho0 = 2700;
  const MaterialParams mat = brittle(K, mu, rho0, 9);
  OneParticle st;
  RhsContext<3> c;
  c.s = st.view();
  c.mat = &mat;
  st.m[0] = Real(2.7e-3);  // 1 cm^3 at rho0
  st.rho[0] = rho0 * Real(1 - 3e-4);
  // p = K (rho/rho0 - 1) = -6e6 Pa; E = 9 K mu/(3K + mu)
  const Real E = youngs_modulus(st.rho[0] * K / rho0, mu);  // K_eff = rho c^2, c^2 = K/rho0 (n = 1)
  const Real eps = Real(6e6) / E;
  st.flaws[0] = 4;
  st.eps_min[0] = eps * Real(0.5);
  st.eps_max[0] = eps * Real(2);  // eps^m lies between: n_act in (1, 4)
  const Real n_act = active_flaws(eps, 4, st.eps_min[0], st.eps_max[0], 9);
  ASSERT_GT(n_act, 1);
  ASSERT_LT(n_act, 4);
  const Real cl = std::sqrt(K / rho0 + Real(4) / 3 * mu / st.rho[0]);  // c_s^2 = K/rho0 for n = 1
  const Real R = std::cbrt(Real(3) * (st.m[0] / st.rho[0]) / (Real(4) * Real(kPi)));
  const Real rate = n_act * Real(0.4) * cl / R;
  const Real cap = std::cbrt(n_act / 4);
  eos_particle<3>(c, 0);
  EXPECT_NEAR(st.p[0], -6e6, 1e-3);
  Real t = 0, last = 0;
  bool capped = false;
  for (int step = 0; step < 100; ++step) {
    const Real r = damage_rate_particle<3>(c, 0);
    if (!capped) {
      EXPECT_NEAR(r, rate, 1e-12 * rate) << "step " << step;
    }
    const Real dt = Real(0.5) * damage_dt_limit(r, kDamageStepChange);  // within the limit
    st.damage_root[0] = integrated_damage_root(st.damage_root[0], r > 0 ? dt : 0, r);
    damage_end_step_particle<3>(c, 0);
    t += r > 0 ? dt : 0;
    EXPECT_LE(st.damage_root[0], cap * (1 + 1e-15));
    EXPECT_LE(st.damage_root[0], 1);
    EXPECT_GE(st.damage_root[0], last);  // never falls
    if (st.damage_root[0] < cap * (1 - 1e-12)) {
      EXPECT_NEAR(st.damage_root[0], rate * t, 1e-12);
    } else {
      capped = true;
    }
    last = st.damage_root[0];
    EXPECT_NEAR(st.active[0], n_act, 1e-12);
  }
  EXPECT_TRUE(capped);
  EXPECT_EQ(damage_rate_particle<3>(c, 0), 0);  // at the cap: no growth
  // unloading (compression) stops the growth and keeps delta and the record
  st.rho[0] = rho0 * Real(1 + 1e-4);
  EXPECT_EQ(damage_rate_particle<3>(c, 0), 0);
  damage_end_step_particle<3>(c, 0);
  EXPECT_EQ(st.damage_root[0], last);
  EXPECT_NEAR(st.active[0], n_act, 1e-12);
  // more strain activates all four flaws: the cap becomes 1 and growth resumes
  st.rho[0] = rho0 * Real(1 - 3e-3);
  EXPECT_GT(damage_rate_particle<3>(c, 0), 0);
  for (int step = 0; step < 200; ++step) {
    const Real r = damage_rate_particle<3>(c, 0);
    st.damage_root[0] = integrated_damage_root(st.damage_root[0], damage_dt_limit(r, kDamageStepChange), r);
    damage_end_step_particle<3>(c, 0);
    EXPECT_LE(st.damage_root[0], 1);
  }
  EXPECT_EQ(st.damage_root[0], 1);
  EXPECT_EQ(st.active[0], 4);
}

TEST(DamageGrowth, CrackLengthKernelSupportGrowsOverTheSupportRadius) {
  // crack_length = "kernel_support" (miluphcuda, Spheral): d delta/dt =
  // n_act c_g / H with H the particle's support radius, in place of R_s.
  const Real K = Real(2e10), mu = Real(1e10), rho0 = 2700;
  MaterialParams mat = brittle(K, mu, rho0, 9);
  OneParticle st;
  RhsContext<3> c;
  c.s = st.view();
  c.mat = &mat;
  st.m[0] = Real(2.7e-3);
  st.rho[0] = rho0 * Real(1 - 3e-4);  // p = -6e6 Pa
  st.h[0] = Real(0.031);
  const Real eps = Real(6e6) / youngs_modulus(st.rho[0] * K / rho0, mu);
  st.flaws[0] = 4;
  st.eps_min[0] = eps * Real(0.5);
  st.eps_max[0] = eps * Real(2);
  eos_particle<3>(c, 0);
  const Real radius_rate = damage_rate_particle<3>(c, 0);
  mat.damage.crack_length = CrackLength::KernelSupport;
  const Real support_rate = damage_rate_particle<3>(c, 0);
  const Real R = std::cbrt(Real(3) * (st.m[0] / st.rho[0]) / (Real(4) * Real(kPi)));
  ASSERT_GT(radius_rate, 0);
  EXPECT_NEAR(support_rate / radius_rate, R / st.h[0], 1e-12);
}

TEST(DamageGrowth, WithoutTheCapAParticleBreaksOnItsFirstFlaws) {
  // cap = "none": the same particle as above grows at n_act c_g / R_s past
  // (n_act/n_f)^(1/3) up to 1, with only some of its flaws active; the cap
  // functions give 1 once a flaw has been active (0 before).
  const Real K = Real(2e10), mu = Real(1e10), rho0 = 2700;
  MaterialParams mat = brittle(K, mu, rho0, 9);
  mat.damage.capped = false;
  OneParticle st;
  RhsContext<3> c;
  c.s = st.view();
  c.mat = &mat;
  st.m[0] = Real(2.7e-3);
  st.rho[0] = rho0 * Real(1 - 3e-4);
  const Real E = youngs_modulus(st.rho[0] * K / rho0, mu);
  const Real eps = Real(6e6) / E;
  st.flaws[0] = 4;
  st.eps_min[0] = eps * Real(0.5);
  st.eps_max[0] = eps * Real(2);
  const Real n_act = active_flaws(eps, 4, st.eps_min[0], st.eps_max[0], 9);
  ASSERT_LT(n_act, 4);
  EXPECT_EQ(damage_root_cap<3>(0, 4, false), 0);
  EXPECT_EQ(damage_root_cap<3>(n_act, 4, false), 1);
  EXPECT_LT(damage_root_cap<3>(n_act, 4, true), 1);
  eos_particle<3>(c, 0);
  const Real rate = damage_rate_particle<3>(c, 0);
  ASSERT_GT(rate, 0);
  Real t = 0;
  int steps = 0;
  while (st.damage_root[0] < 1 && steps < 1000) {
    const Real r = damage_rate_particle<3>(c, 0);
    EXPECT_EQ(r, rate);  // constant up to 1: no cap
    const Real dt = damage_dt_limit(r, kDamageStepChange);
    st.damage_root[0] = integrated_damage_root(st.damage_root[0], dt, r);
    damage_end_step_particle<3>(c, 0);
    t += dt;
    ++steps;
  }
  EXPECT_EQ(st.damage_root[0], 1);
  // broken after 1/rate = R_s/(n_act c_g), to within the last step (which
  // the clamp at 1 ends early)
  EXPECT_NEAR(t, 1 / rate, kDamageStepChange / rate * (1 + 1e-9));
  EXPECT_NEAR(st.active[0], n_act, 1e-12);  // with only n_act < n_f flaws active
  EXPECT_EQ(damage_rate_particle<3>(c, 0), 0);  // at 1: no growth
}

TEST(DamagedStress, CourantStepUsesTheShearModulusThatActs) {
  // Issue #49 item 6: the Courant signal speed is sqrt(c^2 + 4 (1 - D) mu/(3 rho)):
  // a fully damaged particle (deviator acting as (1 - D) S = 0) steps at its
  // sound speed, an intact one at the longitudinal speed; with damage that
  // spares the deviator the full modulus stays.
  const Real K = Real(2e10), mu = Real(3e10), rho0 = 2700;
  MaterialParams mat = brittle(K, mu, rho0, 9);
  OneParticle st;
  std::vector<Real> mu_max{0};
  std::vector<Vec<3>> dvdt{Vec<3>::zero()};
  RhsContext<3> c;
  c.s = st.view();
  c.s.mu_max = mu_max.data(), c.s.dvdt = dvdt.data();
  c.mat = &mat;
  c.courant = Real(0.3), c.force_factor = Real(0.25);
  st.m[0] = Real(2.7e-3), st.rho[0] = rho0, st.h[0] = Real(0.02);
  eos_particle<3>(c, 0);
  const Real cs = st.cs[0];
  const Real hM = monaghan_h<3>(c.kernel, st.h[0]);
  auto expected = [&](Real mu_acting) {
    return courant_dt(c.courant, hM, elastic_signal_speed(cs, mu_acting, rho0), mat.av.alpha, mat.av.beta, 0);
  };
  EXPECT_DOUBLE_EQ(dt_limit_particle<3>(c, 0), expected(mu));
  st.damage_root[0] = 1;
  EXPECT_DOUBLE_EQ(dt_limit_particle<3>(c, 0), expected(0));
  EXPECT_GT(dt_limit_particle<3>(c, 0) / expected(mu), 1.5);  // c_l/c_s = sqrt(1 + 4 mu/(3 K)) = 2.45
  st.damage_root[0] = Real(0.5);  // D = 1/8 in 3-D
  EXPECT_DOUBLE_EQ(dt_limit_particle<3>(c, 0), expected(Real(7) / 8 * mu));
  mat.damage.deviatoric = false;
  EXPECT_DOUBLE_EQ(dt_limit_particle<3>(c, 0), expected(mu));
}

TEST(DamagedStress, FullyDamagedParticlesTransmitNoTension) {
  // Two 2-D particles of a damaged material at rest (no viscosity): the
  // pair force of solid_pair from the acting stress (eos_particle,
  // deviatoric_factor_particle via solid_particle). Intact: a tension pulls
  // them together. D = 1: no force in tension; a compression still pushes.
  const Real K = 1, mu = Real(0.5), rho0 = 1;
  const MaterialParams mat = brittle(K, mu, rho0, 9);
  std::vector<Real> m(2, Real(0.01)), u(2, 0), rho(2, Real(0.99)), h(2, Real(0.25)), p(2, 0), cs(2, 0), dr(2, 0),
      dd(2, 0), emin(2, 1), emax(2, 1), act(2, 0);
  std::vector<std::int32_t> mid(2, 0), nf(2, 1);
  std::vector<Vec<2>> x(2, Vec<2>::zero()), v(2, Vec<2>::zero());
  x[1][0] = Real(0.1);
  std::vector<Mat<2>> S(2, Mat<2>::zero());
  S[0].m[0][0] = S[1].m[0][0] = Real(0.02), S[0].m[1][1] = S[1].m[1][1] = Real(-0.02);
  StoreView<2> s;
  s.n = 2, s.m = m.data(), s.u = u.data(), s.rho = rho.data(), s.h = h.data(), s.p = p.data(), s.cs = cs.data();
  s.material_id = mid.data(), s.x = x.data(), s.v = v.data(), s.S = S.data(), s.damage_root = dr.data();
  s.ddamage_root_dt = dd.data(), s.flaw_count = nf.data(), s.flaw_eps_min = emin.data(), s.flaw_eps_max = emax.data();
  s.flaws_active = act.data();
  RhsContext<2> c;
  c.s = s;
  c.mat = &mat;
  c.kernel = KernelType::CubicSpline;
  auto force = [&](Real delta) {
    dr[0] = dr[1] = delta;
    eos_particle<2>(c, 0), eos_particle<2>(c, 1);
    return solid_pair<2>(c.kernel, solid_particle<2>(c, 0), solid_particle<2>(c, 1), x[0] - x[1]).dvdt[0];
  };
  const Real intact = force(0);
  EXPECT_GT(intact, 0);  // tension: a is pulled towards b (+x)
  EXPECT_EQ(force(1), 0);
  EXPECT_EQ(p[0], 0);  // the acting pressure
  // continuous in D: linear for a tension, so the force at D is (1 - D) times the intact one
  for (const Real D : {Real(0.1), Real(0.5), Real(0.9), Real(0.999999)})
    EXPECT_NEAR(force(std::sqrt(D)) / intact, 1 - D, 1e-9) << "D = " << D;  // delta = D^(1/2) in 2-D
  // compression at D = 1: the pressure acts in full, the deviator not
  rho[0] = rho[1] = Real(1.01);
  S[0] = S[1] = Mat<2>::zero();
  const Real comp_intact = force(0), comp_broken = force(1);
  EXPECT_LT(comp_intact, 0);
  EXPECT_EQ(comp_broken, comp_intact);
}

// ---- the scene and a run ----------------------------------------------------------

namespace {

// A 2-D block of a dimensionless linear-elastic solid (K = 1, mu = 0.5,
// rho0 = 1, c_l ~ 1.3), 1 x 0.4 at spacing 0.05, as two halves moving apart
// at -/+ speed: a tension of ~ speed/c_l strain runs out from the middle.
// `damage` is the material's damage table ("" = none).
std::string stretched_block(const std::string& damage, double speed = 0.1, double end_time = 1.0) {
  std::ostringstream s;
  s << "[simulation]\ndimension = 2\nend_time = " << end_time << "\nintegrator = \"leapfrog\"\n"
    << "[materials.rock]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\nshear_modulus = 0.5\n"
    << damage << "\n";
  for (int half = 0; half < 2; ++half)
    s << "[[bodies]]\nshape = \"box\"\nmaterial = \"rock\"\nmin = [" << 0.5 * half << ", 0.0]\nmax = ["
      << 0.5 * (half + 1) << ", 0.4]\nspacing = 0.05\ndensity = 1.0\ninternal_energy = 0.0\nvelocity = ["
      << (half ? speed : -speed) << ", 0.0]\n";
  s << "[output]\ninterval = " << end_time / 4 << "\n";
  return s.str();
}

const char* kDamage = "damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0 }";

using rubble::test::parse_error;

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) : path(std::filesystem::temp_directory_path() / ("rubble_dmg_" + std::to_string(getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

}  // namespace

TEST(DamageScene, KeysDefaultsAndErrors) {
  const Scene s = parse_scene(stretched_block(kDamage), "t.toml");
  const DamageConfig& d = s.materials[0].damage;
  EXPECT_TRUE(d.enabled);
  EXPECT_EQ(d.weibull_k, 1e20);
  EXPECT_EQ(d.weibull_m, 6.0);
  EXPECT_EQ(d.crack_speed, 0.4);  // Benz & Asphaug 1994
  EXPECT_TRUE(d.deviatoric);
  EXPECT_EQ(d.seed, 1);
  EXPECT_EQ(d.min_flaws_per_particle, 1);  // Benz & Asphaug 1995: every particle at least one
  EXPECT_TRUE(d.capped);                   // Benz & Asphaug 1995: D <= n_act/n_f
  EXPECT_EQ(d.crack_length, CrackLength::ParticleRadius);  // Benz & Asphaug 1995: the particle's radius
  EXPECT_EQ(parse_scene(stretched_block("damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, "
                                        "crack_length = \"kernel_support\" }"),
                        "t.toml")
                .materials[0]
                .damage.crack_length,
            CrackLength::KernelSupport);
  const Scene t = parse_scene(
      stretched_block("damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, crack_speed = 0.3, "
                      "deviatoric = false, seed = 99, min_flaws_per_particle = 40, cap = \"none\" }"),
      "t.toml");
  EXPECT_EQ(t.materials[0].damage.crack_speed, 0.3);
  EXPECT_FALSE(t.materials[0].damage.deviatoric);
  EXPECT_EQ(t.materials[0].damage.seed, 99);
  EXPECT_EQ(t.materials[0].damage.min_flaws_per_particle, 40);
  EXPECT_FALSE(t.materials[0].damage.capped);
  EXPECT_TRUE(parse_scene(stretched_block("damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, "
                                          "cap = \"active_fraction\" }"),
                          "t.toml")
                  .materials[0]
                  .damage.capped);
  // each bad value: the file and the key in the message
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 0.0 }", "materials.rock.damage.weibull_m"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = -2.0 }", "materials.rock.damage.weibull_m"},
      {"damage = { model = \"grady_kipp\", weibull_k = 0.0, weibull_m = 6.0 }", "materials.rock.damage.weibull_k"},
      {"damage = { model = \"grady_kipp\", weibull_m = 6.0 }", "materials.rock.damage.weibull_k"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20 }", "materials.rock.damage.weibull_m"},
      {"damage = { weibull_k = 1e20, weibull_m = 6.0 }", "materials.rock.damage.model"},
      {"damage = { model = \"weibull\", weibull_k = 1e20, weibull_m = 6.0 }", "materials.rock.damage.model"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, crack_speed = 1.5 }",
       "materials.rock.damage.crack_speed"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, seed = -1 }",
       "materials.rock.damage.seed"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, flaws = 3 }", "materials.rock.damage"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, min_flaws_per_particle = 0 }",
       "materials.rock.damage.min_flaws_per_particle"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, min_flaws_per_particle = 2000000 }",
       "materials.rock.damage.min_flaws_per_particle"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, cap = \"fraction\" }",
       "materials.rock.damage.cap"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, cap = false }",
       "materials.rock.damage.cap"},
      {"damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, crack_length = \"h\" }",
       "materials.rock.damage.crack_length"},
  };
  for (const auto& [table, key] : bad) {
    const std::string msg = parse_error(stretched_block(table));
    EXPECT_NE(msg.find("t.toml"), std::string::npos) << table << ": " << msg;
    EXPECT_NE(msg.find(key), std::string::npos) << table << ": " << msg;
  }
  // damage on a fluid (no shear modulus)
  std::string fluid = stretched_block(kDamage);
  fluid.replace(fluid.find("shear_modulus = 0.5"), 19, "");
  EXPECT_NE(parse_error(fluid).find("materials.rock.damage"), std::string::npos) << parse_error(fluid);
}

TEST(DamageScene, CollinsStrengthKeysAndItsDamageActsThroughTheYieldSurface) {
  const std::string collins =
      "plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 1.0, "
      "friction_damaged = 0.6 }\n";
  const Scene s = parse_scene(stretched_block(collins + kDamage), "t.toml");
  const PlasticityConfig& pc = s.materials[0].plasticity;
  EXPECT_EQ(pc.model, PlasticityModel::Collins);
  EXPECT_EQ(pc.cohesion, 0.01);
  EXPECT_EQ(pc.friction_intact, 1.4);
  EXPECT_EQ(pc.strength_limit, 1.0);
  EXPECT_EQ(pc.friction_damaged, 0.6);
  EXPECT_EQ(pc.cohesion_damaged, 0.0);  // default: a cohesionless Coulomb law (Collins et al. 2004)
  EXPECT_EQ(pc.melt_energy, 0.0);       // default: no thermal softening
  // damage weakens Collins rock through Y(p, D), not by scaling the deviator
  EXPECT_FALSE(s.materials[0].damage.deviatoric);
  const MaterialParams mp = material_params_from_scene(s)[0];
  EXPECT_EQ(mp.plasticity.model, PlasticityModel::Collins);
  EXPECT_EQ(mp.plasticity.strength_limit, 1.0);
  EXPECT_EQ(damaged_deviatoric_factor(mp.damage, 1.0), 1.0);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"plasticity = { model = \"collins\", friction_intact = 1.4, strength_limit = 1.0, friction_damaged = 0.6 }",
       "materials.rock.plasticity.cohesion"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 0.001, "
       "friction_damaged = 0.6 }",
       "materials.rock.plasticity.strength_limit"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = -1.0, strength_limit = 1.0, "
       "friction_damaged = 0.6 }",
       "materials.rock.plasticity.friction_intact"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 1.0 }",
       "materials.rock.plasticity.friction_damaged"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 1.0, "
       "friction_damaged = 0.6, cohesion_damaged = 0.02 }",
       "materials.rock.plasticity.cohesion_damaged"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 1.0, "
       "friction_damaged = 0.6, melt_energy = 0.0 }",
       "materials.rock.plasticity.melt_energy"},
      {"plasticity = { model = \"collins\", cohesion = 0.01, friction_intact = 1.4, strength_limit = 1.0, "
       "friction_damaged = 0.6, yield_stress = 1.0 }",
       "materials.rock.plasticity"},
      {collins + "damage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, deviatoric = true }",
       "materials.rock.damage.deviatoric"},
  };
  for (const auto& [table, key] : bad) {
    const std::string msg = parse_error(stretched_block(table));
    EXPECT_NE(msg.find("t.toml"), std::string::npos) << table << ": " << msg;
    EXPECT_NE(msg.find(key), std::string::npos) << table << ": " << msg;
  }
}

TEST(DamageRun, FieldsOnlyWithDamageAndAStretchedBlockBreaks) {
  auto run = [](const std::string& text, const std::string& name) {
    TempDir d(name);
    const Scene s = parse_scene(text, "t.toml");
    RunOptions opt;
    opt.out_dir = d.path.string();
    opt.quiet = true;
    run_scene(s, opt);
    std::vector<ParticleStore<2>> out;
    for (int k = 0;; ++k) {
      const auto f = d.path / snapshot_filename(s.output.name, k);
      if (!std::filesystem::exists(f)) break;
      ParticleStore<2> ps;
      SnapshotMeta meta;
      read_snapshot<2>(f.string(), ps, meta);
      out.push_back(std::move(ps));
    }
    return out;
  };
  // the elastic block allocates no damage field
  std::string intact = stretched_block("", 0.1, 0.1);
  const auto a = run(intact, "intact");
  for (const char* f : {"damage_root", "flaw_count", "flaw_eps_min", "flaw_eps_max", "flaws_active"})
    for (const auto& name : a.back().allocated_fields()) EXPECT_NE(name, f);
  // pulled apart (a tensile strain ~0.1/1.3) with flaws that activate at
  // eps ~ 1e-3 (k V = 1e20 * 0.2 per half, m = 6): it breaks
  std::string text = stretched_block(kDamage, 0.1, 1.0);
  const auto b = run(text, "stretched");
  ASSERT_FALSE(b.empty());
  const ParticleStore<2>& last = b.back();
  ASSERT_EQ(last.damage_root.size(), last.n);
  Real most = 0;
  for (std::size_t i = 0; i < last.n; ++i) {
    EXPECT_GE(last.flaw_count[i], 1);
    EXPECT_LE(last.flaws_active[i], Real(last.flaw_count[i]));
    EXPECT_LE(last.damage_root[i], std::sqrt(last.flaws_active[i] / Real(last.flaw_count[i])) * (1 + 1e-12));
    EXPECT_LE(last.damage_root[i], 1);
    most = std::max(most, last.damage_root[i]);
  }
  EXPECT_EQ(most, 1);  // at least one particle broke
  // delta never falls between outputs (particles keep their order in snapshots by id)
  for (std::size_t k = 1; k < b.size(); ++k)
    for (std::size_t i = 0; i < last.n; ++i) {
      auto find = [&](const ParticleStore<2>& ps) {
        return std::size_t(std::find(ps.id.begin(), ps.id.end(), std::int32_t(i)) - ps.id.begin());
      };
      EXPECT_GE(b[k].damage_root[find(b[k])], b[k - 1].damage_root[find(b[k - 1])]);
    }
}

TEST(DamageLibrary, BrittleBasaltAndIceCarryTheirWeibullConstants) {
  // Benz & Asphaug (1999) as tabulated by miluphcuda (the files' provenance)
  struct Want {
    const char* name;
    const char* matrix;
    double k, m, mu, Y;
  };
  for (const Want& w : {Want{"basalt_brittle", "basalt", 4e35, 9.0, 2.27e10, 3.5e9},
                        Want{"ice_brittle", "ice", 1.4e38, 9.6, 2.8e9, 1e9}}) {
    const MaterialConfig m = load_material(w.name), base = load_material(w.matrix);
    EXPECT_TRUE(m.damage.enabled) << w.name;
    EXPECT_EQ(m.damage.weibull_k, w.k) << w.name;
    EXPECT_EQ(m.damage.weibull_m, w.m) << w.name;
    EXPECT_EQ(m.shear_modulus, w.mu) << w.name;
    EXPECT_EQ(m.plasticity.yield_stress, w.Y) << w.name;
    EXPECT_EQ(m.tillotson.A, base.tillotson.A) << w.name;  // the same matrix as the plain library file
    EXPECT_EQ(m.tillotson.E0, base.tillotson.E0) << w.name;
    EXPECT_EQ(m.tillotson.alpha, base.tillotson.alpha) << w.name;
  }
}

TEST(DamageLibrary, CollinsRocksCarryTheirStrengthAndDamageActsThroughIt) {
  // the values of the files' sources (reference_data/materials/*_collins.toml)
  const MaterialConfig b = load_material("basalt_collins"), basalt = load_material("basalt_brittle");
  EXPECT_EQ(b.plasticity.model, PlasticityModel::Collins);
  EXPECT_EQ(b.plasticity.cohesion, 2.0e7);  // SALEc example/sup_material.inp basalt_: YINT0
  EXPECT_EQ(b.plasticity.friction_intact, 1.4);
  EXPECT_EQ(b.plasticity.strength_limit, 3.5e9);
  EXPECT_EQ(b.plasticity.cohesion_damaged, 1.0e4);
  EXPECT_EQ(b.plasticity.friction_damaged, 0.6);
  EXPECT_EQ(b.plasticity.melt_energy, 3.4e6);  // miluphcuda basalt.plasticity.cfg
  EXPECT_TRUE(b.damage.enabled);
  EXPECT_FALSE(b.damage.deviatoric);  // damage acts through the yield surface
  EXPECT_EQ(b.damage.weibull_k, basalt.damage.weibull_k);
  EXPECT_EQ(b.damage.weibull_m, basalt.damage.weibull_m);
  EXPECT_EQ(b.shear_modulus, basalt.shear_modulus);
  EXPECT_EQ(b.tillotson.A, basalt.tillotson.A);
  const MaterialConfig g = load_material("granite_collins"), granite = load_material("granite");
  EXPECT_EQ(g.plasticity.model, PlasticityModel::Collins);
  EXPECT_EQ(g.plasticity.cohesion, 9.0e7);  // miluphcuda granite.plasticity.cfg
  EXPECT_EQ(g.plasticity.strength_limit, 1.5e9);
  EXPECT_EQ(g.plasticity.friction_intact, 2.0);
  EXPECT_EQ(g.plasticity.friction_damaged, 0.8);
  EXPECT_EQ(g.shear_modulus, 2.7e10);  // miluphcuda Granite.cfg
  EXPECT_FALSE(g.damage.enabled);
  EXPECT_EQ(g.tillotson.A, granite.tillotson.A);
}

TEST(VelocityGradient, LinearInitialVelocityAndErrors) {
  // a 1-D bar stretched about x = 0: v = 2 + 1e3 x
  const std::string base =
      "[simulation]\ndimension = 1\nend_time = 1e-9\n[materials.r]\neos = \"murnaghan\"\n"
      "murnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n[[bodies]]\nshape = \"box\"\nmaterial = \"r\"\nmin = [-0.5]\n"
      "max = [0.5]\nspacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nvelocity = [2.0]\n";
  const Scene s = parse_scene(base + "velocity_gradient = [[1e3]]\n", "t.toml");
  EXPECT_EQ(s.bodies[0].velocity_gradient[0][0], 1e3);
  TempDir d("vgrad");
  RunOptions opt;
  opt.out_dir = d.path.string();
  opt.quiet = true;
  run_scene(s, opt);
  ParticleStore<1> ps;
  SnapshotMeta meta;
  read_snapshot<1>((d.path / snapshot_filename(s.output.name, 0)).string(), ps, meta);
  for (std::size_t i = 0; i < ps.n; ++i) EXPECT_NEAR(ps.v[i][0], 2 + 1e3 * ps.x[i][0], 1e-12);
  EXPECT_NE(parse_error(base + "velocity_gradient = [1e3]\n").find("bodies[0].velocity_gradient"), std::string::npos);
  EXPECT_NE(parse_error(base + "velocity_gradient = [[1e3, 0.0]]\n").find("bodies[0].velocity_gradient"),
            std::string::npos);
  EXPECT_NE(parse_error(base + "velocity_gradient = [[1e3]]\nboundary = \"fixed\"\n").find("bodies[0].velocity_gradient"),
            std::string::npos);
}

TEST(VelocityGradient, MovingBoundaryParticlesKeepTheirOwnVelocity) {
  // a stretching grip: a moving boundary body with v = 1e3 x next to a free
  // body; every grip particle keeps its own initial velocity and moves with it
  const std::string scene =
      "[simulation]\ndimension = 1\nend_time = 1e-5\n[materials.r]\neos = \"murnaghan\"\n"
      "murnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n"
      "[[bodies]]\nshape = \"box\"\nmaterial = \"r\"\nmin = [-0.5]\nmax = [0.5]\nspacing = 0.1\ndensity = 1.0\n"
      "internal_energy = 0.0\nvelocity_gradient = [[1e3]]\n"
      "[[bodies]]\nshape = \"box\"\nmaterial = \"r\"\nmin = [0.5]\nmax = [0.8]\nspacing = 0.1\ndensity = 1.0\n"
      "internal_energy = 0.0\nboundary = \"moving\"\nvelocity_gradient = [[1e3]]\n"
      "[output]\nname = \"g\"\ninterval = 1e-5\n";
  const Scene s = parse_scene(scene, "t.toml");
  TempDir d("vgrad_moving");
  RunOptions opt;
  opt.out_dir = d.path.string();
  opt.quiet = true;
  run_scene(s, opt);
  ParticleStore<1> p0, p1;
  SnapshotMeta m0, m1;
  read_snapshot<1>((d.path / snapshot_filename(s.output.name, 0)).string(), p0, m0);
  read_snapshot<1>((d.path / snapshot_filename(s.output.name, 1)).string(), p1, m1);
  ASSERT_EQ(p0.n, p1.n);
  std::size_t grip = 0;
  for (std::size_t i = 0; i < p1.n; ++i) {
    if (!p1.boundary[i]) continue;
    ++grip;
    const std::size_t j = std::size_t(std::find(p0.id.begin(), p0.id.begin() + long(p0.n), p1.id[i]) - p0.id.begin());
    ASSERT_LT(j, p0.n);
    EXPECT_NEAR(p0.v[j][0], 1e3 * p0.x[j][0], 1e-12);
    EXPECT_EQ(p1.v[i][0], p0.v[j][0]);
    EXPECT_NEAR(p1.x[i][0], p0.x[j][0] + p0.v[j][0] * (m1.time - m0.time), 1e-12);
  }
  EXPECT_EQ(grip, 3u);
}
