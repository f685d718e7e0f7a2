#pragma once
// Hydrostatic structure of a layered, self-gravitating sphere (issue #52
// item 1, the profile; the particles on it: scene/layered_body.hpp).
// Given the layers from the centre out (each a material's EOS and its outer
// radius), the radial profiles m(r), p(r), rho(r), u(r) that satisfy
//
//   dm/dr = 4 pi r^2 rho,   dp/dr = -G m rho / r^2,
//
// with p = 0 at the surface and each layer on its own adiabat from u = 0 at
// its outer edge: along an adiabat du = (p/rho^2) d rho, so
// dp/d rho = dP/d rho|_u + (p/rho^2) dP/du|_rho = c^2 (the EOS's squared
// sound speed), and
//
//   d rho/dr = (dp/dr) / c^2(rho, u),   du/dr = (p/rho^2) d rho/dr.
//
// The adiabat from u = 0 puts into u the work of compressing the layer, so
// a layer that is later decompressed adiabatically returns to u = 0 instead
// of falling below it (the set-up problem of issue #50: bodies compressed
// with u = 0). At a layer's outer edge its density is the one its EOS
// gives at u = 0 and the pressure of the layer above (bisection).
//
// Integrated inwards with RK4 on a uniform grid per layer; the total mass
// is the unknown (m(R) = M), found by the secant method so that m -> 0 at
// the centre. Host-only reference code (set-up, tests), double precision.
// Implemented in solver/src/hydrostatic.cpp; tested against the analytic
// profiles of one- and two-layer incompressible spheres (test_hydrostatic.cpp).
#include <vector>

#include "rubble/physics/eos/eos.hpp"

namespace rubble {

struct HydrostaticLayer {
  EosParams eos;        // its material (Murnaghan, Tillotson; the ideal gas has no p = 0 surface density)
  double outer_radius;  // [m], increasing from the centre out
};

struct HydrostaticProfile {
  // samples from the surface (index 0) inwards to the centre, per layer
  std::vector<double> r, m, p, rho, u;
  std::vector<int> layer;                // each sample's layer (0 = innermost)
  double mass = 0;                       // total mass [kg]
  std::vector<double> layer_mass;        // by layer [kg]
  std::vector<double> layer_radius;      // each layer's outer radius [m]
  double centre_pressure = 0;            // [Pa]
  double centre_mass_residual = 0;       // m at the centre / mass (the shooting's miss)
};

// The profile of `layers` under the gravitational constant G with
// `steps_per_layer` RK4 steps in each. Throws std::invalid_argument for bad
// layers (radii not increasing, an EOS without a surface density) and
// std::runtime_error when no mass makes m vanish at the centre.
HydrostaticProfile hydrostatic_profile(const std::vector<HydrostaticLayer>& layers, double G,
                                       int steps_per_layer = 2000);

// The density of a layer's material at p = 0 and u = 0 (its surface
// density; Murnaghan and Tillotson: rho0). Throws std::invalid_argument for
// an ideal gas, which has none.
double layer_reference_density(const EosParams& eos);

// The profile's pressure, density and internal energy at radius r (linear
// interpolation between samples; r within the body).
struct HydrostaticState {
  double p, rho, u;
  int layer;
};
HydrostaticState hydrostatic_at(const HydrostaticProfile& profile, double r);

}  // namespace rubble
