// [[energy_deposits]] (scene.hpp, docs/scene.md): the energy lands where
// the scene says, in the amount it says, and bad tables are refused naming
// the key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rubble/core/error.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"

using namespace rubble;

namespace {

std::string blast_scene(const std::string& deposit) {
  return "[simulation]\ndimension = 3\nend_time = 0.01\n"
         "[materials.gas]\neos = \"ideal_gas\"\ngamma = 1.6666666666666667\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"gas\"\nlattice = \"cubic\"\nmin = [-0.5, -0.5, -0.5]\n"
         "max = [0.5, 0.5, 0.5]\nspacing = 0.0625\ndensity = 1.0\npressure = 1e-5\n"
         "[domain]\nperiodic = [true, true, true]\nmin = [-0.5, -0.5, -0.5]\nmax = [0.5, 0.5, 0.5]\n" +
         deposit;
}

ParticleStore<3> generate(const Scene& s) {
  ParticleStore<3> ps;
  generate_bodies<3>(s, 1.2, Features{}, ps);
  return ps;
}

double thermal_energy(const ParticleStore<3>& ps) {
  double e = 0;
  for (std::size_t i = 0; i < ps.n; ++i) e += double(ps.m[i]) * double(ps.u[i]);
  return e;
}

std::string error_of(const std::string& text) {
  try {
    generate(parse_scene(text, "blast.toml"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// The added thermal energy is the deposit's energy, to rounding; the kernel
// profile follows W(r, radius) of the cubic spline (weights relative to the
// central particle), the uniform one gives equal u inside the radius.
TEST(EnergyDeposit, AddsExactlyTheEnergyWithTheStatedProfile) {
  const ParticleStore<3> ambient = generate(parse_scene(blast_scene(""), "blast.toml"));
  const double e0 = thermal_energy(ambient);
  for (const char* profile : {"kernel", "uniform"}) {
    const std::string deposit = std::string("[[energy_deposits]]\nenergy = 2.5\ncenter = [0.03125, 0.03125, 0.03125]\n"
                                            "radius = 0.2\nprofile = \"") + profile + "\"\n";
    const ParticleStore<3> ps = generate(parse_scene(blast_scene(deposit), "blast.toml"));
    EXPECT_NEAR(thermal_energy(ps) - e0, 2.5, 1e-12 * 2.5) << profile;
    const Vec<3> c{Real(0.03125), Real(0.03125), Real(0.03125)};
    double du_max = 0;
    for (std::size_t i = 0; i < ps.n; ++i) du_max = std::max(du_max, double(ps.u[i] - ambient.u[i]));
    for (std::size_t i = 0; i < ps.n; ++i) {
      const double r = double(norm(ps.x[i] - c)), du = double(ps.u[i] - ambient.u[i]);
      if (r >= 0.2) {
        EXPECT_EQ(du, 0.0) << profile << " r = " << r;
        continue;
      }
      const double expected = std::string(profile) == "uniform"
                                  ? du_max
                                  : du_max * double(kernel_w<3>(KernelType::CubicSpline, Real(r), Real(0.2))) /
                                        double(kernel_w<3>(KernelType::CubicSpline, Real(0), Real(0.2)));
      EXPECT_NEAR(du, expected, 1e-10 * du_max) << profile << " r = " << r;
    }
  }
}

// The minimum image is used on periodic axes: a deposit centred on a corner
// of the periodic cube reaches the particles of all eight corners.
TEST(EnergyDeposit, WrapsAroundPeriodicAxes) {
  const ParticleStore<3> ambient = generate(parse_scene(blast_scene(""), "blast.toml"));
  const ParticleStore<3> ps = generate(parse_scene(
      blast_scene("[[energy_deposits]]\nenergy = 1\ncenter = [0.5, 0.5, 0.5]\nradius = 0.1\nprofile = \"uniform\"\n"),
      "blast.toml"));
  int heated = 0;
  for (std::size_t i = 0; i < ps.n; ++i) heated += ps.u[i] > ambient.u[i];
  EXPECT_EQ(heated, 8);  // the eight lattice points at distance sqrt(3)/32 from the corner
  EXPECT_NEAR(thermal_energy(ps) - thermal_energy(ambient), 1.0, 1e-12);
}

TEST(EnergyDeposit, BadTablesAreRefusedNamingTheKey) {
  const std::string ok_center = "center = [0, 0, 0]\n";
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = -1\n" + ok_center + "radius = 0.1\n"))
                .find("energy_deposits[0].energy"), std::string::npos);
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\n" + ok_center + "radius = 0\n"))
                .find("energy_deposits[0].radius"), std::string::npos);
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\nradius = 0.1\n")).find("energy_deposits[0].center"),
            std::string::npos);
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\ncenter = [0, 0]\nradius = 0.1\n"))
                .find("energy_deposits[0].center"), std::string::npos);
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\n" + ok_center + "radius = 0.1\nprofile = \"gauss\"\n"))
                .find("energy_deposits[0].profile"), std::string::npos);
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\n" + ok_center + "radius = 0.1\nenergi = 2\n"))
                .find("energy_deposits[0].energi"), std::string::npos);
  EXPECT_NE(error_of(blast_scene("[energy_deposits]\nenergy = 1\n")).find("energy_deposits"), std::string::npos);
  // no particle within the radius (the nearest are sqrt(3)/32 away): the
  // energy would go nowhere
  EXPECT_NE(error_of(blast_scene("[[energy_deposits]]\nenergy = 1\ncenter = [0, 0, 0]\n"
                                 "radius = 0.01\n"))
                .find("energy_deposits[0].radius"), std::string::npos);
}
