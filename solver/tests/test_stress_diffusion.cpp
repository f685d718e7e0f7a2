// Deviatoric stress diffusion (physics/stress_diffusion.hpp; Feng,
// Fourtakas, Rogers & Lombardi 2021): the geostatic deviator difference
// against the geostatic stresses written out, the pair term's sign, and the
// rate of pass 1 (drivers/particle_rates.hpp) on a hand-made lattice: it
// damps particle-scale noise, leaves a uniform stress and, with the
// correction, a geostatic column alone, and is absent with zeta = 0.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/drivers/particle_rates.hpp"
#include "rubble/physics/stress_diffusion.hpp"

using namespace rubble;

namespace {

constexpr Real kRho = 2650, kG = 9.81;

// The deviator of the 3-D geostatic stress at height y (compression < 0):
// sigma_yy = rho g y, sigma_xx = sigma_zz = K0 rho g y (+ constants), in-plane block.
Mat<2> geostatic_deviator(Real y, Real k0) {
  const Real syy = kRho * kG * y, sxx = k0 * syy, mean = (syy + 2 * sxx) / 3;
  Mat<2> S = Mat<2>::zero();
  S.m[0][0] = sxx - mean;
  S.m[1][1] = syy - mean;
  return S;
}

}  // namespace

TEST(StressDiffusion, GeostaticDifferenceIsThatOfTheGeostaticStresses) {
  const Vec<2> g{Real(0), -kG};
  const Real k0 = Real(1 - std::sin(19.8 * 3.141592653589793 / 180));
  const Vec<2> xa{Real(0.3), Real(0.07)}, xb{Real(0.28), Real(0.05)};
  const Mat<2> d = geostatic_deviator_difference<2>(xa - xb, g, kRho, k0);
  const Mat<2> want = geostatic_deviator(xa[1], k0) - geostatic_deviator(xb[1], k0);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(d.m[i][j], want.m[i][j], 1e-9 * kRho * kG) << i << j;
  // without a body force, or with K0 = 1 (an isotropic geostatic stress), none
  const Mat<2> none = geostatic_deviator_difference<2>(xa - xb, Vec<2>::zero(), kRho, k0);
  const Mat<2> iso = geostatic_deviator_difference<2>(xa - xb, g, kRho, Real(1));
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      EXPECT_EQ(none.m[i][j], 0);
      EXPECT_EQ(iso.m[i][j], 0);
    }
}

TEST(StressDiffusion, PairTermPullsTowardsTheNeighbour) {
  Mat<2> Sa = Mat<2>::zero(), Sb = Mat<2>::zero();
  Sa.m[0][1] = Sa.m[1][0] = 100;  // a carries more shear than b
  const Vec<2> dx{Real(0.01), Real(0)};
  const Vec<2> grad_a{Real(-30), Real(0)};  // along dx times W'(r)/r < 0
  const Mat<2> t = stress_diffusion_pair_term<2>(Sa, Sb, Mat<2>::zero(), Real(1e-4), dx, grad_a, Real(0.012));
  EXPECT_LT(t.m[0][1], 0);
  EXPECT_EQ(t.m[0][0], 0);
  const Mat<2> same = stress_diffusion_pair_term<2>(Sa, Sa, Mat<2>::zero(), Real(1e-4), dx, grad_a, Real(0.012));
  EXPECT_EQ(same.m[0][1], 0);
}

namespace {

// A 2-D lattice of n x n particles at rest, spacing dx, Wendland C2 support
// 2.4 dx, with the fields pass 1 reads and writes.
struct Lattice2D {
  std::size_t n;
  std::vector<Real> m, u, rho, h, p, cs;
  std::vector<std::int32_t> mat, boundary;
  std::vector<Vec<2>> x, v;
  std::vector<Mat<2>> S, dSdt;
  Lattice2D(int side, Real dx)
      : n(std::size_t(side) * std::size_t(side)), m(n, kRho * dx * dx), u(n, 0), rho(n, kRho), h(n, Real(2.4) * dx),
        p(n, 0), cs(n, 16), mat(n, 0), boundary(n, kFreeParticle), x(n), v(n, Vec<2>::zero()), S(n, Mat<2>::zero()),
        dSdt(n, Mat<2>::zero()) {
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) x[std::size_t(j * side + i)] = Vec<2>{Real((i + 0.5) * dx), Real((j + 0.5) * dx)};
  }
  StoreView<2> view() {
    StoreView<2> s;
    s.n = n;
    s.m = m.data(), s.u = u.data(), s.rho = rho.data(), s.h = h.data(), s.p = p.data(), s.cs = cs.data();
    s.material_id = mat.data(), s.boundary = boundary.data();
    s.x = x.data(), s.v = v.data(), s.S = S.data(), s.dSdt = dSdt.data();
    return s;
  }
  // pass 1 for every particle, every other particle a candidate neighbour
  void pass1(const MaterialParams& mp, const Vec<2>& g) {
    RhsContext<2> c;
    c.s = view();
    c.mat = &mp;
    c.kernel = KernelType::WendlandC2;
    c.stress_diffusion = true;
    c.body_force = g;
    c.has_body_force = dot(g, g) > 0;
    for (std::uint32_t a = 0; a < n; ++a)
      solid_gradient_particle<2>(c, a, [&](auto&& f) {
        for (std::uint32_t b = 0; b < n; ++b)
          if (b != a) f(b);
      });
  }
};

MaterialParams granular(Real zeta) {
  MaterialParams m{};
  m.eos.kind = EosKind::Murnaghan;
  m.eos.murnaghan = MurnaghanParams{kRho, Real(7e5), Real(1)};
  m.shear_modulus = Real(3.23e5);
  m.plasticity = drucker_prager_params(Real(19.8), Real(0), Real(0), DpConeFit::PlaneStrain);
  m.stress_diffusion = zeta;
  m.k0 = Real(1 - std::sin(19.8 * 3.141592653589793 / 180));
  return m;
}

Real frob(const Mat<2>& a, const Mat<2>& b) {
  Real s = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) s += a.m[i][j] * b.m[i][j];
  return s;
}

}  // namespace

TEST(StressDiffusion, DampsNoiseAndLeavesAUniformStress) {
  Lattice2D L(10, Real(0.01));
  // deterministic particle-scale noise on a uniform shear stress
  Real mean = 0;
  for (std::size_t a = 0; a < L.n; ++a) {
    const Real noise = Real(50) * std::sin(Real(12.9898) * Real(a) + Real(0.3));
    L.S[a].m[0][1] = L.S[a].m[1][0] = Real(200) + noise;
    L.S[a].m[0][0] = noise;
    L.S[a].m[1][1] = -noise;
    mean += L.S[a].m[0][1];
  }
  mean /= Real(L.n);
  L.pass1(granular(Real(0.1)), Vec<2>::zero());
  // d/dt of the noise energy sum_a |S_a - mean|^2 is negative
  Real rate = 0;
  for (std::size_t a = 0; a < L.n; ++a) {
    Mat<2> dev = L.S[a];
    dev.m[0][1] -= mean;
    dev.m[1][0] -= mean;
    rate += frob(dev, L.dSdt[a]);
  }
  EXPECT_LT(rate, 0);

  // a uniform stress at rest stays (to rounding)
  for (std::size_t a = 0; a < L.n; ++a) {
    L.S[a] = Mat<2>::zero();
    L.S[a].m[0][1] = L.S[a].m[1][0] = Real(200);
    L.S[a].m[0][0] = Real(-70);
    L.S[a].m[1][1] = Real(70);
  }
  L.pass1(granular(Real(0.1)), Vec<2>::zero());
  for (std::size_t a = 0; a < L.n; ++a)
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) EXPECT_NEAR(L.dSdt[a].m[i][j], 0, 1e-9) << a;

  // zeta = 0: no rate at rest whatever the stress
  for (std::size_t a = 0; a < L.n; ++a) L.S[a].m[0][1] = L.S[a].m[1][0] = Real(200) + Real(a);
  L.pass1(granular(Real(0)), Vec<2>::zero());
  for (std::size_t a = 0; a < L.n; ++a) EXPECT_EQ(L.dSdt[a].m[0][1], 0) << a;
}

TEST(StressDiffusion, KeepsTheGeostaticColumnWithTheCorrectionOnly) {
  Lattice2D L(10, Real(0.01));
  const MaterialParams mp = granular(Real(0.1));
  for (std::size_t a = 0; a < L.n; ++a) L.S[a] = geostatic_deviator(L.x[a][1], mp.k0);
  const Vec<2> g{Real(0), -kG};
  L.pass1(mp, g);
  const Real scale = kRho * kG * Real(0.1);  // the deviator's range over the column [Pa]
  Real worst = 0;
  for (std::size_t a = 0; a < L.n; ++a)
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) worst = std::max(worst, std::fabs(L.dSdt[a].m[i][j]));
  EXPECT_LT(worst, 1e-9 * scale) << "the geostatic deviator is diffused";
  // without the correction (K0 = 1 in the material) the truncated kernel at
  // the top and bottom rows erodes the same column
  MaterialParams plain = mp;
  plain.k0 = 1;
  L.pass1(plain, g);
  worst = 0;
  for (std::size_t a = 0; a < L.n; ++a) worst = std::max(worst, std::fabs(L.dSdt[a].m[1][1]));
  EXPECT_GT(worst, 1e-3 * scale);
}
