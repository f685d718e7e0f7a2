#pragma once
// Initial-condition generators: turn the scene's [[bodies]] into particles.
#include "rubble/core/box.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Volume per particle of a lattice with spacing dx in D dimensions:
// cubic dx^D; hexagonal (2-D) sqrt(3)/2 dx^2; hexagonal close packed (3-D) dx^3/sqrt(2).
template <int D>
double lattice_cell_volume(Lattice lattice, double dx);

// Fill the store with every body of the scene: positions on the body's
// lattice, mass = density * cell volume, velocity, internal energy (from the
// pressure through the material's EOS if pressure is given), density, and
// h = hfact (m/rho)^(1/D). Throws InputError if a body yields no particle or
// a non-finite value. Returns where each body's particle ids begin: body k
// holds ids [first[k], first[k + 1]) (size: bodies + 1).
template <int D>
std::vector<std::int64_t> generate_bodies(const Scene& scene, double hfact, const FieldNeeds& needs,
                                          ParticleStore<D>& ps);

// The domain box from [domain]: periodic axes get their bounds.
template <int D>
Box<D> domain_from_scene(const Scene& scene);

}  // namespace rubble
