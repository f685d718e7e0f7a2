// The per-particle loop bodies that give a granular (Drucker–Prager) material
// and its walls their state (drivers/particle_rates.hpp), on hand-made stores
// of a few particles:
//  - tension cracking persists: a particle stretched beyond the apex is
//    returned there, and its inelastic volume strain eps_v grows so that the
//    EOS then gives the apex pressure (to second order in the opening); it is
//    compressed again as soon as it closes (Bui et al. 2008's rate form);
//  - an extrapolated wall particle takes the hydrostatic pressure of its free
//    neighbours at its own depth, their deviator and density, and ignores
//    other boundary particles; one without free neighbours keeps its state.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/drivers/particle_rates.hpp"

using namespace rubble;

namespace {

constexpr Real kRho0 = 2650, kK = 7e5, kG = 3.23e5;

MaterialParams granular() {
  MaterialParams m{};
  m.eos.kind = EosKind::Murnaghan;
  m.eos.murnaghan = MurnaghanParams{kRho0, kK, Real(1)};
  m.shear_modulus = kG;
  m.plasticity = drucker_prager_params(Real(19.8), Real(0), Real(0), DpConeFit::PlaneStrain);
  return m;
}

// A store of n particles in 2-D with the fields the loop bodies below read.
struct SmallStore {
  std::vector<Real> m, u, rho, h, p, cs, eps_p, eps_v;
  std::vector<std::int32_t> mat, boundary;
  std::vector<Vec<2>> x, v;
  std::vector<Mat<2>> S;
  explicit SmallStore(std::size_t n)
      : m(n, 1), u(n, 0), rho(n, kRho0), h(n, 0.01), p(n, 0), cs(n, 0), eps_p(n, 0), eps_v(n, 0), mat(n, 0),
        boundary(n, kFreeParticle), x(n, Vec<2>::zero()), v(n, Vec<2>::zero()), S(n, Mat<2>::zero()) {}
  StoreView<2> view() {
    StoreView<2> s;
    s.n = m.size();
    s.m = m.data(), s.u = u.data(), s.rho = rho.data(), s.h = h.data(), s.p = p.data(), s.cs = cs.data();
    s.eps_p = eps_p.data(), s.eps_v = eps_v.data(), s.material_id = mat.data(), s.boundary = boundary.data();
    s.x = x.data(), s.v = v.data(), s.S = S.data();
    return s;
  }
};

}  // namespace

TEST(TensionCracking, OpeningPersistsAndClosingCompresses) {
  const MaterialParams mat = granular();
  SmallStore st(1);
  RhsContext<2> c;
  c.s = st.view();
  c.mat = &mat;
  for (const Real opening : {Real(1e-4), Real(1e-3), Real(1e-2)}) {
    st.rho[0] = kRho0;
    st.eps_v[0] = 0;
    st.rho[0] = kRho0 * (1 - opening);  // stretched: p(rho) < 0, beyond the cohesionless apex p = 0
    eos_particle<2>(c, 0);
    ASSERT_LT(st.p[0], 0);
    plastic_return_particle<2>(c, 0, true);  // end of an accepted step
    EXPECT_EQ(st.p[0], 0);                   // at the apex
    EXPECT_GT(st.eps_v[0], 0);               // the opening is remembered
    eos_particle<2>(c, 0);                   // next evaluation, same density
    // p at the apex to second order in the opening: K * O(opening^2)
    EXPECT_LE(std::fabs(st.p[0]), kK * opening * opening) << "opening " << opening;
    // closing by 1e-4 of the volume compresses at once: p = K * 1e-4 to first order
    st.rho[0] *= Real(1.0001);
    eos_particle<2>(c, 0);
    EXPECT_NEAR(st.p[0], kK * 1e-4, kK * (1e-8 + opening * opening)) << "opening " << opening;
  }
}

TEST(WallExtrapolationParticle, HydrostaticFromFreeNeighboursOnly) {
  const MaterialParams mat = granular();
  // particle 0: the wall particle at the origin; 1-3: free particles above
  // it in a hydrostatic column p = rho g (H - y); 4: another wall particle
  // with an absurd pressure that must not count; 5: a far free particle.
  SmallStore st(6);
  const Real g = 9.81, H = 0.1;
  const Vec<2> xs[6] = {{0, 0}, {0.002, 0.004}, {-0.003, 0.003}, {0.0, 0.006}, {0.004, 0.0}, {0.5, 0.5}};
  for (int i = 0; i < 6; ++i) {
    st.x[i] = xs[i];
    st.p[i] = kRho0 * g * (H - xs[i][1]);
    st.cs[i] = 16;
    st.S[i].m[0][0] = 100, st.S[i].m[1][1] = -100, st.S[i].m[0][1] = st.S[i].m[1][0] = 40;
  }
  st.boundary[0] = st.boundary[4] = kBoundaryExtrapolated;
  st.p[4] = 1e9;
  st.p[0] = -7;  // overwritten
  RhsContext<2> c;
  c.s = st.view();
  c.mat = &mat;
  c.body_force = Vec<2>{0, -g};
  auto all = [&](std::uint32_t a) {
    return [&, a](auto&& f) {
      for (std::uint32_t b = 0; b < 6; ++b)
        if (b != a) f(b);
    };
  };
  wall_extrapolation_particle<2>(c, 0, all(0));
  EXPECT_NEAR(st.p[0], kRho0 * g * H, 1e-10 * kRho0 * g * H);
  EXPECT_NEAR(st.rho[0], kRho0, 1e-12 * kRho0);
  EXPECT_NEAR(st.cs[0], 16, 1e-12);
  EXPECT_NEAR(st.S[0].m[0][1], 40, 1e-10);
  // a free particle is left alone
  const Real p1 = st.p[1];
  wall_extrapolation_particle<2>(c, 1, all(1));
  EXPECT_EQ(st.p[1], p1);
  // a wall particle with no free neighbour within its support keeps its state
  st.x[4] = Vec<2>{0.2, -0.2};
  st.p[4] = 123;
  wall_extrapolation_particle<2>(c, 4, all(4));
  EXPECT_EQ(st.p[4], 123);
}

// The memory stops at eps_v = ln 2 (kMaxInelasticVolume): a particle opened
// further (an ejected grain) keeps eps_v = ln 2 and is stress-free (at the
// apex) until its density is back above rho0/2.
TEST(TensionCracking, MemoryStopsAtTwiceTheVolume) {
  const MaterialParams mat = granular();
  SmallStore st(1);
  RhsContext<2> c;
  c.s = st.view();
  c.mat = &mat;
  st.rho[0] = kRho0;
  for (int k = 0; k < 100; ++k) {  // open by 1 % a step, to 0.366 rho0
    st.rho[0] *= Real(0.99);
    eos_particle<2>(c, 0);
    plastic_return_particle<2>(c, 0, true);
  }
  EXPECT_EQ(st.eps_v[0], kMaxInelasticVolume);
  eos_particle<2>(c, 0);
  EXPECT_LT(st.p[0], 0);  // rho exp(eps_v) < rho0: below the apex, returned to it
  plastic_return_particle<2>(c, 0, false);
  EXPECT_EQ(st.p[0], 0);
  // closing to rho0/2 + 1e-4 compresses again
  st.rho[0] = kRho0 / 2 * Real(1.0001);
  eos_particle<2>(c, 0);
  EXPECT_NEAR(st.p[0], kK * 1e-4, kK * 1e-8);
}
