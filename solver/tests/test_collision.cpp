// Collision geometry (scene/collision.hpp; issue #52 item 3): the orbit traced
// back from contact reaches contact again, at the stated speed and angle, when
// the two-body problem is integrated forward from its start (RK4, the crossing
// of the contact distance found by bisection of the last step); the placed
// bodies have zero total momentum and their centres where the orbit starts;
// bad [collision] tables are refused with the key.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <cmath>
#include <string>
#include <vector>

#include "rubble/drivers/run_physics.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/collision.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "scene_error.hpp"

using namespace rubble;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct State {
  std::array<double, 3> x, v;
};

State rk4(const State& s, double mu, double dt) {
  auto acc = [&](const std::array<double, 3>& x) {
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    const double f = -mu / (r * r * r);
    return std::array<double, 3>{f * x[0], f * x[1], f * x[2]};
  };
  auto add = [](const std::array<double, 3>& a, const std::array<double, 3>& b, double w) {
    return std::array<double, 3>{a[0] + w * b[0], a[1] + w * b[1], a[2] + w * b[2]};
  };
  const auto k1x = s.v, k1v = acc(s.x);
  const auto k2x = add(s.v, k1v, dt / 2), k2v = acc(add(s.x, k1x, dt / 2));
  const auto k3x = add(s.v, k2v, dt / 2), k3v = acc(add(s.x, k2x, dt / 2));
  const auto k4x = add(s.v, k3v, dt), k4v = acc(add(s.x, k3x, dt));
  State n;
  for (int k = 0; k < 3; ++k) {
    n.x[k] = s.x[k] + dt / 6 * (k1x[k] + 2 * k2x[k] + 2 * k3x[k] + k4x[k]);
    n.v[k] = s.v[k] + dt / 6 * (k1v[k] + 2 * k2v[k] + 2 * k3v[k] + k4v[k]);
  }
  return n;
}

double norm3(const std::array<double, 3>& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// Integrates from the orbit's start until the centres are r_contact apart;
// returns the state there and the time taken.
std::pair<State, double> integrate_to_contact(const CollisionOrbit& o) {
  State s{o.x_start, o.v_start};
  const double dt = o.time_to_contact / 20000;
  double t = 0;
  for (int step = 0; step < 100000; ++step) {
    const State n = rk4(s, o.mu, dt);
    if (norm3(n.x) <= o.r_contact) {
      double lo = 0, hi = dt;  // the sub-step that lands on the contact distance
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (norm3(rk4(s, o.mu, mid).x) > o.r_contact ? lo : hi) = mid;
      }
      return {rk4(s, o.mu, hi), t + hi};
    }
    s = n;
    t += dt;
  }
  ADD_FAILURE() << "no contact";
  return {s, t};
}

// The angle between the line of centres and the reversed relative velocity.
double impact_angle(const State& s) {
  const double c = -(s.x[0] * s.v[0] + s.x[1] * s.v[1] + s.x[2] * s.v[2]) / (norm3(s.x) * norm3(s.v));
  return std::acos(std::min(1.0, c));
}

}  // namespace

// Hyperbolic, parabolic, bound and head-on orbits (mu = r_contact = 1,
// start 3 touching distances apart): contact at the stated speed and angle,
// at the stated time, where the orbit says, to 1e-6.
TEST(CollisionOrbit, ReachesContactAtTheStatedSpeedAndAngle) {
  const double v_esc = std::sqrt(2.0);
  struct Case {
    double v_over_vesc, angle_deg;
  };
  for (const Case c : {Case{2.5, 30}, Case{1.0, 60}, Case{0.9, 45}, Case{1.5, 0}, Case{1.2, 89}}) {
    const CollisionOrbit o = collision_orbit(1.0, 1.0, c.v_over_vesc * v_esc, c.angle_deg * kPi / 180, 3.0);
    EXPECT_NEAR(norm3(o.x_start), 3.0, 1e-12);
    EXPECT_NEAR(o.v_esc, v_esc, 1e-15);
    const auto [end, t] = integrate_to_contact(o);
    const std::string what = "v = " + std::to_string(c.v_over_vesc) + " v_esc, " + std::to_string(c.angle_deg) + " deg";
    EXPECT_NEAR(norm3(end.v), o.v_contact, 1e-6 * o.v_contact) << what;
    EXPECT_NEAR(impact_angle(end), c.angle_deg * kPi / 180, 1e-6) << what;
    EXPECT_NEAR(t, o.time_to_contact, 1e-6 * o.time_to_contact) << what;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(end.x[k], o.x_contact[k], 1e-6) << what << " x[" << k << "]";
      EXPECT_NEAR(end.v[k], o.v_contact_vector[k], 1e-6 * o.v_contact) << what << " v[" << k << "]";
    }
  }
}

TEST(CollisionOrbit, RefusesABoundOrbitThatNeverWasThatFarApart) {
  // 0.5 v_esc: E = -0.75 mu/r_c, apoapsis below 1.34 r_c for any angle
  EXPECT_THROW(collision_orbit(1.0, 1.0, 0.5 * std::sqrt(2.0), 0.5, 3.0), std::invalid_argument);
  EXPECT_NO_THROW(collision_orbit(1.0, 1.0, 0.5 * std::sqrt(2.0), 0.5, 1.2));
}

namespace {
std::string two_spheres(const std::string& collision, const std::string& extra_body = "") {
  return "[simulation]\ndimension = 3\nend_time = 1.0\n"
         "[gravity]\nmode = \"direct\"\n"
         "[materials.rock]\neos = \"ideal_gas\"\ngamma = 1.4\n"
         "[[bodies]]\nshape = \"sphere\"\nmaterial = \"rock\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0e5\n"
         "spacing = 2.5e4\ndensity = 3000.0\npressure = 1.0e5\n" +
         extra_body +
         "[[bodies]]\nshape = \"sphere\"\nmaterial = \"rock\"\ncenter = [0.0, 0.0, 0.0]\nradius = 5.0e4\n"
         "spacing = 2.5e4\ndensity = 3000.0\npressure = 1.0e5\n"
         "[collision]\n" +
         collision;
}
}  // namespace

// The placed bodies: centres on the orbit's start in the barycentric frame,
// total momentum zero to round-off, each body moving as a whole.
TEST(CollisionPlacement, BodiesStartOnTheOrbitWithZeroMomentum) {
  const Scene scene = parse_scene(
      two_spheres("target = 0\nimpactor = 1\nimpact_speed_vesc = 2.5\nimpact_angle = 30.0\nseparation = 3.0\n"),
      "c.toml");
  ParticleStore<3> ps;
  CollisionSetup setup;
  const std::vector<std::int64_t> first =
      generate_bodies<3>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps, &setup);
  double M[2] = {0, 0}, com[2][3] = {}, p[3] = {}, vmax = 0;
  for (int b = 0; b < 2; ++b)
    for (std::int64_t i = first[b]; i < first[b + 1]; ++i) {
      M[b] += ps.m[i];
      for (int k = 0; k < 3; ++k) {
        com[b][k] += ps.m[i] * ps.x[i][k];
        p[k] += ps.m[i] * ps.v[i][k];
      }
      vmax = std::max(vmax, double(norm(ps.v[i])));
    }
  EXPECT_EQ(M[0], setup.mass_target);
  EXPECT_EQ(M[1], setup.mass_impactor);
  for (int k = 0; k < 3; ++k) {
    com[0][k] /= M[0];
    com[1][k] /= M[1];
    EXPECT_NEAR(p[k], 0.0, 1e-14 * (M[0] + M[1]) * vmax) << "momentum " << k;
    EXPECT_NEAR(com[1][k] - com[0][k], setup.orbit.x_start[k], 1e-9 * setup.orbit.r_start) << "separation " << k;
    EXPECT_NEAR(M[0] * com[0][k] + M[1] * com[1][k], 0.0, 1e-9 * (M[0] + M[1]) * setup.orbit.r_start);
  }
  // radii: the outermost particle plus half a spacing
  EXPECT_GT(setup.radius_target, 0.9e5);
  EXPECT_LE(setup.radius_target, 1.0e5 + 1.25e4);
  EXPECT_NEAR(setup.orbit.r_start, 3.0 * (setup.radius_target + setup.radius_impactor), 1e-6);
  EXPECT_NEAR(setup.orbit.v_contact, 2.5 * setup.orbit.v_esc, 1e-9 * setup.orbit.v_esc);
  const double G = scene.gravity.G;
  EXPECT_NEAR(setup.orbit.v_esc,
              std::sqrt(2 * G * (M[0] + M[1]) / (setup.radius_target + setup.radius_impactor)), 1e-12 * setup.orbit.v_esc);
  // every particle of a body moves with it
  for (int b = 0; b < 2; ++b)
    for (std::int64_t i = first[b] + 1; i < first[b + 1]; ++i)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(ps.v[i][k], ps.v[first[b]][k]);
  EXPECT_NE(collision_report(setup).find("s after the launch (at t = 0)"), std::string::npos) << collision_report(setup);
}

// v_infinity: v_contact^2 = v_inf^2 + v_esc^2; a list of bodies makes one group.
TEST(CollisionPlacement, VInfinityAndGroupsOfBodies) {
  const std::string shell =
      "[[bodies]]\nshape = \"sphere\"\nmaterial = \"rock\"\ncenter = [0.0, 0.0, 0.0]\nradius = 4.0e4\n"
      "spacing = 2.5e4\ndensity = 3000.0\npressure = 1.0e5\n";
  const Scene scene = parse_scene(
      two_spheres("target = [0]\nimpactor = [1, 2]\nv_infinity = 100.0\nimpact_angle = 0.0\nseparation = 2.0\n", shell),
      "c.toml");
  ParticleStore<3> ps;
  CollisionSetup setup;
  generate_bodies<3>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps, &setup);
  const CollisionOrbit& o = setup.orbit;
  EXPECT_NEAR(o.v_contact * o.v_contact, 100.0 * 100.0 + o.v_esc * o.v_esc, 1e-9 * o.v_contact * o.v_contact);
  EXPECT_NEAR(o.x_start[1], 0.0, 1e-9);  // head-on: along x
}

TEST(CollisionScene, BadTablesAreRefusedWithTheKey) {
  using rubble::test::parse_error;
  const std::string ok = "target = 0\nimpactor = 1\nimpact_speed = 100.0\nimpact_angle = 45.0\nseparation = 2.0\n";
  EXPECT_EQ(parse_error(two_spheres(ok)), "");
  auto refused = [&](const std::string& table, const std::string& key, const std::string& words) {
    const std::string e = parse_error(two_spheres(table));
    EXPECT_NE(e.find("key '" + key + "'"), std::string::npos) << e;
    EXPECT_NE(e.find(words), std::string::npos) << e;
  };
  refused("target = 0\nimpactor = 1\nimpact_angle = 45.0\nseparation = 2.0\n", "collision", "needs the impact speed");
  refused(ok + "v_infinity = 3.0\n", "collision", "only one of");
  refused("target = 0\nimpactor = 0\nimpact_speed = 1.0\nimpact_angle = 0.0\nseparation = 2.0\n", "collision.impactor",
          "in both");
  refused("target = 0\nimpactor = 5\nimpact_speed = 1.0\nimpact_angle = 0.0\nseparation = 2.0\n", "collision.impactor",
          "bodies 0 to 1");
  refused("target = 0\nimpactor = 1\nimpact_speed = 1.0\nimpact_angle = 90.0\nseparation = 2.0\n",
          "collision.impact_angle", "[0, 90)");
  refused("target = 0\nimpactor = 1\nimpact_speed = 1.0\nimpact_angle = 10.0\nseparation = 0.5\n",
          "collision.separation", ">= 1");
  refused("target = 0\nimpactor = 1\nimpact_speed = 1.0\nimpact_angle = 10.0\nseparation = 2.0\nspin = 1.0\n",
          "collision.spin", "unknown key");  // (spin_target, spin_impactor)
  // a body that already moves
  std::string moving = two_spheres(ok);
  moving.replace(moving.find("radius = 5.0e4\n"), 15, "radius = 5.0e4\nvelocity = [1.0, 0.0, 0.0]\n");
  EXPECT_NE(parse_error(moving).find("the collision sets it"), std::string::npos) << parse_error(moving);
  // without self-gravity
  std::string flat = two_spheres(ok);
  flat.replace(flat.find("[gravity]\nmode = \"direct\"\n"), 26, "");
  EXPECT_NE(parse_error(flat).find("needs a 3-D scene with self-gravity"), std::string::npos) << parse_error(flat);
}

// A bound orbit whose apoapsis is closer than the start: refused at set-up,
// naming [collision].
TEST(CollisionScene, UnreachableStartIsRefusedAtSetUp) {
  const Scene scene = parse_scene(
      two_spheres("target = 0\nimpactor = 1\nimpact_speed_vesc = 0.5\nimpact_angle = 30.0\nseparation = 3.0\n"),
      "c.toml");
  ParticleStore<3> ps;
  try {
    generate_bodies<3>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps);
    FAIL() << "placed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "collision");
    EXPECT_NE(std::string(e.what()).find("apoapsis"), std::string::npos) << e.what();
  }
}

// Each particle's body of origin is a snapshot field (`body`, issue #52
// item 4): a run of two bodies writes 0 for the first body's particles and 1
// for the second's, whatever order the solver sorted them into.
TEST(CollisionSnapshot, SnapshotsCarryEachParticlesBody) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rubble_body_field_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  RunOptions opt;
  opt.out_dir = dir.string();
  opt.quiet = true;
  const Scene scene = parse_scene(
      two_spheres("target = 0\nimpactor = 1\nimpact_speed_vesc = 2.0\nimpact_angle = 45.0\nseparation = 2.0\n") +
          "[output]\nname = \"pair\"\ninterval = 0.5\n",
      "c.toml");
  run_scene(scene, opt);
  const std::string file = (dir / snapshot_filename("pair", 1)).string();
  ParticleStore<3> ps;
  SnapshotMeta meta;
  read_restart<3>(file, ps, meta);  // the fields and the restart group (body_first_id)
  ASSERT_EQ(meta.restart.body_first_id.size(), 3u);
  std::vector<std::int32_t> body(ps.n, -1);
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t d = H5Dopen2(f, "body", H5P_DEFAULT);
  ASSERT_GE(d, 0) << "no dataset 'body'";
  EXPECT_GE(H5Dread(d, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, body.data()), 0);
  H5Dclose(d);
  H5Fclose(f);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < ps.n; ++i)
    wrong += body[i] != (ps.id[i] < meta.restart.body_first_id[1] ? 0 : 1);
  EXPECT_EQ(wrong, 0u);
  std::filesystem::remove_all(dir);
}

// spin_target, spin_impactor: each body turns rigidly about its own centre
// of mass (L = I w about it), the total momentum stays zero.
TEST(CollisionPlacement, SpinIsARigidRotationAboutEachBodysCentre) {
  const Scene scene = parse_scene(
      two_spheres("target = 0\nimpactor = 1\nimpact_speed_vesc = 2.0\nimpact_angle = 30.0\nseparation = 2.0\n"
                  "spin_target = [0.0, 0.0, 1e-3]\nspin_impactor = [2e-3, 0.0, 0.0]\n"),
      "c.toml");
  ParticleStore<3> ps;
  const std::vector<std::int64_t> first =
      generate_bodies<3>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps);
  double p[3] = {0, 0, 0}, scale = 0;
  const double w[2][3] = {{0, 0, 1e-3}, {2e-3, 0, 0}};
  for (int b = 0; b < 2; ++b) {
    double M = 0, com[3] = {0, 0, 0}, vc[3] = {0, 0, 0};
    for (std::int64_t i = first[b]; i < first[b + 1]; ++i) {
      M += ps.m[i];
      for (int k = 0; k < 3; ++k) {
        com[k] += ps.m[i] * ps.x[i][k];
        vc[k] += ps.m[i] * ps.v[i][k];
      }
    }
    for (int k = 0; k < 3; ++k) {
      com[k] /= M;
      vc[k] /= M;
    }
    // every particle: v = v_c + w x (x - com)
    double worst = 0, speed = 0;
    for (std::int64_t i = first[b]; i < first[b + 1]; ++i) {
      const double r[3] = {ps.x[i][0] - com[0], ps.x[i][1] - com[1], ps.x[i][2] - com[2]};
      const double s[3] = {w[b][1] * r[2] - w[b][2] * r[1], w[b][2] * r[0] - w[b][0] * r[2],
                           w[b][0] * r[1] - w[b][1] * r[0]};
      for (int k = 0; k < 3; ++k) {
        worst = std::max(worst, std::fabs(ps.v[i][k] - vc[k] - s[k]));
        speed = std::max(speed, std::fabs(s[k]));
        p[k] += ps.m[i] * ps.v[i][k];
      }
    }
    EXPECT_GT(speed, 0.0) << "body " << b << " does not spin";
    EXPECT_LE(worst, 1e-9 * (speed + std::fabs(vc[0]) + std::fabs(vc[1]))) << "body " << b;
    scale += M * (std::fabs(vc[0]) + std::fabs(vc[1]) + speed);
  }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(p[k], 0.0, 1e-13 * scale) << "momentum " << k;
  // a spin of the wrong length is refused with the key
  EXPECT_NE(rubble::test::parse_error(two_spheres("target = 0\nimpactor = 1\nimpact_speed = 1.0\nimpact_angle = 0.0\n"
                                                  "separation = 2.0\nspin_target = [1.0, 2.0]\n"))
                .find("collision.spin_target"),
            std::string::npos);
}

// Relax and launch (issue #52 item 2): with simulation.damping_time and
// damping_end, two layered embryos are held where the orbit starts while
// their motion about their own centres is damped, and launched onto the
// orbit at damping_end: their mean velocities are then the orbit's, the
// total momentum zero, and the centres have not left the start.
TEST(CollisionRelaxation, BodiesAreHeldThenLaunchedOntoTheOrbit) {
  const std::string text =
      "[simulation]\ndimension = 3\nend_time = 200.0\ndamping_time = 50.0\ndamping_end = 200.0\n"
      "[gravity]\nmode = \"barnes_hut\"\n"
      "[materials.iron]\nlibrary = \"iron\"\n[materials.basalt]\nlibrary = \"basalt\"\n"
      "[materials.ice]\nlibrary = \"ice\"\n"
      "[[bodies]]\nshape = \"layered\"\nparticles = 600\nmass = 9e22\n"
      "layers = [{ material = \"iron\", mass_fraction = 0.3 }, { material = \"basalt\", mass_fraction = 0.7 }]\n"
      "[[bodies]]\nshape = \"layered\"\nparticles = 300\nmass = 1e22\n"
      "layers = [{ material = \"ice\", mass_fraction = 1.0 }]\n"
      "[collision]\ntarget = 0\nimpactor = 1\nimpact_speed_vesc = 2.5\nimpact_angle = 30.0\nseparation = 3.0\n"
      "spin_impactor = [0.0, 0.0, 1e-4]\n";
  const Scene scene = parse_scene(text, "relax.toml");
  EXPECT_EQ(scene.simulation.damping_frame, DampingFrame::Body);
  ParticleStore<3> ps;
  CollisionSetup setup;
  generate_bodies<3>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps, &setup);
  ASSERT_TRUE(setup.held);
  for (std::size_t i = 0; i < ps.n; ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(ps.v[i][k], 0.0) << "held bodies start at rest";
  // the centres where the orbit starts (the generated positions)
  auto centre_of = [](const std::vector<double>& x, const std::vector<double>& m, const std::vector<int>& mat,
                      bool impactor, int ice) {
    std::array<double, 4> c{};  // mass, then mass x position
    for (std::size_t i = 0; i < m.size(); ++i) {
      if ((mat[i] == ice) != impactor) continue;
      c[0] += m[i];
      for (int k = 0; k < 3; ++k) c[1 + k] += m[i] * x[3 * i + k];
    }
    return c;
  };
  std::vector<double> x0, m0;
  std::vector<int> mat0;
  for (std::size_t i = 0; i < ps.n; ++i) {
    for (int k = 0; k < 3; ++k) x0.push_back(ps.x[i][k]);
    m0.push_back(ps.m[i]);
    mat0.push_back(ps.material_id[i]);
  }
  const int ice = 2;
  RunOptions opt;
  opt.write_output = false;
  opt.quiet = true;
  const FinalState fs = run_scene(scene, opt);
  for (bool impactor : {false, true}) {
    const auto c0 = centre_of(x0, m0, mat0, impactor, ice);
    const auto c1 = centre_of(fs.x, fs.m, fs.material_id, impactor, ice);
    std::array<double, 3> mv{};
    double m = 0;
    for (std::size_t i = 0; i < fs.m.size(); ++i) {
      if ((fs.material_id[i] == ice) != impactor) continue;
      m += fs.m[i];
      for (int k = 0; k < 3; ++k) mv[k] += fs.m[i] * fs.v[3 * i + k];
    }
    const auto& want = impactor ? setup.velocity_impactor : setup.velocity_target;
    const double speed = norm3(want);
    double moved = 0;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(mv[k] / m, want[k], 1e-9 * speed) << (impactor ? "impactor" : "target") << " v[" << k << "]";
      moved = std::max(moved, std::fabs(c1[1 + k] / c1[0] - c0[1 + k] / c0[0]));
    }
    // held: the mutual pull acts for one step at a time only (the mean
    // velocity is reset to 0 after each), far less than a spacing
    EXPECT_LT(moved, 1e-3 * setup.orbit.r_start) << (impactor ? "impactor" : "target") << " drifted while held";
  }
}

TEST(CollisionRelaxation, GlobalDampingIsRefusedWithACollision) {
  const std::string e = test::parse_error(two_spheres("target = 0\nimpactor = 1\nimpact_speed = 100.0\nimpact_angle = 0.0\nseparation = 3.0\n")
                                              .replace(0, std::string("[simulation]\n").size(),
                                                       "[simulation]\ndamping_time = 1.0\ndamping_end = 1.0\n"
                                                       "damping_frame = \"global\"\n"));
  EXPECT_NE(e.find("'simulation.damping_frame'"), std::string::npos) << e;
}
