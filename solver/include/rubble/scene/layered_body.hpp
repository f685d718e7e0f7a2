#pragma once
// A differentiated body in hydrostatic equilibrium, as particles (issue #52
// item 1): shape = "layered" (docs/scene.md).
//
// 1. The structure. The layers (centre out) are given either by their outer
//    radii or by their mass fractions and the total mass. With radii, the
//    structure is hydrostatic_profile's (scene/hydrostatic.hpp: each layer
//    on its adiabat from u = 0 at its top, p = 0 at the surface). With mass
//    fractions, the radii are the unknowns: each layer's volume is scaled by
//    (wanted mass / profile mass) and the profile recomputed until every
//    layer's mass is right to 1e-10.
//
// 2. The particles, on nested spherical shells of equal particle mass with
//    the layer boundaries exact (the approach of Kegerreis, Eke, Gonnet et
//    al. 2019, MNRAS 487:5029, "SEAGen"; written here from the paper's
//    description, not its code). Layer k of mass M_k holds N_k =
//    round(M_k / m0) particles of mass m_k = M_k / N_k (m0 = M / N, N the
//    asked-for count), so masses differ between layers by at most 1/(2 N_k).
//    Within a layer, shells are about one local spacing d(r) = (m_k /
//    rho(r))^(1/3) thick: their number is the integral of dr / d over the
//    layer, rounded; each shell's particle count is the rounded mass it
//    encloses over m_k, and its boundaries are then moved so that it
//    encloses exactly count x m_k (the profile's m(r) inverted), so every
//    particle of a layer has the same mass. A shell's particles sit at its
//    mass-median radius on a Fibonacci spiral (near-equal area per point;
//    Gonzalez 2010, Math. Geosci. 42:49) turned by a random rotation drawn
//    per shell from `seed`, so neighbouring shells do not line up.
//    A central shell of one particle is put at the centre.
//
// Host-only set-up code, double precision; implemented in
// solver/src/layered_body.cpp; tested in test_layered_body.cpp.
#include <array>
#include <cstdint>
#include <vector>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/scene/hydrostatic.hpp"

namespace rubble {

// The layers from the centre out: each one's EOS and either its outer
// radius (all > 0, increasing) or its mass fraction (all > 0, summing to 1,
// with total_mass > 0).
struct LayeredSpec {
  std::vector<EosParams> eos;
  std::vector<double> outer_radius;   // [m], or empty
  std::vector<double> mass_fraction;  // or empty
  double total_mass = 0;              // [kg] with mass_fraction
};

struct BodyConfig;
struct MaterialConfig;
// The spec of a shape = "layered" body (scene.hpp BodyConfig::layers): each
// layer's material's EOS and its radius or mass fraction (with b.mass).
LayeredSpec layered_spec(const std::vector<MaterialConfig>& materials, const BodyConfig& b);

// The body's hydrostatic profile (radii found for mass fractions). Throws
// std::invalid_argument for an inconsistent spec, std::runtime_error when
// the structure cannot be found (e.g. a body too massive for its EOSs).
HydrostaticProfile layered_profile(const LayeredSpec& spec, double G);

struct ShellParticles {
  std::vector<std::array<double, 3>> x;  // relative to the body's centre [m]
  std::vector<double> m;                 // [kg]
  std::vector<int> layer;                // 0 = innermost
  std::vector<int> shell;                // shell index from the centre out
  int shells = 0;
};

// About `particles` particles on nested shells following `profile`
// (particles >= 1; every layer gets at least one particle).
ShellParticles place_on_shells(const HydrostaticProfile& profile, std::int64_t particles, std::uint64_t seed);

// m(r) of the profile inverted: the radius enclosing mass `m` (linear
// between samples; 0 <= m <= profile.mass).
double radius_enclosing(const HydrostaticProfile& profile, double m);

// The profile's state at radius r taken within layer `layer` (a particle of
// that layer near a boundary reads its own layer's side of the jump).
HydrostaticState hydrostatic_in_layer(const HydrostaticProfile& profile, double r, int layer);

}  // namespace rubble
