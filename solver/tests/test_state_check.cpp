// The state check (drivers/state_check.hpp, issue #13): each field's rule
// catches a bad value, a good state passes, and the first faulty field is
// the one reported.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "rubble/drivers/state_check.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/initial_conditions.hpp"

using namespace rubble;

namespace {

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();

// One particle with every field allocated and a valid state.
ParticleStore<2> one_particle() {
  Features all;
  all.continuity_density = all.summation_density = all.gravity = all.solid = all.boundary = all.xsph = true;
  all.porosity = all.plasticity = all.free_slip = all.wall_friction = all.inelastic_volume = true;
  ParticleStore<2> ps;
  ps.allocate(1, all);
  ps.rho[0] = 1;
  ps.h[0] = 0.1;
  ps.cs[0] = 1;
  ps.m[0] = 0.01;
  return ps;
}

int fault_of(ParticleStore<2>& ps) { return particle_fault<2>(ps.view(), 0); }

}  // namespace

TEST(StateCheck, AValidStatePasses) {
  ParticleStore<2> ps = one_particle();
  EXPECT_EQ(fault_of(ps), kStateOk);
  ps.cs[0] = 0;  // a cold ideal gas
  ps.u[0] = -1;  // u may be negative (a cold expanded Tillotson state)
  ps.eps_v[0] = -0.1;
  EXPECT_EQ(fault_of(ps), kStateOk);
}

TEST(StateCheck, EachRuleCatchesItsField) {
  struct Case {
    void (*spoil)(ParticleStore<2>&);
    int fault;
  };
  const Case cases[] = {
      {[](ParticleStore<2>& p) { p.x[0][1] = kNaN; }, kFaultPosition},
      {[](ParticleStore<2>& p) { p.v[0][0] = kInf; }, kFaultVelocity},
      {[](ParticleStore<2>& p) { p.rho[0] = 0; }, kFaultDensity},
      {[](ParticleStore<2>& p) { p.rho[0] = -1; }, kFaultDensity},
      {[](ParticleStore<2>& p) { p.h[0] = 0; }, kFaultSmoothingLength},
      {[](ParticleStore<2>& p) { p.h[0] = kInf; }, kFaultSmoothingLength},
      {[](ParticleStore<2>& p) { p.u[0] = kNaN; }, kFaultInternalEnergy},
      {[](ParticleStore<2>& p) { p.S[0][0][1] = kNaN; }, kFaultStress},
      {[](ParticleStore<2>& p) { p.alpha[0] = 0.99; }, kFaultDistention},
      {[](ParticleStore<2>& p) { p.eps_p[0] = -1e-3; }, kFaultPlasticStrain},
      {[](ParticleStore<2>& p) { p.eps_v[0] = kInf; }, kFaultInelasticVolume},
      {[](ParticleStore<2>& p) { p.p[0] = -kInf; }, kFaultPressure},
      {[](ParticleStore<2>& p) { p.cs[0] = -1; }, kFaultSoundSpeed},
      {[](ParticleStore<2>& p) { p.omega[0] = kNaN; }, kFaultGradH},
      {[](ParticleStore<2>& p) { p.dvdt[0][1] = kNaN; }, kFaultAcceleration},
      {[](ParticleStore<2>& p) { p.dudt[0] = kInf; }, kFaultEnergyRate},
      {[](ParticleStore<2>& p) { p.drhodt[0] = kNaN; }, kFaultDensityRate},
      {[](ParticleStore<2>& p) { p.dSdt[0][1][1] = kInf; }, kFaultStressRate},
      {[](ParticleStore<2>& p) { p.dalphadt[0] = kNaN; }, kFaultDistentionRate},
      {[](ParticleStore<2>& p) { p.phi[0] = kNaN; }, kFaultGravity},
  };
  for (const Case& c : cases) {
    ParticleStore<2> ps = one_particle();
    c.spoil(ps);
    EXPECT_EQ(fault_of(ps), c.fault) << state_fault_field(c.fault);
    EXPECT_FALSE(finite_particle<2>(ps.view(), 0));
    EXPECT_STRNE(state_fault_field(c.fault), "none");
  }
}

// The evolved state is reported before what is derived from it: a NaN
// density that made the pressure NaN is reported as the density.
TEST(StateCheck, TheCauseIsReportedBeforeItsConsequences) {
  ParticleStore<2> ps = one_particle();
  ps.rho[0] = kNaN;
  ps.p[0] = kNaN;
  ps.dvdt[0][0] = kNaN;
  EXPECT_EQ(fault_of(ps), kFaultDensity);
  EXPECT_STREQ(state_fault_requirement(kFaultDensity), "finite and > 0");
}

// Fields a run does not allocate are not checked (and not touched).
TEST(StateCheck, UnallocatedFieldsAreSkipped) {
  ParticleStore<2> ps;
  ps.allocate(1, Features{});
  ps.rho[0] = 1;
  ps.h[0] = 0.1;
  EXPECT_EQ(fault_of(ps), kStateOk);
}

// Messages name a particle's body from its id (generate_bodies' body_first).
TEST(StateCheck, BodyOfId) {
  const std::vector<std::int64_t> first = {0, 10, 10, 25};  // body 1 is empty
  EXPECT_EQ(body_of_id(first, 0), 0u);
  EXPECT_EQ(body_of_id(first, 9), 0u);
  EXPECT_EQ(body_of_id(first, 10), 2u);
  EXPECT_EQ(body_of_id(first, 24), 2u);
  EXPECT_EQ(body_of_id({}, 5), 0u);
  EXPECT_EQ(body_of_id({0, 7}, 3), 0u);
}
