// Unit tests of the analytic two-wave piston-compaction solution
// (rubble/reference/porous_piston.hpp), the reference of the
// p_alpha_compaction rung (Jutzi, Benz & Michel 2008, Icarus 198:242, §5.1).
//
// Tolerances: the solution is built by bisection to the last bit and an RK4
// path of 4000 steps, so the jump conditions, written here in the
// conservation form (independent of the Hugoniot form the solver of the
// reference uses), hold to 1e-12 relative; the EOS and crush-curve
// consistency of the end states to 1e-10 (bisection on rho leaves the
// pressure exact to ~1e-15 of A·(drho/rho)). Physical bounds (Lax entropy
// condition, monotonicity) are inequalities.
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/porosity.hpp"
#include "rubble/reference/porous_piston.hpp"

namespace {

using namespace rubble;

// Aluminium, Tillotson (reference_data/materials/aluminium.toml; Melosh 1989).
EosParams aluminium() {
  EosParams m;
  m.kind = EosKind::Tillotson;
  m.tillotson = TillotsonParams{2700, 7.52e10, 6.5e10, 5.0e6, 3.0e6, 1.39e7, 0.5, 1.63, 5, 5};
  return m;
}

// Porous aluminium of Jutzi et al. 2008 §5.1 (PHYSICS.md §4).
PorosityParams jutzi_al() {
  PorosityParams q;
  q.enabled = true;
  q.curve = CrushCurve::Quadratic;
  q.alpha_e = 1.275;
  q.p_e = 8e7;
  q.p_s = 7e8;
  q.n2 = 2;
  q.c_e = 4110;
  q.c_s0 = 5350;
  return q;
}

constexpr double kRho0 = 2700 / 1.275;

void expect_jump_exact(const PorousPistonState& a, const PorousPistonState& b, double U, const char* what) {
  const JumpResiduals r = porous_jump_residuals(a, b, U);
  EXPECT_LT(std::fabs(r.mass), 1e-12) << what << " mass";
  EXPECT_LT(std::fabs(r.momentum), 1e-12) << what << " momentum";
  EXPECT_LT(std::fabs(r.energy), 1e-12) << what << " energy";
}

TEST(PorousPiston, JutziAluminiumJumpConditionsHold) {
  const PorousPiston pp(aluminium(), jutzi_al(), kRho0, 0.0, 458.0);
  const PorousPistonSolution& s = pp.solution();
  ASSERT_TRUE(s.two_waves);
  expect_jump_exact(s.initial, s.elastic, s.elastic_speed, "elastic precursor");
  expect_jump_exact(s.elastic, s.compacted, s.compaction_speed, "compaction shock");
  // the piston's velocity behind the compaction shock; p_e behind the precursor
  EXPECT_DOUBLE_EQ(s.compacted.v, 458.0);
  // the precursor carries the envelope's kink: on both curves, just above p_e
  EXPECT_DOUBLE_EQ(s.elastic.p, s.p_kink);
  EXPECT_GT(s.p_kink, 8e7);
  EXPECT_LT(s.p_kink, 8.2e7);
  // two separate fronts, the precursor ahead
  EXPECT_GT(s.elastic_speed, s.compaction_speed);
  EXPECT_GT(pp.elastic_front(3.5e-6), pp.compaction_front(3.5e-6));
  EXPECT_GT(pp.compaction_front(3.5e-6), 0.0);
}

TEST(PorousPiston, EndStatesLieOnTheEosAndTheCrushCurve) {
  const EosParams m = aluminium();
  const PorosityParams q = jutzi_al();
  const PorousPiston pp(m, q, kRho0, 0.0, 458.0);
  const PorousPistonSolution& s = pp.solution();
  for (const PorousPistonState* st : {&s.elastic, &s.compacted}) {
    const double p = porous_eos_evaluate(m, q, st->rho, st->u, st->alpha).p;
    EXPECT_NEAR(p, st->p, 1e-10 * st->p);
  }
  // 458 m/s crushes the aluminium completely (p_S > p_s): alpha = 1, and the
  // porous EOS reduces to the matrix EOS, so the compacted state is a point
  // of the plain Tillotson Hugoniot centred on the elastic state
  EXPECT_GT(s.compacted.p, q.p_s);
  EXPECT_EQ(s.compacted.alpha, 1.0);
  EXPECT_NEAR(eos_evaluate(m, s.compacted.rho, s.compacted.u).p, s.compacted.p, 1e-10 * s.compacted.p);
  // the elastic state: on the virgin elastic curve, below alpha0 by ~1e-3
  EXPECT_LT(s.elastic.alpha, q.alpha_e);
  EXPECT_GT(s.elastic.alpha, q.alpha_e - 2e-3);
  // (to 1e-6: the rate law decides its branch with kPorosityCurveRelTol =
  // 1e-8, and the last stretch of the path before the kink takes the
  // crush curve's slope once within that tolerance of it)
  EXPECT_NEAR(porosity_elastic_curve_pressure(m, q, s.elastic.alpha), s.p_kink, 1e-3 * q.p_e);
  EXPECT_NEAR(crush_curve_alpha(q, s.p_kink), s.elastic.alpha, 1e-6);
}

TEST(PorousPiston, PrecursorIsAnAdmissibleElasticShock) {
  const EosParams m = aluminium();
  const PorosityParams q = jutzi_al();
  const PorousPiston pp(m, q, kRho0, 0.0, 458.0);
  const PorousPistonSolution& s = pp.solution();
  // Lax: faster than the small-amplitude speed ahead, slower than behind
  EXPECT_GT(s.c_path_elastic, s.c_path_initial);
  EXPECT_GT(s.elastic_speed, s.c_path_initial);
  EXPECT_LT(s.elastic_speed, s.c_path_elastic + s.elastic.v);
  // the small-amplitude speed of the elastic branch at rest: with the
  // matrix stiffness A (Tillotson at rho_s0, u = 0) and the branch's slope
  // dalpha/dp = (alpha²/K)(1 − 1/h²), K = rho_s0 c_s0², h = c_e/c_s0 at
  // alpha_e, dp/drho = (A/rho_s0)/(1 − (A/K)(1 − 1/h²)), which is c_e
  // exactly when A = K (here 4077 m/s against c_e = 4110: A/rho_s0 =
  // 5277² m²/s², c_s0 = 5350 m/s)
  const double A = 7.52e10, K = 2700 * q.c_s0 * q.c_s0, h = q.c_e / q.c_s0;
  const double c_expected = std::sqrt(A / 2700 / (1 - A / K * (1 - 1 / (h * h))));
  // (forward difference at rest: c_path_initial is O(1e-6) relative off)
  EXPECT_NEAR(s.c_path_initial, c_expected, 1e-4 * c_expected);
}

TEST(PorousPiston, SlowPistonGivesOneElasticWaveThatTendsToAcoustics) {
  const EosParams m = aluminium();
  const PorosityParams q = jutzi_al();
  const PorousPiston two(m, q, kRho0, 0.0, 458.0);
  const double vE = two.solution().elastic.v;
  // below v_E: a single elastic wave; just below, its pressure tends to p_k
  const PorousPiston near(m, q, kRho0, 0.0, vE * (1 - 1e-9));
  EXPECT_FALSE(near.solution().two_waves);
  EXPECT_NEAR(near.solution().elastic.p, two.solution().p_kink, 1e-6 * q.p_e);
  expect_jump_exact(near.solution().initial, near.solution().elastic, near.solution().elastic_speed, "near v_E");
  // a very slow piston: acoustic limit p = rho0 c V, U = c
  const double V = 1e-3;
  const PorousPiston slow(m, q, kRho0, 0.0, V);
  const double c = slow.solution().c_path_initial;
  EXPECT_NEAR(slow.solution().elastic_speed, c, 1e-5 * c);
  EXPECT_NEAR(slow.solution().elastic.p, kRho0 * c * V, 1e-5 * kRho0 * c * V);
}

TEST(PorousPiston, PartialCompactionEndsOnTheCrushCurve) {
  const EosParams m = aluminium();
  const PorosityParams q = jutzi_al();
  // a piston slow enough to end between p_e and p_s
  const PorousPiston pp(m, q, kRho0, 0.0, 120.0);
  const PorousPistonSolution& s = pp.solution();
  ASSERT_TRUE(s.two_waves);
  ASSERT_GT(s.compacted.p, q.p_e);
  ASSERT_LT(s.compacted.p, q.p_s);
  EXPECT_NEAR(s.compacted.alpha, crush_curve_alpha(q, s.compacted.p), 1e-14);
  EXPECT_GT(s.compacted.alpha, 1.0);
  EXPECT_LT(s.compacted.alpha, s.elastic.alpha);
  expect_jump_exact(s.elastic, s.compacted, s.compaction_speed, "partial compaction");
}

TEST(PorousPiston, CompactionPressureGrowsWithPistonSpeed) {
  const EosParams m = aluminium();
  const PorosityParams q = jutzi_al();
  double last_p = 0, last_rho = 0;
  for (double V : {50.0, 100.0, 200.0, 458.0, 1000.0}) {
    const PorousPistonSolution s = PorousPiston(m, q, kRho0, 0.0, V).solution();
    EXPECT_TRUE(s.two_waves && !s.overdriven) << V;
    EXPECT_GT(s.compacted.p, last_p) << V;
    EXPECT_GT(s.compacted.rho, last_rho) << V;
    EXPECT_LT(s.compaction_speed, s.elastic_speed) << V;
    last_p = s.compacted.p;
    last_rho = s.compacted.rho;
  }
}

TEST(PorousPiston, StrongDriveIsOneOverdrivenShock) {
  const PorousPistonSolution s = PorousPiston(aluminium(), jutzi_al(), kRho0, 0.0, 2000.0).solution();
  EXPECT_TRUE(s.overdriven);
  EXPECT_EQ(s.compacted.alpha, 1.0);
  EXPECT_GT(s.compaction_speed, 2000.0);
  expect_jump_exact(s.initial, s.compacted, s.compaction_speed, "overdriven shock");
}

TEST(PorousPiston, WallFrameSampling) {
  const PorousPiston pp(aluminium(), jutzi_al(), kRho0, 0.0, 458.0);
  const double t = 3.5e-6, xs = pp.compaction_front(t), xe = pp.elastic_front(t);
  EXPECT_DOUBLE_EQ(pp.sample_wall_frame(0.5 * xs, t).v, 0.0);  // at rest against the wall
  EXPECT_DOUBLE_EQ(pp.sample_wall_frame(0.5 * (xs + xe), t).p, pp.solution().p_kink);
  EXPECT_DOUBLE_EQ(pp.sample_wall_frame(2 * xe, t).v, -458.0);
  EXPECT_DOUBLE_EQ(pp.sample_wall_frame(2 * xe, t).alpha, 1.275);
}

TEST(PorousPiston, RejectsBadInput) {
  EXPECT_THROW(PorousPiston(aluminium(), jutzi_al(), kRho0, 0.0, -1.0), std::invalid_argument);
  PorosityParams q = jutzi_al();
  q.p_s = q.p_e;
  EXPECT_THROW(PorousPiston(aluminium(), q, kRho0, 0.0, 458.0), std::invalid_argument);
}

}  // namespace
