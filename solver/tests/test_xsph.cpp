// XSPH (issue #4 item 2; physics/xsph.hpp): the pair term conserves the
// centre-of-mass motion, pulls a particle's drift towards its neighbours'
// velocity, leaves a uniformly moving body untouched, and is switched on by
// the scene key simulation.xsph only (field allocated only then).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "rubble/core/box.hpp"
#include "rubble/core/error.hpp"
#include "rubble/drivers/host_loops.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/xsph.hpp"
#include "rubble/run.hpp"

using namespace rubble;

namespace {

std::string block_scene(const std::string& sim_extra, const std::string& body_extra = "") {
  return "[simulation]\ndimension = 2\nend_time = 0.5\nintegrator = \"leapfrog\"\n" + sim_extra +
         "\n[materials.rubber]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n"
         "shear_modulus = 0.22\n"
         "\n[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n"
         "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\n" +
         body_extra;
}

// A system with no forces whose XSPH correction is a fixed field, to check
// that both integrators drift with v + xsph_v.
struct ForceFree : HostLoops<1> {
  explicit ForceFree(ParticleStore<1>& p) : HostLoops<1>(p), ps(p) {}
  ParticleStore<1>& ps;
  Box<1> box;
  const Box<1>& domain() const { return box; }
  void end_step(const Real*, Real) {}  // no porosity or plasticity here
  void evaluate() {
    for (std::size_t i = 0; i < ps.n; ++i) ps.xsph_v[i][0] = 0.25 * (1.0 + double(i));
  }
};

}  // namespace

TEST(Xsph, IntegratorsDriftWithTheCorrection) {
  for (int which = 0; which < 2; ++which) {
    ParticleStore<1> ps;
    Features needs;
    needs.xsph = true;
    ps.allocate(3, needs);
    for (int i = 0; i < 3; ++i) {
      ps.x[i][0] = i;
      ps.v[i][0] = 1.0;
      ps.h[i] = 1;
      ps.cs[i] = 1;
      ps.rho[i] = 1;
    }
    ForceFree sys(ps);
    sys.evaluate();
    const double dt = 0.1;
    if (which == 0) leapfrog_step<1>(sys, dt);
    else rk2_adaptive_step<1>(sys, dt, 1e-5, 1e-9);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(ps.x[i][0], i + dt * (1.0 + 0.25 * (1.0 + i)), 1e-14) << which;
  }
}

// sum_a m_a dx_a(XSPH) = 0 for any particle set: the correction never moves
// the centre of mass (Monaghan 1992, §4).
TEST(Xsph, PairTermsConserveCentreOfMassMotion) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  const int n = 40;
  std::vector<Vec<2>> x(n), v(n);
  std::vector<double> m(n), rho(n), h(n);
  for (int i = 0; i < n; ++i) {
    x[i] = {U(rng), U(rng)};
    v[i] = {U(rng), U(rng)};
    m[i] = 1.0 + 0.5 * U(rng);
    rho[i] = 2.0 + U(rng);
    h[i] = 0.8 + 0.3 * U(rng);
  }
  Vec<2> total = Vec<2>::zero();
  double scale = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      if (a == b) continue;
      const double r = norm(x[a] - x[b]);
      const double w = 0.5 * (kernel_w<2>(KernelType::CubicSpline, r, h[a]) + kernel_w<2>(KernelType::CubicSpline, r, h[b]));
      const Vec<2> t = m[a] * xsph_pair_term<2>(m[b], rho[a], rho[b], v[b] - v[a], w);
      total += t;
      scale += norm(t);
    }
  ASSERT_GT(scale, 0);
  EXPECT_LT(norm(total), 1e-14 * scale);
}

// The correction points from v_a towards v_b, with weight m_b W / rhobar.
TEST(Xsph, PairTermPullsTowardsTheNeighbourVelocity) {
  const Vec<2> v_ba{0.3, -0.4};
  const Vec<2> t = xsph_pair_term<2>(2.0, 1.0, 3.0, v_ba, 0.5);
  EXPECT_NEAR(t[0], 2.0 * 0.5 / 2.0 * 0.3, 1e-15);
  EXPECT_NEAR(t[1], 2.0 * 0.5 / 2.0 * -0.4, 1e-15);
  EXPECT_EQ(norm(xsph_pair_term<2>(2.0, 1.0, 3.0, v_ba, 0.0)), 0.0);  // outside the kernel
}

TEST(Xsph, SceneKeyIsValidated) {
  EXPECT_EQ(parse_scene(block_scene(""), "t.toml").simulation.xsph, 0.0);
  EXPECT_EQ(parse_scene(block_scene("xsph = 0.5"), "t.toml").simulation.xsph, 0.5);
  EXPECT_THROW(parse_scene(block_scene("xsph = -0.1"), "t.toml"), InputError);
  EXPECT_THROW(parse_scene(block_scene("xsph = 1.5"), "t.toml"), InputError);
  EXPECT_THROW(parse_scene(block_scene("xsph = \"yes\""), "t.toml"), InputError);
}

TEST(Xsph, FieldAllocatedOnlyWhenOn) {
  ParticleStore<2> off, on;
  Features needs;
  off.allocate(10, needs);
  EXPECT_TRUE(off.xsph_v.empty());
  EXPECT_EQ(position_rate(off, 3)[0], off.v[3][0]);
  needs.xsph = true;
  on.allocate(10, needs);
  EXPECT_EQ(on.xsph_v.size(), 10u);
  on.v[3] = {1.0, 2.0};
  on.xsph_v[3] = {0.25, -0.5};
  EXPECT_EQ(position_rate(on, 3)[0], 1.25);
  EXPECT_EQ(position_rate(on, 3)[1], 1.5);
}

// A body in uniform translation has no relative velocities: with XSPH on it
// still moves rigidly by v t (both integrators).
TEST(Xsph, UniformTranslationIsUntouched) {
  for (const std::string integ : {"leapfrog", "rk2_adaptive"}) {
    std::string sc = block_scene("xsph = 0.5", "velocity = [0.2, -0.1]\n");
    sc.replace(sc.find("\"leapfrog\""), 10, "\"" + integ + "\"");
    const Scene s = parse_scene(sc, "t.toml");
    const Scene s0 = parse_scene(block_scene("xsph = 0.5"), "t.toml");
    const FinalState moved = run_scene(s, RunOptions{"", false, false, true});
    const FinalState rest = run_scene(s0, RunOptions{"", false, false, true});
    ASSERT_EQ(moved.x.size(), rest.x.size());
    // every particle is where its counterpart at rest is, shifted by v t
    const double T = moved.time;
    ASSERT_NEAR(T, rest.time, 1e-12);
    double dmax = 0;
    for (std::size_t i = 0; i < moved.x.size() / 2; ++i) {
      const double sx = moved.x[2 * i] - 0.2 * T, sy = moved.x[2 * i + 1] + 0.1 * T;
      double best = 1e300;
      for (std::size_t j = 0; j < rest.x.size() / 2; ++j)
        best = std::min(best, std::hypot(sx - rest.x[2 * j], sy - rest.x[2 * j + 1]));
      dmax = std::max(dmax, best);
    }
    EXPECT_LT(dmax, 1e-12) << integ;
  }
}
