// Time integrators on a problem with a known answer: independent unit
// harmonic oscillators, dv/dt = -x (x = A cos t), with du/dt = -x v so that
// u exercises the energy channel, driven through the same System interface
// (evaluate(), domain()) as the SPH driver.
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/core/box.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/particles/particle_store.hpp"

using namespace rubble;

namespace {

// A mock of HydroCpu: rates of uncoupled unit-frequency oscillators.
struct Oscillators {
  ParticleStore<1>& ps;
  Box<1> box;
  int evaluations = 0;
  const Box<1>& domain() const { return box; }
  void end_step(const Real*, Real) {}  // no porosity or plasticity here
  void evaluate() {
    ++evaluations;
    for (std::size_t i = 0; i < ps.n; ++i) {
      ps.dvdt[i][0] = -ps.x[i][0];
      ps.dudt[i] = -ps.x[i][0] * ps.v[i][0];
    }
  }
};

ParticleStore<1> make_store() {
  ParticleStore<1> ps;
  ps.allocate(3, FieldNeeds{});
  for (int i = 0; i < 3; ++i) {
    ps.x[i][0] = 1.0 + i;  // amplitude 1, 2, 3
    ps.v[i][0] = 0;
    ps.u[i] = 10;
    ps.h[i] = 1;
    ps.cs[i] = 1;
    ps.rho[i] = 1;
  }
  return ps;
}

double leapfrog_error(double dt, double t_end) {
  ParticleStore<1> ps = make_store();
  Oscillators sys{ps, {}};
  sys.evaluate();
  const int steps = static_cast<int>(std::lround(t_end / dt));
  for (int s = 0; s < steps; ++s) leapfrog_step<1>(sys, ps, dt);
  double err = 0;
  for (int i = 0; i < 3; ++i) err = std::max(err, std::fabs(ps.x[i][0] - (1.0 + i) * std::cos(t_end)));
  return err;
}

}  // namespace

// Second order: halving dt quarters the error (observed order in [1.9, 2.1]).
TEST(Leapfrog, SecondOrderConvergence) {
  const double e1 = leapfrog_error(0.02, 2.0), e2 = leapfrog_error(0.01, 2.0);
  const double order = std::log2(e1 / e2);
  EXPECT_NEAR(order, 2.0, 0.1);
}

// Symplectic: the energy error stays bounded (no drift) over 100 periods.
TEST(Leapfrog, NoEnergyDriftOverManyPeriods) {
  ParticleStore<1> ps = make_store();
  Oscillators sys{ps, {}};
  sys.evaluate();
  const double dt = 0.05;
  double max_err = 0;
  for (int s = 0; s < static_cast<int>(100 * 2 * M_PI / dt); ++s) {
    leapfrog_step<1>(sys, ps, dt);
    const double e = 0.5 * (ps.v[2][0] * ps.v[2][0] + ps.x[2][0] * ps.x[2][0]);
    max_err = std::max(max_err, std::fabs(e - 4.5) / 4.5);
  }
  // Energy error of leapfrog for the oscillator is O(dt^2/4) = 6e-4 and bounded.
  EXPECT_LT(max_err, 1e-3);
  EXPECT_EQ(sys.evaluations, 1 + static_cast<int>(100 * 2 * M_PI / dt));  // one evaluation per step
}

// The adaptive RK2 keeps the global error near the requested tolerance and
// takes fewer steps for a looser tolerance.
TEST(Rk2Adaptive, ErrorFollowsTolerance) {
  int steps_for[2] = {0, 0};
  double err_for[2] = {0, 0};
  const double tols[2] = {1e-4, 1e-6};
  for (int k = 0; k < 2; ++k) {
    ParticleStore<1> ps = make_store();
    Oscillators sys{ps, {}};
    sys.evaluate();
    double t = 0, dt = 0.1;
    const double t_end = 2 * M_PI;
    while (t < t_end - 1e-14) {
      dt = std::min(dt, t_end - t);
      const Rk2Result r = rk2_adaptive_step<1>(sys, ps, dt, tols[k], 1e-12);
      t += r.dt_taken;
      dt = r.dt_next;
      ++steps_for[k];
    }
    for (int i = 0; i < 3; ++i)
      err_for[k] = std::max(err_for[k], std::fabs(ps.x[i][0] - (1.0 + i) * std::cos(t_end)) / (1.0 + i));
  }
  EXPECT_GT(steps_for[1], 2 * steps_for[0]);
  // The local error per step is held below tol; over one period with
  // O(100) steps the global error stays within ~100 tol.
  EXPECT_LT(err_for[0], 100 * tols[0]);
  EXPECT_LT(err_for[1], 100 * tols[1]);
  EXPECT_LT(err_for[1], err_for[0]);
}

// A step whose error exceeds the tolerance is rejected and the state
// restored before retrying with a smaller step.
TEST(Rk2Adaptive, RejectsTooLargeStep) {
  ParticleStore<1> ps = make_store();
  Oscillators sys{ps, {}};
  sys.evaluate();
  const Rk2Result r = rk2_adaptive_step<1>(sys, ps, 1.0, 1e-8, 1e-12);
  EXPECT_GT(r.rejections, 0);
  EXPECT_LT(r.dt_taken, 1.0);
  EXPECT_NEAR(ps.x[0][0], std::cos(r.dt_taken), 1e-6);
}
