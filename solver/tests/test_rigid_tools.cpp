// Rigid tools and the forces on walls (issue #54 items 1 and 2;
// physics/rigid_body.hpp, drivers/step_sequence.hpp, boundary_forces.csv):
// the rotation formulas; a turning tool keeps its shape to round-off over
// ten turns with either integrator; a driven block floats at Archimedes'
// depth carrying its weight; a floor under a column at rest carries the
// column's weight; the forces on all boundary bodies balance the
// material's momentum change at every evaluation; the scene keys' errors.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "rubble/drivers/cpu_stepper.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/physics/rigid_body.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "conserved_column.hpp"
#include "scene_error.hpp"

using namespace rubble;
using rubble::test::csv_column;
using rubble::test::parse_error;

namespace {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("rubble_rt_" + std::to_string(getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

template <int D>
struct Generated {
  ParticleStore<D> ps;
  std::vector<std::int64_t> first;  // body k holds ids [first[k], first[k+1])
};

template <int D>
Generated<D> generated(const Scene& scene) {
  Generated<D> g;
  g.first = generate_bodies<D>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), g.ps);
  return g;
}

const char* kWater = "[materials.water]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1000.0, K0 = 2.0e5, n = 7.0 }\n";

// A bar of 20 x 2 particles turning once a second about (2.5, 0) through
// a block of water that it hits from the first turn on.
std::string turning_bar(const std::string& integrator, double turns) {
  std::ostringstream s;
  s << "[simulation]\ndimension = 2\nend_time = " << turns << "\nintegrator = \"" << integrator << "\"\n" << kWater
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [2.2, 0.3]\nmax = [2.8, 0.6]\nspacing = 0.05\n"
       "density = 1000.0\npressure = 0.0\n"
       "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [2.0, -0.05]\nmax = [3.0, 0.05]\nspacing = 0.05\n"
       "density = 1000.0\npressure = 0.0\nboundary = \"moving\"\nangular_velocity = 6.283185307179586\n"
       "rotation_center = [2.5, 0.0]\n";
  return s.str();
}

// A 2-D tank of water, 0.8 m x 0.4 m, with a floor and side walls
// (extrapolated: they push with the water's pressure), and, optionally, a
// 0.2 m square block of half the water's density above its middle, free to
// move vertically only. Damped to rest over `end` seconds.
std::string tank(bool block, double end) {
  std::ostringstream s;
  s << "[simulation]\ndimension = 2\nend_time = " << end
    << "\nintegrator = \"leapfrog\"\ngravity = [0.0, -9.81]\ndamping_time = 0.05\ndamping_end = " << end << "\n"
    << kWater
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [0.8, 0.4]\nspacing = 0.02\n"
       "density = 1000.0\npressure = 0.0\n"
       "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [-0.06, -0.06]\nmax = [0.86, 0.0]\nspacing = 0.02\n"
       "density = 1000.0\npressure = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n"
       "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [-0.06, 0.0]\nmax = [0.0, 0.7]\nspacing = 0.02\n"
       "density = 1000.0\npressure = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n"
       "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.8, 0.0]\nmax = [0.86, 0.7]\nspacing = 0.02\n"
       "density = 1000.0\npressure = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n";
  if (block)
    s << "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.3, 0.42]\nmax = [0.5, 0.62]\nspacing = 0.02\n"
         "density = 1000.0\npressure = 0.0\nboundary = \"driven\"\nboundary_state = \"extrapolated\"\n"
         "tool_mass = 20.0\ndriven_axes = [false, true]\ndriven_rotation = false\n";
  s << "[output]\nsnapshots = false\n";
  return s.str();
}

// The last row of column `name` of boundary_forces.csv for body `body`.
double last_force(const std::filesystem::path& dir, int body, const std::string& name) {
  const std::vector<double> bodies = csv_column(dir / "boundary_forces.csv", "body");
  const std::vector<double> values = csv_column(dir / "boundary_forces.csv", name);
  for (std::size_t k = bodies.size(); k-- > 0;)
    if (int(bodies[k]) == body) return values.at(k);
  return NAN;
}

}  // namespace

// ---- the formulas ------------------------------------------------------------

TEST(RigidBody, RotationIsProperAndKeepsTheAxis) {
  const Real s = Real(1) / std::sqrt(Real(14));
  const Vec<3> n{{1 * s, 2 * s, 3 * s}};
  for (double theta : {0.3, 2.0, -1.1}) {
    const Mat<3> R = rotation_about<3>(n, Real(theta));
    const Mat<3> RtR = transpose(R) * R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(RtR[i][j], i == j ? 1.0 : 0.0, 1e-15);
    EXPECT_NEAR(determinant(R), 1.0, 1e-15);
    const Vec<3> Rn = R * n;
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(Rn[i], n[i], 1e-15);
  }
  // 2-D: counter-clockwise about z
  const Mat<2> R = rotation_about<2>(n, Real(M_PI / 2));
  const Vec<2> x = R * Vec<2>{{1, 0}};
  EXPECT_NEAR(x[0], 0.0, 1e-15);
  EXPECT_NEAR(x[1], 1.0, 1e-15);
}

// omega n x (R r0) is the time derivative of R(n, omega t) r0 (central
// differences, step 1e-5: error ~1e-10), in 2-D and 3-D.
TEST(RigidBody, TurningVelocityIsTheDerivativeOfTheRotation) {
  const Real s = Real(1) / std::sqrt(Real(3));
  const Vec<3> n{{s, -s, s}};
  const Real omega = 2.5, t = 0.7, e = 1e-5;
  const Vec<3> r0{{0.3, -1.2, 0.8}};
  const Vec<3> v = turning_velocity<3>(n, omega, rotation_about<3>(n, omega * t) * r0);
  const Vec<3> fd = (Real(0.5) / e) * (rotation_about<3>(n, omega * (t + e)) * r0 - rotation_about<3>(n, omega * (t - e)) * r0);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(v[k], fd[k], 1e-9);
  const Vec<2> q0{{0.3, -1.2}};
  const Vec<2> v2 = turning_velocity<2>(n, omega, rotation_about<2>(n, omega * t) * q0);
  const Vec<2> fd2 = (Real(0.5) / e) * (rotation_about<2>(n, omega * (t + e)) * q0 - rotation_about<2>(n, omega * (t - e)) * q0);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(v2[k], fd2[k], 1e-9);
}

TEST(RigidBody, StagesCombineLikeTheParticles) {
  RigidState<2> y0;
  y0.c = Vec<2>{{1, 2}};
  y0.V = Vec<2>{{3, 0}};
  y0.omega = 2;
  RigidRates<2> k0;
  k0.A = Vec<2>{{0, -10}};
  k0.alpha = 1;
  const RigidState<2> y = rigid_combine<2>(y0, y0, k0, nullptr, nullptr, 0.5);
  EXPECT_DOUBLE_EQ(y.c[0], 2.5);
  EXPECT_DOUBLE_EQ(y.c[1], 2.0);
  EXPECT_DOUBLE_EQ(y.theta, 1.0);
  EXPECT_DOUBLE_EQ(y.V[1], -5.0);
  EXPECT_DOUBLE_EQ(y.omega, 2.5);
  const bool free_y[3] = {false, true, true};
  const RigidRates<2> k = driven_rates<2>(Vec<2>{{4, 30}}, 6, Vec<2>{{1, 1}}, 2, Vec<2>{{0, -9}}, 2, 4, free_y, true);
  EXPECT_DOUBLE_EQ(k.A[0], 0.0);            // not free: keeps its velocity
  EXPECT_DOUBLE_EQ(k.A[1], 31.0 / 2 - 9);   // (F + F_applied)/M + g
  EXPECT_DOUBLE_EQ(k.alpha, 8.0 / 4);       // (T + T_applied)/I
}

// ---- whole runs ----------------------------------------------------------------

// Ten turns through water: every particle of the bar is where the rotation
// puts it, to round-off (the placement from its offset, never integrated),
// with both integrators.
TEST(RigidTools, ATurningToolKeepsItsShapeOverTenTurns) {
  for (const std::string integrator : {"leapfrog", "rk2_adaptive"}) {
    const Scene scene = parse_scene(turning_bar(integrator, 10.0), "bar.toml");
    Generated<2> g = generated<2>(scene);
    const std::int64_t lo = g.first[1], hi = g.first[2];
    std::vector<Vec<2>> x0(std::size_t(hi - lo));
    for (std::size_t i = 0; i < g.ps.n; ++i)
      if (g.ps.id[i] >= lo && g.ps.id[i] < hi) x0[std::size_t(g.ps.id[i] - lo)] = g.ps.x[i];
    CpuStepper<2> sys(scene, g.ps, domain_from_scene<2>(scene), false);
    double t = 0, dt = sys.dt_limit();
    const double end = 10.0;
    int steps = 0;
    while (t < end * (1 - 1e-12)) {
      dt = std::min(dt, end - t);
      if (integrator == "leapfrog") {
        sys.leapfrog(dt);
        t += dt;
        dt = sys.dt_limit();
      } else {
        const Rk2Result r = sys.rk2(dt, 1e-4, 1e-12);
        t += r.dt_taken;
        dt = std::min(double(r.dt_next), sys.dt_limit());
      }
      ++steps;
    }
    ASSERT_GT(steps, 1000) << integrator;
    const ParticleStore<2>& ps = sys.host();
    const Vec<3> z{{0, 0, 1}};
    const Mat<2> R = rotation_about<2>(z, Real(2 * M_PI * t));
    double worst = 0, worst_distance = 0;
    std::vector<Vec<2>> x1(x0.size());
    for (std::size_t i = 0; i < ps.n; ++i) {
      if (ps.id[i] < lo || ps.id[i] >= hi) continue;
      const std::size_t j = std::size_t(ps.id[i] - lo);
      x1[j] = ps.x[i];
      const Vec<2> c{{2.5, 0.0}};
      worst = std::max(worst, double(norm(ps.x[i] - (c + R * (x0[j] - c)))));
    }
    for (std::size_t a = 0; a < x0.size(); ++a)
      for (std::size_t b = a + 1; b < x0.size(); ++b)
        worst_distance = std::max(worst_distance, std::fabs(double(norm(x1[a] - x1[b]) - norm(x0[a] - x0[b]))));
    // round-off: the angle 2 pi t accumulated over ~1e4 steps (~1e-12 rad)
    // times the bar's 0.5 m
    EXPECT_LT(worst, 1e-10) << integrator;
    EXPECT_LT(worst_distance, 1e-14) << integrator;
  }
}

// A floor under a column of water at rest carries the column's weight:
// its force in boundary_forces.csv is m g to 1 % (issue #54 item 2; the
// residual motion after the damping sets the error).
TEST(RigidTools, AFloorUnderAColumnCarriesItsWeight) {
  TempDir dir("column");
  const std::string text =
      std::string("[simulation]\ndimension = 2\nend_time = 1.5\nintegrator = \"leapfrog\"\ngravity = [0.0, -9.81]\n"
                  "damping_time = 0.05\ndamping_end = 1.5\n") +
      kWater +
      "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [0.2, 0.4]\nspacing = 0.02\n"
      "density = 1000.0\npressure = 0.0\n"
      "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, -0.06]\nmax = [0.2, 0.0]\nspacing = 0.02\n"
      "density = 1000.0\npressure = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n"
      "[domain]\nperiodic = [true, false]\nmin = [0.0, -1.0]\nmax = [0.2, 1.0]\n"
      "[output]\nsnapshots = false\n";
  RunOptions opt;
  opt.out_dir = dir.path.string();
  opt.quiet = true;
  run_scene(parse_scene(text, "column.toml"), opt);
  const double weight = 1000.0 * 0.2 * 0.4 * 9.81;  // the column's particles: 10 x 20 of 0.4 kg/m
  EXPECT_NEAR(last_force(dir.path, 1, "force_y"), -weight, 0.01 * weight);
  EXPECT_NEAR(last_force(dir.path, 1, "force_x"), 0.0, 0.01 * weight);
}

// A driven block of half the water's density, dropped on the tank, comes
// to rest floating: the water carries its weight (its force in
// boundary_forces.csv balances M g to 1 %), it is at rest (below 1 % of
// the free-fall speed over its own height, sqrt(2 g 0.2 m) = 2 m/s), and
// half its height is under the free surface (Archimedes) to within one
// smoothing length h, the width over which SPH smears a surface (measured:
// 0.087 m instead of 0.1 m at h = 1.3 dx = 0.026 m: the block's bottom
// feels the water a little beyond its edges, a resolution effect).
TEST(RigidTools, ADrivenBlockFloatsAtArchimedesDepth) {
  TempDir dir("float");
  RunOptions opt;
  opt.out_dir = dir.path.string();
  opt.quiet = true;
  const Scene scene = parse_scene(tank(true, 3.0), "tank.toml");
  const FinalState fs = run_scene(scene, opt);
  const double M = 20.0, g = 9.81, dx = 0.02, h = smoothing_factor(scene.simulation) * dx;
  EXPECT_NEAR(last_force(dir.path, 4, "force_y"), M * g, 0.01 * M * g);
  EXPECT_NEAR(last_force(dir.path, 4, "velocity_y"), 0.0, 0.01 * std::sqrt(2 * g * 0.2));
  // the free surface away from the block: the top free particle + dx/2
  double surface = -1;
  for (std::size_t i = 0; i < fs.m.size(); ++i) {
    const double x = fs.x[2 * i], y = fs.x[2 * i + 1];
    if (fs.boundary[i] == 0 && (x < 0.15 || x > 0.65)) surface = std::max(surface, y + 0.5 * dx);
  }
  const double bottom = last_force(dir.path, 4, "point_y") - 0.1;  // the block is 0.2 m high about its centre
  EXPECT_NEAR(surface - bottom, 0.1, h) << "surface " << surface << ", block bottom " << bottom;
}

// At any evaluation the forces on all boundary bodies balance the free
// particles' momentum change: sum_free m dv/dt = M_free g - sum_bodies F
// (pair forces are antisymmetric; no-slip walls), to round-off.
TEST(RigidTools, WallForcesBalanceTheMaterialsMomentumChange) {
  const Scene scene = parse_scene(tank(true, 0.2), "tank.toml");
  Generated<2> g = generated<2>(scene);
  CpuStepper<2> sys(scene, g.ps, domain_from_scene<2>(scene), false);
  for (int k = 0; k < 30; ++k) sys.leapfrog(sys.dt_limit());
  const ParticleStore<2>& ps = sys.host();
  double dp[2] = {0, 0}, scale = 0, M = 0;
  for (std::size_t i = 0; i < ps.n; ++i) {
    if (ps.boundary[i] != 0) continue;
    M += double(ps.m[i]);
    for (int k = 0; k < 2; ++k) dp[k] += double(ps.m[i]) * double(ps.dvdt[i][k]);
    scale += double(ps.m[i]) * double(norm(ps.dvdt[i]));
  }
  double walls[2] = {0, 0};
  for (std::size_t b = 1; b < 5; ++b) {
    const ForceSums<2> f = sys.held_force(std::int32_t(g.first[b]), std::int32_t(g.first[b + 1]), Vec<2>::zero());
    for (int k = 0; k < 2; ++k) walls[k] += f.F[k];
  }
  ASSERT_GT(std::fabs(walls[1]), 0.1 * M * 9.81) << "the walls carry nothing: no case";
  EXPECT_NEAR(dp[0], -walls[0], 1e-12 * scale);
  EXPECT_NEAR(dp[1], -M * 9.81 - walls[1], 1e-12 * scale);
}

// ---- the scene keys ----------------------------------------------------------

TEST(RigidTools, SceneKeysAreCheckedWithTheirNames) {
  const std::string head = std::string("[simulation]\ndimension = 2\nend_time = 1.0\n") + kWater +
                           "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n"
                           "spacing = 0.1\ndensity = 1000.0\npressure = 0.0\n";
  const std::string tool = "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [2.0, 0.0]\nmax = [3.0, 0.2]\n"
                           "spacing = 0.1\ndensity = 1000.0\npressure = 0.0\n";
  EXPECT_EQ(parse_error(head + tool + "boundary = \"moving\"\nangular_velocity = 1.0\n"), "");
  EXPECT_EQ(parse_error(head + tool + "boundary = \"driven\"\napplied_force = [0.0, -5.0]\n"), "");
  auto has = [](const std::string& msg, const std::string& part) {
    return msg.find(part) != std::string::npos;
  };
  std::string e = parse_error(head + tool + "angular_velocity = 1.0\n");
  EXPECT_TRUE(has(e, "bodies[1].angular_velocity")) << e;
  e = parse_error(head + tool + "boundary = \"moving\"\nangular_velocity = 1.0\nrotation_axis = [0.0, 0.0, 1.0]\n");
  EXPECT_TRUE(has(e, "bodies[1].rotation_axis") && has(e, "2-D")) << e;
  e = parse_error(head + tool + "boundary = \"driven\"\nrotation_center = [2.5, 0.1]\n");
  EXPECT_TRUE(has(e, "bodies[1].rotation_center") && has(e, "centre of mass")) << e;
  e = parse_error(head + tool + "boundary = \"moving\"\napplied_force = [0.0, 1.0]\n");
  EXPECT_TRUE(has(e, "bodies[1].applied_force") && has(e, "driven")) << e;
  e = parse_error(head + tool + "boundary = \"driven\"\ntool_mass = -1.0\n");
  EXPECT_TRUE(has(e, "bodies[1].tool_mass")) << e;
  e = parse_error(head + tool + "boundary = \"driven\"\nwall_slip = \"free_slip\"\nwall_normal = [0.0, 1.0]\n");
  EXPECT_TRUE(has(e, "bodies[1].wall_slip")) << e;
  e = parse_error(head + tool + "boundary = \"moving\"\nangular_velocity = 1.0\nvelocity_gradient = [[0.0, 1.0], [0.0, 0.0]]\n");
  EXPECT_TRUE(has(e, "bodies[1].velocity_gradient")) << e;
  e = parse_error(head + tool + "boundary = \"driven\"\ndriven_axes = [true]\n");
  EXPECT_TRUE(has(e, "bodies[1].driven_axes")) << e;
  std::string nine = head;
  for (int k = 0; k < 9; ++k) nine += tool + "boundary = \"moving\"\nangular_velocity = 1.0\n";
  e = parse_error(nine);
  EXPECT_TRUE(has(e, "bodies[9]") && has(e, "at most 8")) << e;
}
