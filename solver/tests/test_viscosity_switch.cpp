// The viscosity switch (physics/viscosity_switch.hpp; Morris & Monaghan
// 1997 with the bounded source of Rosswog et al. 2000):
//  - the rate: alpha - alpha_min decays as exp(-l c t / h) without
//    compression, and a constant compression drives alpha to the balance of
//    decay and source, (alpha_min/tau + S alpha_max)/(1/tau + S), below
//    alpha_max; beta scales with alpha;
//  - scene keys, defaults and errors;
//  - a run: a Sod tube with the switch allocates av_alpha (a run without it
//    does not), conserves momentum to round-off and energy as the constant
//    coefficients do, keeps alpha within [alpha_min, alpha_max], raises it
//    at the shock and leaves it at alpha_min in the undisturbed gas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>
#include <unistd.h>

#include "scene_error.hpp"
#include "rubble/core/error.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/physics/viscosity_switch.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/scene.hpp"

using namespace rubble;

TEST(ViscositySwitch, DecaysToItsFloorAtTheRateLcOverH) {
  const ViscositySwitchParams p{true, Real(0.1), Real(0.1)};
  const Real h = Real(0.01), c = Real(2), alpha_max = 1;
  const Real rate = p.decay * c / h;  // 1/tau = 20 /s
  // explicit Euler with dt = tau/1e4 against exp(-t/tau) over 3 tau:
  // Euler's relative error is ~ (t/tau) (dt/tau)/2 = 1.5e-4
  Real alpha = alpha_max;
  const Real dt = Real(1e-4) / rate;
  for (int i = 0; i < 30000; ++i) alpha += dt * viscosity_switch_rate(alpha, 0, h, c, alpha_max, p);
  const Real exact = p.alpha_min + (alpha_max - p.alpha_min) * std::exp(Real(-3));
  EXPECT_NEAR((alpha - p.alpha_min) / (exact - p.alpha_min), 1, 2e-4);
  // at the floor nothing changes; expansion (negative compression) is no source
  EXPECT_EQ(viscosity_switch_rate(p.alpha_min, 0, h, c, alpha_max, p), 0);
  EXPECT_EQ(viscosity_switch_rate(p.alpha_min, Real(-50), h, c, alpha_max, p), 0);
}

TEST(ViscositySwitch, CompressionDrivesItTowardsAlphaMax) {
  const ViscositySwitchParams p{true, Real(0.1), Real(0.1)};
  const Real h = Real(0.01), c = Real(2), alpha_max = Real(1.5);
  const Real inv_tau = p.decay * c / h;
  for (const Real S : {Real(1), Real(20), Real(1e4)}) {
    const Real balance = (p.alpha_min * inv_tau + S * alpha_max) / (inv_tau + S);
    EXPECT_NEAR(viscosity_switch_rate(balance, S, h, c, alpha_max, p), 0, 1e-12 * S * alpha_max);
    EXPECT_GT(viscosity_switch_rate(p.alpha_min, S, h, c, alpha_max, p), 0);
    EXPECT_LT(balance, alpha_max);
    // integrated from the floor it approaches the balance and never passes alpha_max
    Real alpha = p.alpha_min;
    const Real dt = Real(0.01) / (inv_tau + S);
    for (int i = 0; i < 2000; ++i) {
      alpha = integrated_switch_alpha(alpha, dt, viscosity_switch_rate(alpha, S, h, c, alpha_max, p));
      ASSERT_LE(alpha, alpha_max);
    }
    EXPECT_NEAR(alpha, balance, 1e-6 * balance) << "S = " << S;
  }
  // the bounds and beta's scaling
  EXPECT_EQ(viscosity_switch_bound(Real(0.05), alpha_max, p), p.alpha_min);
  EXPECT_EQ(viscosity_switch_bound(Real(2), alpha_max, p), alpha_max);
  EXPECT_EQ(viscosity_switch_bound(Real(0.7), alpha_max, p), Real(0.7));
  const ViscosityParams v = switched_viscosity(ViscosityParams{Real(1), Real(2)}, Real(0.25));
  EXPECT_EQ(v.alpha, Real(0.25));
  EXPECT_EQ(v.beta, Real(0.5));
}

namespace {

std::string sod_scene(const std::string& viscosity) {
  return std::string(R"([simulation]
dimension = 1
end_time = 0.2
integrator = "leapfrog"
density = "summation"
hfact = 2.0
[materials.gas]
eos = "ideal_gas"
gamma = 1.4
)") + viscosity + R"(
[[bodies]]
shape = "box"
material = "gas"
min = [-1.0]
max = [0.0]
spacing = 0.0125
density = 1.0
pressure = 1.0
[[bodies]]
shape = "box"
material = "gas"
min = [0.0]
max = [1.0]
spacing = 0.1
density = 0.125
pressure = 0.1
[domain]
periodic = [true]
min = [-1.0]
max = [1.0]
[output]
name = "sod"
interval = 0.2
)";
}

using rubble::test::parse_error;

}  // namespace

TEST(ViscositySwitch, SceneKeysDefaultsAndErrors) {
  const Scene plain = parse_scene(sod_scene(""), "t.toml");
  EXPECT_FALSE(plain.materials[0].viscosity.switch_on);
  const Scene s = parse_scene(sod_scene("viscosity = { switch = \"morris_monaghan\" }"), "t.toml");
  EXPECT_TRUE(s.materials[0].viscosity.switch_on);
  EXPECT_EQ(s.materials[0].viscosity.alpha, 1.0);  // alpha_max
  EXPECT_EQ(s.materials[0].viscosity.alpha_min, 0.1);
  EXPECT_EQ(s.materials[0].viscosity.decay, 0.1);
  const Scene t = parse_scene(
      sod_scene("viscosity = { alpha = 2.0, switch = \"morris_monaghan\", alpha_min = 0.05, decay = 0.2 }"), "t.toml");
  EXPECT_EQ(t.materials[0].viscosity.alpha, 2.0);
  EXPECT_EQ(t.materials[0].viscosity.alpha_min, 0.05);
  EXPECT_EQ(t.materials[0].viscosity.decay, 0.2);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"viscosity = { switch = \"cullen_dehnen\" }", "materials.gas.viscosity.switch"},
      {"viscosity = { alpha_min = 0.1 }", "materials.gas.viscosity.alpha_min"},
      {"viscosity = { decay = 0.1 }", "materials.gas.viscosity.decay"},
      {"viscosity = { switch = \"morris_monaghan\", decay = 0.0 }", "materials.gas.viscosity.decay"},
      {"viscosity = { switch = \"morris_monaghan\", decay = 2.0 }", "materials.gas.viscosity.decay"},
      {"viscosity = { switch = \"morris_monaghan\", alpha_min = -0.1 }", "materials.gas.viscosity.alpha_min"},
      {"viscosity = { switch = \"morris_monaghan\", alpha = 0.1 }", "materials.gas.viscosity.alpha"},
  };
  for (const auto& [table, key] : bad) {
    const std::string msg = parse_error(sod_scene(table));
    EXPECT_NE(msg.find("t.toml"), std::string::npos) << table << ": " << msg;
    EXPECT_NE(msg.find(key), std::string::npos) << table << ": " << msg;
  }
  // not with a solid in the scene
  std::string solid = sod_scene("viscosity = { switch = \"morris_monaghan\" }");
  solid.replace(solid.find("density = \"summation\""), 21, "density = \"continuity\"");
  solid += "[materials.rock]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\nshear_modulus = 0.5\n";
  const std::string msg = parse_error(solid);
  EXPECT_NE(msg.find("materials.gas.viscosity.switch"), std::string::npos) << msg;
}

TEST(ViscositySwitch, SodTubeRaisesAlphaAtTheShockOnly) {
  auto run = [](const std::string& viscosity, const std::string& name) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("rubble_avsw_" + std::to_string(getpid()) + "_" + name);
    std::filesystem::remove_all(dir);
    const Scene s = parse_scene(sod_scene(viscosity), "t.toml");
    RunOptions opt;
    opt.out_dir = dir.string();
    opt.quiet = true;
    run_scene(s, opt);
    ParticleStore<1> ps;
    SnapshotMeta meta;
    read_snapshot<1>((dir / snapshot_filename(s.output.name, 1)).string(), ps, meta);
    std::filesystem::remove_all(dir);
    EXPECT_NEAR(meta.time, 0.2, 1e-12);
    return ps;
  };
  const ParticleStore<1> plain = run("", "plain");
  EXPECT_TRUE(plain.av_alpha.empty());
  EXPECT_TRUE(plain.dav_alpha_dt.empty());
  const ParticleStore<1> sw = run("viscosity = { switch = \"morris_monaghan\" }", "switch");
  ASSERT_EQ(sw.av_alpha.size(), sw.n);
  // conservation: the pair viscosity stays antisymmetric with per-particle
  // coefficients (momentum to round-off); energy as the constant-alpha run
  // (test_run.cpp, Run.SodConservesMomentumAndEnergy: 1e-4)
  double mom = 0, mom_abs = 0, e = 0;
  for (std::size_t i = 0; i < sw.n; ++i) {
    mom += double(sw.m[i] * sw.v[i][0]);
    mom_abs += double(sw.m[i] * std::fabs(sw.v[i][0]));
    e += double(sw.m[i] * (Real(0.5) * sw.v[i][0] * sw.v[i][0] + sw.u[i]));
  }
  const double e0 = 1.0 * (1.0 / (0.4 * 1.0)) + 0.125 * (0.1 / (0.4 * 0.125));
  EXPECT_LT(std::fabs(mom), 1e-12 * mom_abs);
  EXPECT_LT(std::fabs(e - e0) / e0, 1e-4);
  // alpha within its bounds; raised at the shock (x_s = 0.35 at t = 0.2 for
  // Sod's states), at its floor in the undisturbed left gas between the
  // heads of the two rarefactions, -0.76 (from the periodic second
  // interface at x = -1) and -0.24. At the shock a particle crosses a front
  // ~3 h_M wide (~0.1) in ~0.06 s at -div v ~ 8 /s, so alpha reaches ~0.5
  // there; the check asks for more than 3 times the floor.
  Real at_shock = 0, far_left = 0;
  for (std::size_t i = 0; i < sw.n; ++i) {
    const Real x = sw.x[i][0], a = sw.av_alpha[i];
    ASSERT_GE(a, Real(0.1) * (1 - 1e-12));
    ASSERT_LE(a, Real(1));
    if (x > 0.3 && x < 0.4) at_shock = std::max(at_shock, a);
    if (x > -0.65 && x < -0.35) far_left = std::max(far_left, a);
  }
  EXPECT_GT(at_shock, 0.3);
  // the undisturbed gas sees only the weak sound waves of the start-up
  // (summation density at the initial jump): within 1 % of the range
  EXPECT_LT(far_left - 0.1, 0.01 * (1 - 0.1));
}
