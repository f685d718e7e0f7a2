// Self-gravity in scenes and runs (issue #5): the [gravity] section, the
// polytrope body and the damping keys of the parser; the Lane-Emden
// reference; gravity fields and the gravitational energy in a run.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

#include "rubble/core/error.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/reference/lane_emden.hpp"
#include "rubble/run.hpp"

using namespace rubble;

namespace {

const std::string kGas = "[materials.gas]\neos = \"ideal_gas\"\ngamma = 2.0\n";

std::string polytrope_scene(const std::string& gravity, int particles = 600, double end_time = 0.05,
                            const std::string& extra_sim = "") {
  return "[simulation]\ndimension = 3\nend_time = " + std::to_string(end_time) + "\nintegrator = \"leapfrog\"\n" +
         extra_sim + "\n" + gravity + "\n" + kGas +
         "[[bodies]]\nshape = \"polytrope\"\nmaterial = \"gas\"\nradius = 1.0\nmass = 1.0\n"
         "polytropic_index = 1\nparticles = " +
         std::to_string(particles) + "\n";
}

const std::string kCodeUnitsTree = "[gravity]\nmode = \"barnes_hut\"\nG = 1.0\n";

void expect_error(const std::string& text, const std::string& key, const std::string& fragment) {
  try {
    parse_scene(text, "test.toml");
    ADD_FAILURE() << "expected an InputError for key '" << key << "'";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << "message '" << e.what() << "' lacks '" << fragment << "'";
  }
}

// A fresh, empty directory under the system temp dir.
std::filesystem::path temp_dir(const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / ("rubble_test_gravity_" + std::to_string(getpid()) + "_" + name);
  std::filesystem::remove_all(p);
  return p;
}

// Column `name` of the last line of conserved.csv.
double last_conserved(const std::filesystem::path& dir, const std::string& name, bool first_row = false) {
  std::ifstream f(dir / "conserved.csv");
  std::string header, line, last, first;
  std::getline(f, header);
  while (std::getline(f, line)) {
    if (first.empty()) first = line;
    last = line;
  }
  std::vector<std::string> cols, vals;
  std::stringstream hs(header), vs(first_row ? first : last);
  for (std::string c; std::getline(hs, c, ',');) cols.push_back(c);
  for (std::string c; std::getline(vs, c, ',');) vals.push_back(c);
  for (std::size_t i = 0; i < cols.size(); ++i)
    if (cols[i] == name) return std::stod(vals.at(i));
  ADD_FAILURE() << "no column " << name;
  return NAN;
}

}  // namespace

// ---- Lane-Emden ------------------------------------------------------------------

TEST(LaneEmden, MatchesTheAnalyticN1SolutionAndKnownSurfaces) {
  const LaneEmden le(1.0);
  EXPECT_NEAR(le.xi1(), std::numbers::pi, 1e-10);
  EXPECT_NEAR(le.omega(), std::numbers::pi, 1e-9);
  for (double xi : {0.0, 0.3, 1.0, 2.0, 3.0}) {
    const double exact = xi > 0 ? std::sin(xi) / xi : 1.0;
    EXPECT_NEAR(le.theta(xi), exact, 1e-11) << xi;
    EXPECT_NEAR(le.mass_fraction(xi), (std::sin(xi) - xi * std::cos(xi)) / std::numbers::pi, 1e-10) << xi;
    EXPECT_NEAR(le.xi_of_mass_fraction(le.mass_fraction(xi)), xi, 1e-8) << xi;
  }
  EXPECT_EQ(le.theta(4.0), 0.0);
  // Chandrasekhar (1939) Table 4: xi_1 and -xi_1^2 theta'(xi_1)
  EXPECT_NEAR(LaneEmden(1.5).xi1(), 3.65375, 1e-5);
  EXPECT_NEAR(LaneEmden(1.5).omega(), 2.71406, 1e-5);
  EXPECT_NEAR(LaneEmden(3.0).xi1(), 6.89685, 1e-5);
  EXPECT_NEAR(LaneEmden(3.0).omega(), 2.01824, 1e-5);
  EXPECT_THROW(LaneEmden(5.0), std::invalid_argument);
}

TEST(LaneEmden, PolytropeN1InCodeUnits) {
  const Polytrope p(1.0, 1.0, 1.0, 1.0);
  EXPECT_NEAR(p.K, 2 / std::numbers::pi, 1e-10);          // K = 2 G R^2 / pi
  EXPECT_NEAR(p.rho_c, std::numbers::pi / 4, 1e-10);      // rho_c = pi M / (4 R^3)
  EXPECT_NEAR(p.W, -0.75, 1e-14);                          // -3/(5-n) G M^2 / R
  EXPECT_NEAR(p.pressure(0), p.K * p.rho_c * p.rho_c, 1e-12);
  EXPECT_NEAR(p.mass_fraction(1.0), 1.0, 1e-12);
}

// ---- parser ------------------------------------------------------------------------

TEST(GravityScene, DefaultsAndAllKeys) {
  const Scene off = parse_scene(polytrope_scene(""), "test.toml");
  EXPECT_EQ(off.gravity.mode, GravityMode::Off);
  EXPECT_EQ(off.gravity.theta, 0.5);
  EXPECT_EQ(off.gravity.order, MultipoleOrder::Quadrupole);
  EXPECT_EQ(off.gravity.G, 6.67430e-11);
  EXPECT_EQ(off.gravity.softening, GravitySoftening::SmoothingLength);
  EXPECT_EQ(off.gravity.leaf_size, 8);
  EXPECT_EQ(off.gravity.group_size, 32);
  EXPECT_EQ(off.simulation.damping_time, 0.0);

  const Scene s = parse_scene(
      polytrope_scene("[gravity]\nmode = \"direct\"\ntheta = 0.3\norder = \"monopole\"\nG = 2.5\nsoftening = 0.01\n"
                      "leaf_size = 1\ngroup_size = 0\n",
                      600, 2.0, "damping_time = 0.1\ndamping_end = 1.0"),
      "test.toml");
  EXPECT_EQ(s.gravity.mode, GravityMode::Direct);
  EXPECT_EQ(s.gravity.theta, 0.3);
  EXPECT_EQ(s.gravity.order, MultipoleOrder::Monopole);
  EXPECT_EQ(s.gravity.G, 2.5);
  EXPECT_EQ(s.gravity.softening, GravitySoftening::Fixed);
  EXPECT_EQ(s.gravity.softening_length, 0.01);
  EXPECT_EQ(s.gravity.leaf_size, 1);
  EXPECT_EQ(s.gravity.group_size, 0);
  EXPECT_EQ(s.simulation.damping_time, 0.1);
  EXPECT_EQ(s.simulation.damping_end, 1.0);
  const BodyConfig& b = s.bodies.at(0);
  EXPECT_EQ(b.shape, BodyShape::Polytrope);
  EXPECT_EQ(b.radius, 1.0);
  EXPECT_EQ(b.mass, 1.0);
  EXPECT_EQ(b.polytropic_index, 1.0);
  EXPECT_EQ(b.particles, 600);
  EXPECT_EQ(b.lattice, Lattice::HexagonalClosePacked);
  EXPECT_EQ(b.min[0], -1.0);
  EXPECT_EQ(b.max[2], 1.0);
  // --set reaches the new keys
  const Scene t = parse_scene(polytrope_scene(kCodeUnitsTree), "test.toml", {"gravity.theta=0.7", "gravity.softening=\"smoothing_length\""});
  EXPECT_EQ(t.gravity.theta, 0.7);
  EXPECT_EQ(t.gravity.mode, GravityMode::BarnesHut);
}

TEST(GravityScene, InvalidInputIsNamed) {
  const std::string sim1d = "[simulation]\ndimension = 1\nend_time = 0.2\n";
  const std::string box1d = "[[bodies]]\nshape = \"box\"\nmaterial = \"gas\"\nmin = [0.0]\nmax = [1.0]\n"
                            "spacing = 0.1\ndensity = 1.0\npressure = 1.0\n";
  expect_error(sim1d + "[gravity]\nmode = \"direct\"\n" + kGas + box1d, "gravity.mode", "dimension = 3");
  expect_error(polytrope_scene("[gravity]\nmode = \"tree\"\n"), "gravity.mode", "barnes_hut");
  expect_error(polytrope_scene("[gravity]\ntheta = 1.5\n"), "gravity.theta", "in [0, 1]");
  expect_error(polytrope_scene("[gravity]\norder = \"octupole\"\n"), "gravity.order", "quadrupole");
  expect_error(polytrope_scene("[gravity]\nG = 0\n"), "gravity.G", "> 0");
  expect_error(polytrope_scene("[gravity]\nsoftening = \"smoothing_lenght\"\n"), "gravity.softening",
               "did you mean 'smoothing_length'");
  expect_error(polytrope_scene("[gravity]\nsoftening = -1.0\n"), "gravity.softening", ">= 0");
  expect_error(polytrope_scene("[gravity]\nsoftening = true\n"), "gravity.softening", "got a boolean");
  expect_error(polytrope_scene("[gravity]\nleaf_size = 0\n"), "gravity.leaf_size", "[1, 1024]");
  expect_error(polytrope_scene("[gravity]\nthetta = 0.5\n"), "gravity.thetta", "did you mean 'gravity.theta'");
  expect_error(polytrope_scene(kCodeUnitsTree) + "[domain]\nperiodic = [true, false, false]\nmin = [-2.0, -2.0, -2.0]\n"
                                                 "max = [2.0, 2.0, 2.0]\n",
               "gravity.mode", "open boundaries");
  expect_error(polytrope_scene("", 600, 1.0, "damping_time = 0.1"), "simulation.damping_end", "go together");
  expect_error(polytrope_scene("", 600, 1.0, "damping_time = 0.1\ndamping_end = 2.0"), "simulation.damping_end",
               "end_time");
  expect_error(polytrope_scene("", 600, 1.0, "damping_time = 0\ndamping_end = 0.5"), "simulation.damping_time", "> 0");
  // polytrope body
  std::string s = polytrope_scene("");
  expect_error(s.replace(s.find("radius = 1.0"), 12, "radius = -1.0"), "bodies[0].radius", "> 0");
  s = polytrope_scene("");
  expect_error(s.replace(s.find("particles = 600"), 15, "particles = 10"), "bodies[0].particles", "[100, 1e9]");
  s = polytrope_scene("");
  expect_error(s.replace(s.find("polytropic_index = 1"), 20, "polytropic_index = 5"), "bodies[0].polytropic_index",
               "(0, 5)");
  expect_error(polytrope_scene("") + "spacing = 0.1\n", "bodies[0].spacing", "unknown key");
  s = polytrope_scene("");
  expect_error(s.replace(s.find("dimension = 3"), 13, "dimension = 2"), "bodies[0].shape", "dimension = 3");
}

// ---- runs --------------------------------------------------------------------------

// Gravity fields exist only when gravity is on: a hydro-only scene's
// snapshots have no a_grav and its gravitational energy is 0.
TEST(GravityRun, FieldsAndEnergyOnlyWithGravity) {
  for (bool on : {false, true}) {
    const auto dir = temp_dir(on ? "on" : "off");
    RunOptions o;
    o.out_dir = dir.string();
    o.quiet = true;
    const Scene s = parse_scene(polytrope_scene(on ? kCodeUnitsTree : "[gravity]\nG = 1.0\n", 600, 0.02), "test.toml");
    run_scene(s, o);
    ParticleStore<3> ps;
    SnapshotMeta meta;
    read_snapshot<3>((dir / snapshot_filename("snapshot", 1)).string(), ps, meta);
    EXPECT_EQ(ps.a_grav.empty(), !on);
    EXPECT_TRUE(ps.phi.empty());  // phi is not a snapshot field
    const double W = last_conserved(dir, "gravitational");
    if (on) {
      EXPECT_NEAR(W, -0.75, 0.05);  // Lane-Emden: -3/(5-n) G M^2/R, at N = 600
      // a_grav points inwards, |a| ~ G m(<r)/r^2
      double inward = 0;
      for (std::size_t i = 0; i < ps.n; ++i) inward += dot(ps.a_grav[i], ps.x[i]) < 0 ? 1 : 0;
      EXPECT_GT(inward, 0.99 * double(ps.n));
    } else {
      EXPECT_EQ(W, 0.0);
    }
    std::filesystem::remove_all(dir);
  }
}

// Direct summation and the tree give the same gravitational energy, and a
// short leapfrog run conserves the total energy.
TEST(GravityRun, DirectAndTreeAgreeAndEnergyIsConserved) {
  double W[2];
  int k = 0;
  for (const char* mode : {"direct", "barnes_hut"}) {
    const auto dir = temp_dir(mode);
    RunOptions o;
    o.out_dir = dir.string();
    o.quiet = true;
    const Scene s = parse_scene(polytrope_scene(std::string("[gravity]\nmode = \"") + mode + "\"\nG = 1.0\n", 800, 0.1),
                                "test.toml");
    run_scene(s, o);
    W[k++] = last_conserved(dir, "gravitational", true);
    const double e0 = last_conserved(dir, "total", true), e1 = last_conserved(dir, "total");
    EXPECT_LT(std::fabs(e1 - e0), 2e-4 * std::fabs(e0)) << mode;
    std::filesystem::remove_all(dir);
  }
  EXPECT_NEAR(W[0], W[1], 1e-3 * std::fabs(W[0]));
}

// Damping takes the kinetic energy out.
TEST(GravityRun, DampingRemovesKineticEnergy) {
  RunOptions o;
  o.write_output = false;
  o.quiet = true;
  const Scene damped = parse_scene(polytrope_scene(kCodeUnitsTree, 600, 0.3, "damping_time = 0.01\ndamping_end = 0.3"), "test.toml");
  const Scene free = parse_scene(polytrope_scene(kCodeUnitsTree, 600, 0.3), "test.toml");
  auto kinetic = [](const FinalState& fs) {
    double k = 0;
    for (std::size_t i = 0; i < fs.m.size(); ++i)
      for (int d = 0; d < 3; ++d) k += 0.5 * fs.m[i] * fs.v[3 * i + d] * fs.v[3 * i + d];
    return k;
  };
  const double kd = kinetic(run_scene(damped, o)), kf = kinetic(run_scene(free, o));
  EXPECT_GT(kf, 0);
  EXPECT_LT(kd, 0.05 * kf);
}
