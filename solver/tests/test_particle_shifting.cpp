// Unit tests of particle shifting (physics/particle_shifting.hpp) on 2-D
// square lattices of spacing dp = 1 (unit density and mass, so V_b = 1):
// no shift inside a regular lattice; a particle pushed towards a neighbour
// is shifted away from it; no shift at rest; at a flat free surface no
// outward shift; the shift grows linearly with |v| dt up to its cap.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rubble/physics/kernels.hpp"
#include "rubble/physics/particle_shifting.hpp"

using namespace rubble;

namespace {

constexpr Real kH = 2.4;  // support radius (2.4 dp)

// Lattice points (i, j), |i| <= 6, j from jmin to 6, except (0, 0), which
// is the particle at `xa`.
ShiftSums<2> sums_at(const Vec<2>& xa, int jmin, KernelType k = KernelType::WendlandC2) {
  ShiftSums<2> s;
  s.C = kernel_w<2>(k, Real(0), kH);
  const Real w_dp = kernel_w<2>(k, Real(1), kH);
  for (int i = -6; i <= 6; ++i)
    for (int j = jmin; j <= 6; ++j) {
      if (i == 0 && j == 0) continue;
      const Vec<2> dx = xa - Vec<2>{Real(i), Real(j)};
      const Real r = norm(dx);
      if (r >= kH) continue;
      shift_sums_add<2>(s, Real(1), kernel_w<2>(k, r, kH), w_dp, kernel_grad<2>(k, dx, kH));
    }
  return s;
}

}  // namespace

TEST(ParticleShifting, RegularLatticeIsNotShifted) {
  for (KernelType k : {KernelType::CubicSpline, KernelType::WendlandC2}) {
    const ShiftSums<2> s = sums_at(Vec<2>{0, 0}, -6, k);
    const Vec<2> d = shifting_displacement<2>(s, Real(1), kH, Real(1), Real(0.01), Real(1));
    EXPECT_LT(norm(d), 1e-15);
  }
}

TEST(ParticleShifting, ACloseParticleMovesAwayFromItsNeighbour) {
  // particle a at (0.6, 0): 0.4 dp from the lattice point (1, 0)
  const Vec<2> xa{0.6, 0.0};
  const ShiftSums<2> s = sums_at(xa, -6);
  const Vec<2> d = shifting_displacement<2>(s, Real(1), kH, Real(1), Real(0.01), Real(1));
  EXPECT_LT(d[0], 0);               // away from (1, 0), back towards its lattice site
  EXPECT_NEAR(d[1], 0, 1e-14);      // the lattice is symmetric in y
}

TEST(ParticleShifting, NoShiftAtRest) {
  const ShiftSums<2> s = sums_at(Vec<2>{0.6, 0.0}, -6);
  const Vec<2> d = shifting_displacement<2>(s, Real(1), kH, Real(0), Real(0.01), Real(1));
  EXPECT_EQ(norm(d), 0);
}

TEST(ParticleShifting, NoOutwardShiftAtAFreeSurface) {
  // the top row of a half lattice (j <= 0): nothing above y = 0
  auto below = [](const Vec<2>& xa) {
    ShiftSums<2> s;
    const KernelType k = KernelType::WendlandC2;
    s.C = kernel_w<2>(k, Real(0), kH);
    const Real w_dp = kernel_w<2>(k, Real(1), kH);
    for (int i = -6; i <= 6; ++i)
      for (int j = -6; j <= 0; ++j) {
        if (i == 0 && j == 0) continue;
        const Vec<2> dx = xa - Vec<2>{Real(i), Real(j)};
        const Real r = norm(dx);
        if (r < kH) shift_sums_add<2>(s, Real(1), kernel_w<2>(k, r, kH), w_dp, kernel_grad<2>(k, dx, kH));
      }
    return s;
  };
  const ShiftSums<2> flat = below(Vec<2>{0, 0});
  ASSERT_LT(flat.C, kShiftSurfaceC);
  const Vec<2> d = shifting_displacement<2>(flat, Real(1), kH, Real(1), Real(0.01), Real(1));
  EXPECT_LE(d[1], 1e-15);  // not pushed out of the surface
  // a surface particle pushed towards its right neighbour still moves away from it
  const Vec<2> d2 = shifting_displacement<2>(below(Vec<2>{0.6, 0}), Real(1), kH, Real(1), Real(0.01), Real(1));
  EXPECT_LT(d2[0], 0);
}

TEST(ParticleShifting, LinearInSpeedTimesStepUpToTheCap) {
  const ShiftSums<2> s = sums_at(Vec<2>{0.6, 0.0}, -6);
  const Vec<2> d1 = shifting_displacement<2>(s, Real(1), kH, Real(1), Real(1e-4), Real(1));
  const Vec<2> d2 = shifting_displacement<2>(s, Real(1), kH, Real(2), Real(1e-4), Real(1));
  EXPECT_NEAR(d2[0], 2 * d1[0], 1e-14);
  const Vec<2> big = shifting_displacement<2>(s, Real(1), kH, Real(1e3), Real(1), Real(1));
  EXPECT_NEAR(norm(big), kShiftMaxFraction, 1e-14);  // capped at 0.1 dp
}
