// Backend parity (issue #6 item 5; label `gpu`, built with -DRUBBLE_CUDA=ON,
// skipped where no GPU is present): the same scene on the CPU and CUDA
// backends.
//
// One step: every field of every particle agrees to 1e-12 of the field's
// scale (its largest magnitude over the particles), in double precision.
// Why a scale and not each value: both backends call the same loop bodies
// (drivers/particle_rates.hpp), but the CPU sums a particle's neighbours in
// ascending index order and the GPU in cell order, so each sum differs by
// a few rounding units of its largest terms - a field that nearly cancels
// (a velocity near zero inside a uniform region) can differ by much more
// than 1e-12 of its own tiny value, never of the field's scale. The
// particle order is the same (the same stable Morton sort from the same
// initial positions), so particles are compared index by index.
//
// A hundred steps: mass, momentum, kinetic and internal energy agree to
// 1e-9 of their scale (momentum: sum m|v|; energies: their total).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "rubble/run.hpp"

using namespace rubble;

namespace {

bool gpu_present() {
  return backend_built(Backend::Cuda) && gpu_description().rfind("none", 0) != 0;
}

FinalState run_on(const Scene& scene, Backend b) {
  RunOptions opt;
  opt.write_output = false;
  opt.quiet = true;
  opt.backend = b;
  return run_scene(scene, opt);
}

void expect_fields_agree(const FinalState& c, const FinalState& g, double tol, const std::string& what) {
  ASSERT_EQ(c.m.size(), g.m.size()) << what;
  ASSERT_EQ(c.steps, g.steps) << what;
  ASSERT_EQ(g.backend, "cuda");
  const std::vector<std::pair<std::string, std::pair<const std::vector<double>*, const std::vector<double>*>>> fields =
      {{"x", {&c.x, &g.x}},   {"v", {&c.v, &g.v}},   {"m", {&c.m, &g.m}},   {"rho", {&c.rho, &g.rho}},
       {"p", {&c.p, &g.p}},   {"u", {&c.u, &g.u}},   {"h", {&c.h, &g.h}},   {"cs", {&c.cs, &g.cs}}};
  for (const auto& [name, pair] : fields) {
    const std::vector<double>& a = *pair.first;
    const std::vector<double>& b = *pair.second;
    ASSERT_EQ(a.size(), b.size()) << what << " " << name;
    double scale = 0, worst = 0;
    for (double v : a) scale = std::max(scale, std::fabs(v));
    for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(a[i] - b[i]));
    if (scale == 0) EXPECT_EQ(worst, 0.0) << what << " " << name;
    else EXPECT_LE(worst / scale, tol) << what << ": field " << name << " differs by " << worst << " (scale " << scale << ")";
  }
}

struct Totals {
  double mass = 0, momentum[3] = {0, 0, 0}, momentum_scale = 0, kinetic = 0, internal = 0;
};

Totals totals(const FinalState& s) {
  Totals t;
  const int D = s.dimension;
  for (std::size_t i = 0; i < s.m.size(); ++i) {
    double v2 = 0;
    for (int k = 0; k < D; ++k) {
      const double v = s.v[i * D + k];
      t.momentum[k] += s.m[i] * v;
      v2 += v * v;
    }
    t.mass += s.m[i];
    t.momentum_scale += s.m[i] * std::sqrt(v2);
    t.kinetic += 0.5 * s.m[i] * v2;
    t.internal += s.m[i] * s.u[i];
  }
  return t;
}

void expect_conserved_agree(const FinalState& c, const FinalState& g, double tol, const std::string& what) {
  const Totals a = totals(c), b = totals(g);
  EXPECT_LE(std::fabs(a.mass - b.mass), tol * a.mass) << what;
  for (int k = 0; k < 3; ++k)
    EXPECT_LE(std::fabs(a.momentum[k] - b.momentum[k]), tol * std::max(a.momentum_scale, 1e-300)) << what << " p" << k;
  const double e = a.kinetic + a.internal;
  EXPECT_LE(std::fabs(a.kinetic - b.kinetic), tol * e) << what << " kinetic";
  EXPECT_LE(std::fabs(a.internal - b.internal), tol * e) << what << " internal";
}

// The scenes: 3-D hydro with summation density on a periodic box (the Sod
// tube), 2-D solids with artificial stress, XSPH and a clamp of evolving
// boundary particles (the oscillating plate), and 3-D self-gravity by direct
// summation and by the octree, with damping (a small polytrope) - between
// them every driver.
// Each runs `steps` steps of exactly dt: dt is below the Courant limit and
// the output interval (which bounds every step) is dt.
std::string src(const std::string& rel) { return std::string(RUBBLE_SOURCE_DIR) + "/" + rel; }

std::vector<std::string> steps_of(double dt, int steps) {
  return {"simulation.end_time=" + std::to_string(dt * steps), "output.interval=" + std::to_string(dt)};
}

Scene sod3d(int steps) {
  auto sets = steps_of(1e-3, steps);
  sets.insert(sets.end(), {"bodies.0.spacing=0.0625", "bodies.1.spacing=0.125"});
  return load_scene_file(src("verification/sod_shock_tube/sod_3d.toml"), sets);
}

Scene plate(int steps) {
  auto sets = steps_of(2e-6, steps);
  sets.insert(sets.end(), {"simulation.xsph=0.5", "bodies.0.velocity=[0.0, 1.0]"});
  return load_scene_file(src("validation/oscillating_plate/oscillating_plate.toml"), sets);
}

Scene polytrope(int steps) {
  auto sets = steps_of(1e-3, steps);
  sets.insert(sets.end(), {"bodies.0.particles=2000", "gravity.mode=\"direct\""});
  return load_scene_file(src("verification/polytrope/polytrope_n1.toml"), sets);
}

// Barnes-Hut: the GPU walks the tree once per particle, so the CPU does too
// (group_size = 1); both build the same tree (test_octree_build.cpp).
Scene polytrope_bh(int steps) {
  auto sets = steps_of(1e-3, steps);
  sets.insert(sets.end(), {"bodies.0.particles=2000", "gravity.group_size=1"});
  return load_scene_file(src("verification/polytrope/polytrope_n1.toml"), sets);
}

const std::vector<std::pair<std::string, Scene (*)(int)>> kScenes = {
    {"sod 3-D", sod3d}, {"plate", plate}, {"polytrope, direct gravity", polytrope},
    {"polytrope, Barnes-Hut", polytrope_bh}};

}  // namespace

TEST(BackendParity, OneStepFieldByField) {
  if (!gpu_present()) GTEST_SKIP() << "no GPU: " << gpu_description();
  for (const auto& [name, make] : kScenes) {
    const FinalState cpu = run_on(make(1), Backend::Cpu), gpu = run_on(make(1), Backend::Cuda);
    EXPECT_EQ(cpu.steps, 1) << name;
    expect_fields_agree(cpu, gpu, 1e-12, name);
  }
}

TEST(BackendParity, HundredStepsConservedQuantities) {
  if (!gpu_present()) GTEST_SKIP() << "no GPU: " << gpu_description();
  for (const auto& [name, make] : kScenes) {
    const FinalState cpu = run_on(make(100), Backend::Cpu), gpu = run_on(make(100), Backend::Cuda);
    EXPECT_EQ(cpu.steps, 100) << name;
    expect_conserved_agree(cpu, gpu, 1e-9, name);
  }
}
