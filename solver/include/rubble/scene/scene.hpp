#pragma once
// A scene as read from TOML, validated, with every default filled in.
// The parser (scene_parser.cpp) is the only place that knows TOML; the
// solver sees only this structure. Every key is documented in
// docs/scene.md with its unit and default.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/core/real.hpp"
#include "rubble/physics/kernel_type.hpp"

namespace rubble {

enum class DensityForm : int { Summation = 0, Continuity = 1 };
enum class Integrator : int { RK2Adaptive = 0, Leapfrog = 1 };
enum class EosType : int { IdealGas = 0 };

struct SimulationConfig {
  int dimension = 0;                        // 1, 2 or 3 (required)
  double end_time = 0;                      // [s] (required, > 0)
  Integrator integrator = Integrator::RK2Adaptive;
  KernelType kernel = KernelType::CubicSpline;
  DensityForm density = DensityForm::Summation;
  double hfact = 0;                         // h = hfact * (m/rho)^(1/D); 0 = kernel default
  double courant = 0.3;                     // Courant factor C
  double force_factor = 0.25;               // dt <= force_factor * sqrt(h/|a|)
  double rk2_tolerance = 1e-5;              // relative error per step (rk2_adaptive)
  double dt_initial = 0;                    // 0 = from the Courant limit
  double dt_min = 0;                        // a step below this stops the run; 0 = 1e-12 * end_time
  std::int64_t max_steps = 10000000;
};

struct ArtificialViscosity {
  double alpha = 1.0;  // Monaghan (1992) linear term
  double beta = 2.0;   // quadratic term
};

struct ArtificialConductivity {
  bool enabled = false;
  double alpha_u = 1.0;  // Price (2008)
};

struct MaterialConfig {
  std::string name;     // the key under [materials]
  EosType eos = EosType::IdealGas;
  double gamma = 0;     // ideal gas adiabatic index (> 1)
  ArtificialViscosity viscosity;
  ArtificialConductivity conductivity;
};

enum class BodyShape : int { Box = 0 };
enum class Lattice : int { Cubic = 0, HexagonalClosePacked = 1 };

struct BodyConfig {
  BodyShape shape = BodyShape::Box;
  std::string material;      // name of a [materials] entry
  int material_id = 0;       // its index (filled by the parser)
  std::array<double, 3> min{}, max{};  // box corners [m] (first D used)
  double spacing = 0;        // lattice spacing [m]
  Lattice lattice = Lattice::Cubic;
  double density = 0;        // [kg/m^3] (> 0)
  double pressure = -1;      // [Pa]  one of pressure / internal_energy
  double internal_energy = -1;  // [J/kg]
  std::array<double, 3> velocity{};  // [m/s]
};

struct DomainConfig {
  // Periodic axes need both bounds; open axes ignore them.
  std::array<double, 3> min{}, max{};
  std::array<bool, 3> periodic{};
};

struct OutputConfig {
  std::string name = "snapshot";  // snapshot files NAME.NNNN.h5
  double interval = 0;            // [s]; 0 = only initial and final
  bool snapshots = true;
};

struct Scene {
  std::string file;     // where it came from (for messages)
  std::string text;     // full scene text after --set overrides (stored in snapshots)
  SimulationConfig simulation;
  std::vector<MaterialConfig> materials;
  std::vector<BodyConfig> bodies;
  DomainConfig domain;
  OutputConfig output;
};

}  // namespace rubble
