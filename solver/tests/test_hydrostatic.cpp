// The hydrostatic structure of layered spheres (scene/hydrostatic.hpp; issue
// #52 item 1, the profile), against the analytic incompressible sphere
//   p(r) = (2 pi / 3) G rho^2 (R^2 - r^2)
// and a two-layer incompressible sphere (core rho1 to a, mantle rho2 to R):
//   mantle p(r) = (4 pi / 3) G rho2 [rho2 (R^2 - r^2)/2 + (rho1 - rho2) a^3 (1/r - 1/R)]
//   core   p(r) = p(a) + (2 pi / 3) G rho1^2 (a^2 - r^2)
// (dp/dr = -G m(r) rho / r^2 with m(r) of the two densities), with a
// Murnaghan EOS so stiff (K0 = 1e22 Pa) that rho stays rho0 to ~1e-12; and a
// Tillotson iron-basalt-ice body checked for what the equations demand:
// pressure falling outwards, each layer at or above its reference density,
// u >= 0 on each layer's adiabat, the layer masses summing to the total;
// and a polytrope: a Murnaghan body with n = 2 has p + K0/2 = (K0/(2 rho0^2))
// rho^2, so its dp/dr is that of an N = 1 polytrope, rho = rho_c sin(xi)/xi,
// xi = r/alpha, alpha^2 = K0/(4 pi G rho0^2), truncated where rho = rho0.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "rubble/scene/hydrostatic.hpp"

using namespace rubble;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double G = 6.6743e-11;

EosParams stiff(double rho0) {
  EosParams e;
  e.kind = EosKind::Murnaghan;
  e.murnaghan = {Real(rho0), Real(1e22), Real(1)};
  return e;
}
EosParams tillotson(double rho0, double A, double B, double E0, double E_iv, double E_cv, double a, double b,
                    double alpha, double beta) {
  EosParams e;
  e.kind = EosKind::Tillotson;
  e.tillotson = {Real(rho0), Real(A), Real(B), Real(E0), Real(E_iv), Real(E_cv), Real(a), Real(b), Real(alpha),
                 Real(beta)};
  return e;
}
}  // namespace

TEST(Hydrostatic, IncompressibleSphereMatchesTheAnalyticProfile) {
  const double R = 1e6, rho = 3000;
  const HydrostaticProfile pr = hydrostatic_profile({{stiff(rho), R}}, G);
  const double pc = 2 * kPi / 3 * G * rho * rho * R * R;
  EXPECT_NEAR(pr.mass, 4 * kPi / 3 * R * R * R * rho, 1e-9 * pr.mass);
  EXPECT_NEAR(pr.centre_pressure, pc, 1e-6 * pc);
  for (double x : {0.05, 0.3, 0.5, 0.8, 0.99}) {
    const HydrostaticState s = hydrostatic_at(pr, x * R);
    EXPECT_NEAR(s.p, 2 * kPi / 3 * G * rho * rho * (R * R - x * x * R * R), 1e-6 * pc) << "r = " << x << " R";
    EXPECT_NEAR(s.rho, rho, 1e-9 * rho);
  }
  EXPECT_LT(std::fabs(pr.centre_mass_residual), 1e-9);
}

TEST(Hydrostatic, TwoLayerIncompressibleSphereMatchesTheAnalyticProfile) {
  const double a = 5e5, R = 1e6, rho1 = 8000, rho2 = 3000;
  const HydrostaticProfile pr = hydrostatic_profile({{stiff(rho1), a}, {stiff(rho2), R}}, G);
  auto p_exact = [&](double r) {
    const double pa = 4 * kPi / 3 * G * rho2 * (rho2 * (R * R - a * a) / 2 + (rho1 - rho2) * a * a * a * (1 / a - 1 / R));
    if (r >= a) return 4 * kPi / 3 * G * rho2 * (rho2 * (R * R - r * r) / 2 + (rho1 - rho2) * a * a * a * (1 / r - 1 / R));
    return pa + 2 * kPi / 3 * G * rho1 * rho1 * (a * a - r * r);
  };
  const double pc = p_exact(0);
  EXPECT_NEAR(pr.centre_pressure, pc, 1e-6 * pc);
  for (double x : {0.1, 0.4, 0.499, 0.501, 0.7, 0.95}) {
    const HydrostaticState s = hydrostatic_at(pr, x * R);
    EXPECT_NEAR(s.p, p_exact(x * R), 1e-6 * pc) << "r = " << x << " R";
    EXPECT_NEAR(s.rho, x * R < a ? rho1 : rho2, 1e-9 * rho1) << "r = " << x << " R";
  }
  ASSERT_EQ(pr.layer_mass.size(), 2u);
  EXPECT_NEAR(pr.layer_mass[0], 4 * kPi / 3 * a * a * a * rho1, 1e-6 * pr.layer_mass[0]);
  EXPECT_NEAR(pr.layer_mass[1], 4 * kPi / 3 * (R * R * R - a * a * a) * rho2, 1e-6 * pr.layer_mass[1]);
  EXPECT_NEAR(pr.layer_mass[0] + pr.layer_mass[1], pr.mass, 1e-6 * pr.mass);
}

// An embryo-like body (iron core, basalt mantle, ice shell; Tillotson, Benz &
// Asphaug 1999 / the library's values), 1000 km across.
TEST(Hydrostatic, LayeredTillotsonBodyIsCompressedInwardsOnItsAdiabats) {
  const std::vector<HydrostaticLayer> layers = {
      {tillotson(7800, 1.28e11, 1.05e11, 9.5e6, 2.4e6, 8.67e6, 0.5, 1.5, 5, 5), 2.5e5},
      {tillotson(2700, 2.67e10, 2.67e10, 4.87e8, 4.72e6, 1.82e7, 0.5, 1.5, 5, 5), 4.5e5},
      {tillotson(917, 9.47e9, 9.47e9, 1.0e7, 7.73e5, 3.04e6, 0.3, 0.1, 10, 5), 5e5}};
  const HydrostaticProfile pr = hydrostatic_profile(layers, G);
  const double rho0[3] = {7800, 2700, 917};
  double sum = 0;
  for (double m : pr.layer_mass) sum += m;
  EXPECT_NEAR(sum, pr.mass, 1e-9 * pr.mass);
  EXPECT_LT(std::fabs(pr.centre_mass_residual), 1e-10);
  // the shooting's residual is continuous in the mass, so the root is found
  // at any resolution (a residual that jumped where m ran out above the
  // centre left 1.7e-6 M at the centre of a 9e22 kg embryo)
  for (int steps : {500, 1000}) EXPECT_LT(std::fabs(hydrostatic_profile(layers, G, steps).centre_mass_residual), 1e-10);
  for (std::size_t i = 1; i < pr.r.size(); ++i) {
    EXPECT_GE(pr.p[i], pr.p[i - 1]) << "pressure falls inwards at r = " << pr.r[i];
    EXPECT_GE(pr.rho[i], rho0[pr.layer[i]] * (1 - 1e-12)) << "r = " << pr.r[i];
    EXPECT_GE(pr.u[i], 0.0) << "r = " << pr.r[i];
  }
  // the surface is at p = 0 and the reference density of ice
  EXPECT_EQ(pr.p.front(), 0.0);
  EXPECT_NEAR(pr.rho.front(), 917.0, 1e-9 * 917);
  // against the same layers incompressible at their reference densities
  // (the solver's incompressible profiles are the analytic ones, above):
  // compression only adds mass, and at centre pressures ~1e9 Pa against
  // bulk moduli A >= 9.5e9 Pa the densities rise by at most ~10 %, so the
  // centre pressure and the mass exceed the incompressible ones by less
  // than 20 % and 10 %
  const HydrostaticProfile rigid =
      hydrostatic_profile({{stiff(7800), 2.5e5}, {stiff(2700), 4.5e5}, {stiff(917), 5e5}}, G);
  std::printf("centre pressure %.4g Pa (incompressible %.4g), mass %.4g kg (%.4g)\n", pr.centre_pressure,
              rigid.centre_pressure, pr.mass, rigid.mass);
  EXPECT_GE(pr.centre_pressure, rigid.centre_pressure);
  EXPECT_LE(pr.centre_pressure, 1.2 * rigid.centre_pressure);
  EXPECT_GE(pr.mass, rigid.mass);
  EXPECT_LE(pr.mass, 1.1 * rigid.mass);
}

TEST(Hydrostatic, MurnaghanBodyWithNEqualTwoIsATruncatedPolytrope) {
  const double rho0 = 3000, K0 = 1e10, x = 1.2;  // x = R / alpha: rho_c / rho0 = x / sin x = 1.29
  const double alpha = std::sqrt(K0 / (4 * kPi * G * rho0 * rho0)), R = x * alpha;
  EosParams e;
  e.kind = EosKind::Murnaghan;
  e.murnaghan = {Real(rho0), Real(K0), Real(2)};
  const HydrostaticProfile pr = hydrostatic_profile({{e, R}}, G);
  const double rho_c = rho0 * x / std::sin(x), Kp = K0 / (2 * rho0 * rho0);
  const double p_c = Kp * rho_c * rho_c - K0 / 2;
  const double M = 4 * kPi * rho_c * alpha * alpha * alpha * (std::sin(x) - x * std::cos(x));
  EXPECT_NEAR(pr.mass / M, 1.0, 1e-6);
  EXPECT_NEAR(pr.centre_pressure / p_c, 1.0, 1e-6);
  for (std::size_t i = 0; i < pr.r.size(); i += 97) {
    const double xi = pr.r[i] / alpha;
    const double rho = xi > 0 ? rho_c * std::sin(xi) / xi : rho_c;
    EXPECT_NEAR(pr.rho[i] / rho, 1.0, 1e-6) << "r = " << pr.r[i];
    EXPECT_NEAR(pr.p[i], Kp * rho * rho - K0 / 2, 1e-6 * p_c) << "r = " << pr.r[i];
  }
}

TEST(Hydrostatic, BadLayersAreRefused) {
  EXPECT_THROW(hydrostatic_profile({}, G), std::invalid_argument);
  EXPECT_THROW(hydrostatic_profile({{stiff(3000), 2e5}, {stiff(2000), 1e5}}, G), std::invalid_argument);
  EosParams gas;
  gas.kind = EosKind::IdealGas;
  EXPECT_THROW(hydrostatic_profile({{gas, 1e5}}, G), std::invalid_argument);
}
