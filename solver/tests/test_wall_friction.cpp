// Sliding walls, the formulas alone (physics/wall_friction.hpp; issue #12
// item 5): a sliding wall passes on only the normal part of the pair
// forces, and only when their sum pushes; Coulomb friction is mu times that
// push against the sliding direction while sliding faster than the stick
// speed, viscous with the stick rate below it, continuous across it, never
// reverses the sliding within a step the Courant limit allows, and heats by
// exactly the kinetic energy it removes. The whole-run checks (a block
// sliding on a Coulomb floor, on an incline below and above the friction
// angle) are in test_porous_plastic_run.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/physics/wall_friction.hpp"

using namespace rubble;

namespace {

Vec<2> v2(double x, double y) { return Vec<2>{Real(x), Real(y)}; }

// The friction alone: the reaction less the push.
Vec<2> friction(const WallContact<2>& w, const Vec<2>& va, Real k_max) {
  return wall_reaction<2>(w, va, k_max).dvdt - w.normal;
}

}  // namespace

TEST(WallContact, OnlyTheNormalPartsArePassedOnAndThePushIsTheirSum) {
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0.3, 2.0), v2(0, 1), Real(0.5), v2(0.1, 0));
  EXPECT_DOUBLE_EQ(w.normal[0], 0.0);  // the tangential 0.3 is dropped
  EXPECT_DOUBLE_EQ(w.normal[1], 2.0);
  EXPECT_DOUBLE_EQ(w.push, 2.0);
  EXPECT_DOUBLE_EQ(w.mu_push, 1.0);
  // a pair that pulls towards the wall (shear stress at the wall makes the
  // pairs' normal parts scatter about their sum) counts against the push
  wall_contact_add<2>(w, v2(-1.0, -0.5), v2(0, 1), Real(0.5), v2(0.3, 0));
  EXPECT_DOUBLE_EQ(w.normal[1], 1.5);
  EXPECT_DOUBLE_EQ(w.push, 1.5);
  EXPECT_DOUBLE_EQ(w.mu_push, 0.75);
  EXPECT_DOUBLE_EQ(w.velocity[0] / w.count, 0.2);  // the wall's mean velocity
  // the push is passed on (a particle at rest: no friction)
  const WallReaction<2> r = wall_reaction<2>(w, v2(0.2, 0), 100);
  EXPECT_DOUBLE_EQ(r.dvdt[0], 0.0);
  EXPECT_DOUBLE_EQ(r.dvdt[1], 1.5);
  // an oblique wall: the part along its normal
  WallContact<2> o;
  const Real s = Real(1) / std::sqrt(Real(2));
  wall_contact_add<2>(o, v2(1.0, 0.0), v2(s, s), Real(0), v2(0, 0));
  EXPECT_NEAR(o.normal[0], 0.5, 1e-15);
  EXPECT_NEAR(o.normal[1], 0.5, 1e-15);
  EXPECT_NEAR(o.push, s, 1e-15);
}

TEST(WallContact, AWallThatWouldPullDoesNothing) {
  // a particle in tension next to the wall: its pairs with the wall pull
  // it towards it on the whole; a wall holds material, it does not stick
  WallContact<2> pulled;
  wall_contact_add<2>(pulled, v2(0.2, 1.0), v2(0, 1), Real(0.5), v2(0, 0));
  wall_contact_add<2>(pulled, v2(0.0, -1.5), v2(0, 1), Real(0.5), v2(0, 0));
  const WallReaction<2> r = wall_reaction<2>(pulled, v2(1, 0), 100);
  EXPECT_DOUBLE_EQ(r.dvdt[0], 0.0);
  EXPECT_DOUBLE_EQ(r.dvdt[1], 0.0);
  EXPECT_DOUBLE_EQ(r.dudt, 0.0);
  const WallReaction<2> none = wall_reaction<2>(WallContact<2>{}, v2(1, 0), 100);
  EXPECT_DOUBLE_EQ(none.dvdt[0], 0.0);
  EXPECT_DOUBLE_EQ(none.dvdt[1], 0.0);
}

TEST(WallFriction, SlidingIsCoulombsLawAgainstTheSlidingDirection) {
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0, 0));  // N = 4, mu N = 1.2
  const Real k_max = 100;  // stick speed mu N / k_max = 0.012
  for (double vx : {0.02, 0.5, -3.0}) {
    const Vec<2> va = v2(vx, 0.7);  // the normal velocity plays no part
    const Vec<2> f = friction(w, va, k_max);
    EXPECT_NEAR(f[0], -std::copysign(1.2, vx), 1e-14) << vx;
    EXPECT_NEAR(f[1], 0.0, 1e-15);
    // heating = the kinetic energy the friction removes (wall at rest)
    EXPECT_NEAR(wall_reaction<2>(w, va, k_max).dudt, 1.2 * std::fabs(vx), 1e-13) << vx;
  }
  // relative to a moving wall: a particle moving with the wall has none
  WallContact<2> m;
  wall_contact_add<2>(m, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0.5, 0));
  EXPECT_DOUBLE_EQ(friction(m, v2(0.5, -0.2), k_max)[0], 0.0);
  EXPECT_NEAR(friction(m, v2(1.5, 0), k_max)[0], -1.2, 1e-14);
}

TEST(WallFriction, BelowTheStickSpeedItIsViscousContinuousAndCannotReverse) {
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0, 0));
  const Real k_max = 100;
  const Real v_stick = Real(1.2) / k_max;
  EXPECT_NEAR(friction(w, v2(0.25 * v_stick, 0), k_max)[0], -k_max * 0.25 * v_stick, 1e-15);
  // continuous at the stick speed
  EXPECT_NEAR(friction(w, v2(v_stick * (1 - 1e-9), 0), k_max)[0], friction(w, v2(v_stick * (1 + 1e-9), 0), k_max)[0],
              1e-8);
  // an explicit step the Courant limit allows (k_max dt <= C; C = 0.3, the
  // column collapse's) never reverses the sliding, at any speed
  const Real dt = Real(0.3) / k_max;
  for (double vx : {1e-6, 0.3 * v_stick, v_stick, 3 * v_stick, 1.0}) {
    const Real after = Real(vx) + dt * friction(w, v2(vx, 0), k_max)[0];
    EXPECT_GE(after, 0.0) << vx;
    EXPECT_LT(after, vx) << vx;
  }
  // at rest: none
  EXPECT_DOUBLE_EQ(friction(w, v2(0, 0), k_max)[0], 0.0);
  EXPECT_DOUBLE_EQ(wall_reaction<2>(w, v2(0, 0), k_max).dudt, 0.0);
}

TEST(WallFriction, AFreeSlipWallHasNone) {
  WallContact<2> frictionless;
  wall_contact_add<2>(frictionless, v2(0, 4.0), v2(0, 1), Real(0), v2(0, 0));
  EXPECT_DOUBLE_EQ(friction(frictionless, v2(1, 0), 100)[0], 0.0);
  EXPECT_DOUBLE_EQ(wall_reaction<2>(frictionless, v2(1, 0), 100).dudt, 0.0);
}

TEST(WallFriction, TwoWallsOfACornerActAlongTheirMeanNormal) {
  // a particle in a corner pushed equally by a floor (n = y) and a wall
  // (n = x): the push's direction is the diagonal; sliding along the other
  // diagonal meets mu (N1 + N2)
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 1.0), v2(0, 1), Real(0.5), v2(0, 0));
  wall_contact_add<2>(w, v2(1.0, 0), v2(1, 0), Real(0.5), v2(0, 0));
  const Vec<2> f = friction(w, v2(1.0, -1.0), 1e6);
  const Real s = Real(1) / std::sqrt(Real(2));
  EXPECT_NEAR(f[0], -1.0 * s, 1e-14);
  EXPECT_NEAR(f[1], 1.0 * s, 1e-14);
}
