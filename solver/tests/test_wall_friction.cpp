// Sliding walls, the formulas alone (physics/wall_friction.hpp; issue #12
// item 5): a sliding wall passes on only the normal part of the pair
// forces, and only when their sum pushes; Coulomb friction is mu times that
// push against the sliding direction when the particle slips, and the
// damped spring to its anchor when that holds it; the anchor follows a
// slip so that the spring pulls exactly mu N, and is the particle's
// position off the walls. The whole-run checks (a block
// sliding on a Coulomb floor, on an incline below and above the friction
// angle) are in test_porous_plastic_run.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/physics/wall_friction.hpp"

using namespace rubble;

namespace {

Vec<2> v2(double x, double y) { return Vec<2>{Real(x), Real(y)}; }

// The friction alone: the reaction less the push (spring stretch d).
Vec<2> friction(const WallContact<2>& w, const Vec<2>& va, Real omega, const Vec<2>& d = v2(0, 0)) {
  return wall_reaction<2>(w, va, d, omega).dvdt - w.normal;
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
  const WallReaction<2> r = wall_reaction<2>(w, v2(0.2, 0), v2(0, 0), 100);
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
  const WallReaction<2> r = wall_reaction<2>(pulled, v2(1, 0), v2(0.1, 0), 100);
  EXPECT_DOUBLE_EQ(r.dvdt[0], 0.0);
  EXPECT_DOUBLE_EQ(r.dvdt[1], 0.0);
  EXPECT_DOUBLE_EQ(r.dudt, 0.0);
  EXPECT_DOUBLE_EQ(norm(r.grip), 0.0);  // and no grip: the anchor goes back to the particle
  const WallReaction<2> none = wall_reaction<2>(WallContact<2>{}, v2(1, 0), v2(0, 0), 100);
  EXPECT_DOUBLE_EQ(none.dvdt[0], 0.0);
  EXPECT_DOUBLE_EQ(none.dvdt[1], 0.0);
}

TEST(WallFriction, SlippingIsCoulombsLawAgainstTheSlidingDirection) {
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0, 0));  // N = 4, mu N = 1.2
  const Real omega = 100;  // a relaxed spring slips above |v_t| = mu N / (2 omega) = 0.006
  for (double vx : {0.02, 0.5, -3.0}) {
    const Vec<2> va = v2(vx, 0.7);  // the normal velocity plays no part
    // with the spring relaxed and with it stretched to its cap behind the particle
    for (const Vec<2>& d : {v2(0, 0), v2(std::copysign(1.2 / (omega * omega), vx), 0.05)}) {
      const WallReaction<2> r = wall_reaction<2>(w, va, d, omega);
      EXPECT_NEAR(r.dvdt[0], -std::copysign(1.2, vx), 1e-13) << vx;
      EXPECT_NEAR(r.dvdt[1], 4.0, 1e-15);  // the push
      // heating = the kinetic energy the friction removes (wall at rest)
      EXPECT_NEAR(r.dudt, 1.2 * std::fabs(vx), 1e-12) << vx;
      EXPECT_NEAR(r.grip[1], 1.2, 1e-15);
    }
  }
  // relative to a moving wall: a particle moving with the wall has none
  WallContact<2> m;
  wall_contact_add<2>(m, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0.5, 0));
  EXPECT_DOUBLE_EQ(friction(m, v2(0.5, -0.2), omega)[0], 0.0);
  EXPECT_NEAR(friction(m, v2(1.5, 0), omega)[0], -1.2, 1e-13);
}

TEST(WallFriction, StickingIsTheDampedSpringToTheAnchor) {
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 4.0), v2(0, 1), Real(0.3), v2(0, 0));
  const Real omega = 100, mu_n = 1.2;
  // at rest, stretched by half the cap: the spring pulls back, half mu N
  const Vec<2> held = friction(w, v2(0, 0), omega, v2(0.5 * mu_n / (omega * omega), 0.3));
  EXPECT_NEAR(held[0], -0.5 * mu_n, 1e-13);
  EXPECT_NEAR(held[1], 0.0, 1e-15);  // the stretch's normal part plays no part
  EXPECT_DOUBLE_EQ(wall_reaction<2>(w, v2(0, 0), v2(0.5 * mu_n / (omega * omega), 0), omega).dudt, 0.0);
  // slowly moving, relaxed: critical damping, heating by the damping's work
  const WallReaction<2> slow = wall_reaction<2>(w, v2(0.001, 0), v2(0, 0), omega);
  EXPECT_NEAR(slow.dvdt[0], -2 * omega * 0.001, 1e-15);
  EXPECT_NEAR(slow.dudt, 2 * omega * 0.001 * 0.001, 1e-15);
  // continuous where sticking turns into slipping
  const Real v_turn = mu_n / (2 * omega);
  EXPECT_NEAR(friction(w, v2(v_turn * (1 - 1e-9), 0), omega)[0], friction(w, v2(v_turn * (1 + 1e-9), 0), omega)[0],
              1e-8);
  // none at rest with the spring relaxed
  EXPECT_DOUBLE_EQ(friction(w, v2(0, 0), omega)[0], 0.0);
}

TEST(WallFriction, TheAnchorFollowsASlipAndLetsGoOffTheWall) {
  const Real omega = 100;
  const Vec<2> grip = v2(0, 1.2);  // mu N = 1.2 along the floor's normal
  const Real cap = Real(1.2) / (omega * omega);
  // within the cap: kept (its normal part dropped)
  const Vec<2> kept = wall_anchor_update<2>(v2(0.5 * cap, 0.01), grip, omega);
  EXPECT_NEAR(kept[0], 0.5 * cap, 1e-18);
  EXPECT_DOUBLE_EQ(kept[1], 0.0);
  // beyond it (the particle slipped): shortened to the cap, same direction
  const Vec<2> slipped = wall_anchor_update<2>(v2(-7 * cap, 0.01), grip, omega);
  EXPECT_NEAR(slipped[0], -cap, 1e-18);
  EXPECT_DOUBLE_EQ(slipped[1], 0.0);
  // no grip (off the walls, or a free-slip wall): the anchor is the particle
  const Vec<2> off = wall_anchor_update<2>(v2(3 * cap, 0), v2(0, 0), omega);
  EXPECT_DOUBLE_EQ(off[0], 0.0);
  EXPECT_DOUBLE_EQ(off[1], 0.0);
}

TEST(WallFriction, AFreeSlipWallHasNone) {
  WallContact<2> frictionless;
  wall_contact_add<2>(frictionless, v2(0, 4.0), v2(0, 1), Real(0), v2(0, 0));
  EXPECT_DOUBLE_EQ(friction(frictionless, v2(1, 0), 100, v2(0.1, 0))[0], 0.0);
  const WallReaction<2> r = wall_reaction<2>(frictionless, v2(1, 0), v2(0.1, 0), 100);
  EXPECT_DOUBLE_EQ(r.dudt, 0.0);
  EXPECT_DOUBLE_EQ(norm(r.grip), 0.0);
}

TEST(WallFriction, TwoWallsOfACornerActAlongTheirMeanNormal) {
  // a particle in a corner pushed equally by a floor (n = y) and a wall
  // (n = x): the push's direction is the diagonal; sliding along the other
  // diagonal meets mu (N1 + N2)
  WallContact<2> w;
  wall_contact_add<2>(w, v2(0, 1.0), v2(0, 1), Real(0.5), v2(0, 0));
  wall_contact_add<2>(w, v2(1.0, 0), v2(1, 0), Real(0.5), v2(0, 0));
  const Vec<2> f = friction(w, v2(1.0, -1.0), 1e3);
  const Real s = Real(1) / std::sqrt(Real(2));
  EXPECT_NEAR(f[0], -1.0 * s, 1e-14);
  EXPECT_NEAR(f[1], 1.0 * s, 1e-14);
}
