// Unit tests of the exact Sedov-Taylor solution (rubble/reference/sedov.hpp),
// the reference the Sedov-Taylor rung is judged against.
//
// Printed reference: Kamm & Timmes (2007, LA-UR-07-2849) give, for the
// standard spherical test (gamma = 1.4, uniform density), the energy
// alpha = 0.851072 that puts the shock at r = 1 at t = 1 with rho0 = 1, i.e.
// xi0 = alpha^(-1/5). A printed 6-decimal value is the exact one to within
// half a unit of its last place, 5e-7. The other checks need no printed
// number: conservation laws of the similarity solution itself, to the
// accuracy of its quadrature (1e-6 relative; the table is accurate to
// ~1e-9, the trapezoid mass integral below to ~1e-6).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rubble/reference/sedov.hpp"

namespace {

using rubble::SedovSolution;

constexpr double kPi = std::numbers::pi;

// sigma_j r^(j-1): the measure of a shell in geometry j.
double shell(int j, double r) { return j == 1 ? 2.0 : j == 2 ? 2 * kPi * r : 4 * kPi * r * r; }

}  // namespace

TEST(SedovExact, SphericalAirEnergyConstantMatchesKammTimmes) {
  const SedovSolution s(1.4, 3);
  EXPECT_NEAR(std::pow(s.xi0(), -5.0), 0.851072, 5e-7);
}

TEST(SedovExact, ConvergedInTheNumberOfSteps) {
  for (int j = 1; j <= 3; ++j) {
    const SedovSolution a(5.0 / 3.0, j, 20000), b(5.0 / 3.0, j, 40000);
    EXPECT_NEAR(a.xi0(), b.xi0(), 1e-9 * b.xi0()) << "j = " << j;
  }
}

// Strong-shock Rankine-Hugoniot conditions just behind the front:
// rho = (g+1)/(g-1) rho0, v = 2/(g+1) Rdot, p = 2/(g+1) rho0 Rdot^2.
TEST(SedovExact, JumpConditionsAtTheShock) {
  const double g = 5.0 / 3.0, E = 2.0, rho0 = 3.0, t = 0.7;
  const SedovSolution s(g, 3);
  const double R = s.shock_radius(E, rho0, t), U = s.shock_speed(E, rho0, t);
  EXPECT_NEAR(U, 0.4 * R / t, 1e-14 * U);
  const rubble::SedovState in = s.sample(R, t, E, rho0);
  EXPECT_NEAR(in.rho, (g + 1) / (g - 1) * rho0, 1e-12 * in.rho);
  EXPECT_NEAR(in.v, 2 / (g + 1) * U, 1e-12 * in.v);
  EXPECT_NEAR(in.p, 2 / (g + 1) * rho0 * U * U, 1e-12 * in.p);
  const rubble::SedovState out = s.sample(R * (1 + 1e-12), t, E, rho0, 1e-5);
  EXPECT_EQ(out.rho, rho0);
  EXPECT_EQ(out.v, 0.0);
  EXPECT_EQ(out.p, 1e-5);
}

// Mass: every bit of gas the shock has swept lies between the centre and
// the shock, so int rho dV over r < R equals rho0 times that volume; energy:
// int (rho v^2/2 + p/(g-1)) dV over r < R equals E. Both in each geometry,
// integrated here from sample() by the trapezoid rule on 2e5 shells.
TEST(SedovExact, SweptMassAndEnergyAreConserved) {
  for (double g : {1.4, 5.0 / 3.0})
    for (int j = 1; j <= 3; ++j) {
      const double E = 1.5, rho0 = 0.8, t = 0.3;
      const SedovSolution s(g, j);
      const double R = s.shock_radius(E, rho0, t);
      const int n = 200000;
      double mass = 0, energy = 0;
      for (int i = 0; i <= n; ++i) {
        const double r = R * i / n, w = (i == 0 || i == n ? 0.5 : 1.0) * R / n * shell(j, r);
        const rubble::SedovState q = s.sample(r, t, E, rho0);
        mass += w * q.rho;
        energy += w * (q.rho * q.v * q.v / 2 + q.p / (g - 1));
      }
      const double swept = rho0 * (j == 1 ? 2 * R : j == 2 ? kPi * R * R : 4 * kPi / 3 * R * R * R);
      EXPECT_NEAR(mass, swept, 1e-6 * swept) << "gamma " << g << " j " << j;
      EXPECT_NEAR(energy, E, 1e-6 * E) << "gamma " << g << " j " << j;
    }
}

// Near the centre the gas moves homologously, v -> (delta/gamma) r/t with
// delta = 2/(j+2) (the entropy and continuity equations with psi -> 0 at
// finite pressure give phi/lambda -> 1/gamma). The integrated part of the
// table (lambda >= 1e-2) must approach it by itself: at lambda = 0.02 the
// remaining deviation is O(lambda^2) or smaller, < 1e-4 in every case.
TEST(SedovExact, HomologousCoreVelocity) {
  for (double g : {1.4, 5.0 / 3.0})
    for (int j = 1; j <= 3; ++j) {
      const SedovSolution s(g, j);
      EXPECT_NEAR(s.profile(0.02).v / 0.02, 1 / g, 1e-4) << "gamma " << g << " j = " << j;
      // and the core below it continues the asymptote: pressure flat
      EXPECT_NEAR(s.profile(1e-5).p, s.profile(0.01).p, 1e-12);
    }
}

TEST(SedovExact, RefusesBadArguments) {
  EXPECT_THROW(SedovSolution(1.0, 3), std::invalid_argument);
  EXPECT_THROW(SedovSolution(1.4, 4), std::invalid_argument);
  EXPECT_THROW(SedovSolution(1.4, 3, 1001), std::invalid_argument);
  const SedovSolution s(1.4, 3);
  EXPECT_THROW(s.profile(1.5), std::invalid_argument);
}
