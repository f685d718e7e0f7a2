// Unit tests of the extrapolated wall state (physics/wall_extrapolation.hpp;
// Adami, Hu & Adams 2012, eq. 27): for a body at rest under a uniform body
// force g the pressure is hydrostatic, p(x) = p0 + rho g.(x - x0), a linear
// field, and the formula gives the wall particle exactly that pressure
// whatever the neighbours' positions and weights, for a wall particle below
// them along g (the Shepard average of a linear field plus the gradient term
// times the weighted offset is exact).
// Constant fields (S, rho, c) come back unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rubble/physics/kernels.hpp"
#include "rubble/physics/wall_extrapolation.hpp"

using namespace rubble;

namespace {

template <int D>
void check_hydrostatic(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Real rho = 2650, p0 = 1234.5;
  Vec<D> g = Vec<D>::zero();
  g[D - 1] = -9.81;
  if (D > 1) g[0] = 0.7;  // any direction: the formula knows only g
  Vec<D> x0 = Vec<D>::zero();
  auto p_of = [&](const Vec<D>& x) { return p0 + rho * dot(g, x - x0); };  // grad p = rho g
  Mat<D> S = Mat<D>::zero();
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) S.m[i][j] = Real(10 * (i + 1) + (i == j ? 3 : 0) * (j + 1));
  const Real h = 0.03;
  for (int trial = 0; trial < 20; ++trial) {
    Vec<D> xw;
    for (int k = 0; k < D; ++k) xw[k] = Real(0.01 * u(rng));
    WallSums<D> sum;
    int used = 0;
    for (int f = 0; f < 40; ++f) {
      Vec<D> xf;
      for (int k = 0; k < D; ++k) xf[k] = xw[k] + Real(h * u(rng));
      if (dot(g, xw - xf) < 0) xf = xw - (xf - xw);  // above the wall particle along g (a floor)
      const Vec<D> dx = xw - xf;
      const Real w = kernel_w<D>(KernelType::CubicSpline, norm(dx), h);
      if (w <= 0) continue;
      ++used;
      wall_sums_add<D>(sum, w, dx, p_of(xf), rho, Real(50), S);
    }
    ASSERT_GT(used, 3);
    const WallState st = wall_state<D>(sum, g);
    EXPECT_NEAR(st.p, p_of(xw), 1e-12 * std::fabs(p0) + 1e-12 * rho * 9.81 * h) << "trial " << trial;
    EXPECT_NEAR(st.rho, rho, 1e-12 * rho);
    EXPECT_NEAR(st.cs, 50.0, 1e-12 * 50.0);
    const Mat<D> Sw = wall_deviator<D>(sum);
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) EXPECT_NEAR(Sw.m[i][j], S.m[i][j], 1e-12 * 100);
  }
}

}  // namespace

// A wall particle above its neighbours (a wall rising past the material's
// free surface) takes their Shepard pressure: the hydrostatic field is not
// continued into a tension that would pull the material up the wall.
TEST(WallExtrapolation, NoTensionAboveTheMaterial) {
  WallSums<2> sum;
  wall_sums_add<2>(sum, Real(0.5), Vec<2>{0, 0.01}, Real(100), Real(2650), Real(16), Mat<2>::zero());
  wall_sums_add<2>(sum, Real(0.5), Vec<2>{0.004, 0.012}, Real(100), Real(2650), Real(16), Mat<2>::zero());
  const WallState st = wall_state<2>(sum, Vec<2>{0, -9.81});
  EXPECT_EQ(st.p, 100);
}

TEST(WallExtrapolation, HydrostaticPressureIsExact1D) { check_hydrostatic<1>(1); }
TEST(WallExtrapolation, HydrostaticPressureIsExact2D) { check_hydrostatic<2>(2); }
TEST(WallExtrapolation, HydrostaticPressureIsExact3D) { check_hydrostatic<3>(3); }

// Without a body force the wall pressure is the Shepard average of the
// neighbours' pressures: between their smallest and largest value.
TEST(WallExtrapolation, NoBodyForceIsAShepardAverage) {
  WallSums<2> sum;
  const Real ps[3] = {100, 250, 175};
  const Real ws[3] = {0.2, 0.5, 0.3};
  for (int k = 0; k < 3; ++k) wall_sums_add<2>(sum, ws[k], Vec<2>{Real(0.01 * k), Real(-0.01)}, ps[k], 1, 1, Mat<2>::zero());
  const WallState st = wall_state<2>(sum, Vec<2>::zero());
  EXPECT_NEAR(st.p, (0.2 * 100 + 0.5 * 250 + 0.3 * 175) / 1.0, 1e-12);
}
