// The step sequence written once (drivers/step_sequence.hpp, issue #51),
// run on the CPU with the backend's own pair loops declined: the
// gather loops of the sequence then run, those the CUDA backend runs for
// every scene. On the backend-parity scenes (gpu/parity_scenes.hpp: hydro,
// solids with either stress update, self-gravity, Drucker-Prager with
// extrapolated and Coulomb walls, particle shifting) one step of the two
// must agree to 1e-12 of each field's scale - the backend-parity test's
// bound (gpu/test_backend_parity.cpp): the same loop bodies, summed in
// another order. So the GPU's path through the sequence is checked on a
// machine without a GPU. (Where the CPU itself gathers - the viscosity
// switch, sliding walls, porosity - both runs take the same path; those
// scenes then check only that a step driven directly through the sequence
// equals the time loop's stepper's.) Checked to fail when the gather loops
// skip every 97th particle (Sod3D, Plate, Polytrope, GranularColumn).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gpu/parity_scenes.hpp"
#include "rubble/drivers/cpu_stepper.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/drivers/step_sequence.hpp"
#include "rubble/scene/initial_conditions.hpp"

using namespace rubble;

namespace {

// The CPU backend without its pair-once loops: every pass gathers.
template <int D>
class GatherOnlyBackend : public CpuBackend<D> {
 public:
  using CpuBackend<D>::CpuBackend;
  bool hydro_pair_once(const RhsContext<D>&) { return false; }
  bool solid_gradients_pair_once(const RhsContext<D>&, unsigned long long*) { return false; }
  bool solid_forces_pair_once(const RhsContext<D>&) { return false; }
};

template <int D>
ParticleStore<D> generated(const Scene& scene) {
  ParticleStore<D> ps;
  generate_bodies<D>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps);
  return ps;
}

// Largest |value| of a field over the particles, for the bound's scale.
double magnitude(Real x) { return std::fabs(double(x)); }
template <int D>
double magnitude(const Vec<D>& v) {
  return std::sqrt(double(norm2(v)));
}
template <int D>
double magnitude(const Mat<D>& m) {
  return std::sqrt(double(double_dot(m, m)));
}

template <class T>
void expect_field_agrees(const std::vector<T>& a, const std::vector<T>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  double scale = 0, worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) scale = std::max(scale, magnitude(a[i]));
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, magnitude(T(a[i] - b[i])));
  EXPECT_LE(worst, 1e-12 * scale) << what << ": largest difference " << worst << " at field scale " << scale;
}

template <int D>
void one_step_each_way(const Scene& scene, const std::string& name) {
  const Box<D> domain = domain_from_scene<D>(scene);
  const Real dt = Real(scene.output.interval);
  const bool leapfrog = scene.simulation.integrator == Integrator::Leapfrog;

  ParticleStore<D> pair_once = generated<D>(scene);
  CpuStepper<D> cpu(scene, pair_once, domain, /*resumed=*/false);
  if (leapfrog) cpu.leapfrog(double(dt));
  else cpu.rk2(double(dt), scene.simulation.rk2_tolerance, 1e-30);

  ParticleStore<D> gathered = generated<D>(scene);
  const RunPhysics physics = run_physics(scene);
  GatherOnlyBackend<D> backend(physics, gathered, domain);
  StepSequence<D, GatherOnlyBackend<D>> steps(physics, backend, domain);
  steps.sort_particles();
  steps.evaluate();
  if (leapfrog) steps.leapfrog(dt);
  else steps.rk2(dt, Real(scene.simulation.rk2_tolerance), Real(1e-30));

  expect_field_agrees(pair_once.x, gathered.x, name + " x");
  expect_field_agrees(pair_once.v, gathered.v, name + " v");
  expect_field_agrees(pair_once.u, gathered.u, name + " u");
  expect_field_agrees(pair_once.rho, gathered.rho, name + " rho");
  expect_field_agrees(pair_once.h, gathered.h, name + " h");
  expect_field_agrees(pair_once.p, gathered.p, name + " p");
  expect_field_agrees(pair_once.dvdt, gathered.dvdt, name + " dv/dt");
  expect_field_agrees(pair_once.dudt, gathered.dudt, name + " du/dt");
  expect_field_agrees(pair_once.S, gathered.S, name + " S");
  expect_field_agrees(pair_once.dSdt, gathered.dSdt, name + " dS/dt");
  expect_field_agrees(pair_once.alpha, gathered.alpha, name + " alpha");
  expect_field_agrees(pair_once.eps_p, gathered.eps_p, name + " eps_p");
  EXPECT_EQ(cpu.correction_fallbacks(), steps.correction_fallbacks()) << name;
  EXPECT_EQ(cpu.evaluations(), steps.evaluations()) << name;
}

}  // namespace

class StepSequenceGather : public ::testing::TestWithParam<parity::ParityScene> {};

TEST_P(StepSequenceGather, AgreesWithThePairOnceLoops) {
  const Scene scene = GetParam().make(1);
  switch (scene.simulation.dimension) {
    case 1: one_step_each_way<1>(scene, GetParam().name); break;
    case 2: one_step_each_way<2>(scene, GetParam().name); break;
    default: one_step_each_way<3>(scene, GetParam().name); break;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, StepSequenceGather, ::testing::ValuesIn(parity::scenes()),
                         [](const auto& info) { return std::string(info.param.name); });
