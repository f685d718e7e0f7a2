#pragma once
// Initial-condition generators: turn the scene's [[bodies]] into particles.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/collision.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Volume per particle of a lattice with spacing dx in D dimensions:
// cubic dx^D; hexagonal (2-D) sqrt(3)/2 dx^2; hexagonal close packed (3-D) dx^3/sqrt(2).
template <int D>
double lattice_cell_volume(Lattice lattice, double dx);

// The particle positions of a box, sphere or ring body on its lattice
// (b.lattice, b.spacing): lattice points inside [min, max), then inside the
// shape; a sphere or ring has its lattice centred on its centre. Used by
// generate_bodies, and by rungs that must know a body's particles before the
// run (e.g. to match a small body's mass).
template <int D>
std::vector<Vec<D>> lattice_points(BodyConfig b);

// Fill the store with every body of the scene: positions on the body's
// lattice, mass = density * cell volume, velocity, internal energy (from the
// pressure through the material's EOS if pressure is given), density, and
// h = hfact (m/rho)^(1/D). Throws InputError if a body yields no particle or
// a non-finite value. Returns where each body's particle ids begin: body k
// holds ids [first[k], first[k + 1]) (size: bodies + 1).
// The fields a run allocates: features_of_scene (rubble/drivers/run_physics.hpp).
// A [collision] places its bodies on their orbit (scene/collision.hpp);
// `collision` (when given) receives what it did.

template <int D>
std::vector<std::int64_t> generate_bodies(const Scene& scene, double hfact, const Features& needs,
                                          ParticleStore<D>& ps, CollisionSetup* collision = nullptr);

// The body that generated particle `id`, from generate_bodies' `first`
// (body k holds ids [first[k], first[k + 1])); 0 if `first` is empty.
inline std::size_t body_of_id(const std::vector<std::int64_t>& first, std::int64_t id) {
  if (first.size() < 2) return 0;
  return std::size_t(std::upper_bound(first.begin() + 1, first.end() - 1, id) - (first.begin() + 1));
}

// ---- resource guards (issue #13) ----

// The particle count the bodies will hold, from their volumes and lattice
// cells (polytropes: their `particles`), without generating them.
template <int D>
double estimated_particle_count(const Scene& scene);

// Bytes the run holds per particle: the allocated fields, the integrator's
// copies (RK2: two stores; leapfrog: the half-step fields), the state
// check's copy of the snapshot fields, the neighbour lists (4 bytes per
// neighbour within the search radius) and the cell list's sorted copies.
template <int D>
std::size_t bytes_per_particle(const Scene& scene, const Features& needs, double hfact);

// Memory this process may use: RUBBLE_MEMORY_LIMIT (bytes) if set, else
// the smaller of /proc/meminfo's MemAvailable and the cgroup limit; 0 if
// unknown.
double available_memory_bytes();

// "1.5 GiB", "320 MiB", ...
std::string format_bytes(double bytes);

// Refuses (InputError naming the file and `bodies`) a scene with more
// particles than a 32-bit id can number, or whose estimated memory exceeds
// the available memory; the message gives the estimate.
template <int D>
void check_resources(const Scene& scene, const Features& needs, double hfact);

// Bodies whose particles come closer than half the particle spacing
// (estimated per particle as h / hfact) overlap: an InputError naming both
// bodies, unless simulation.allow_overlap. Returns one warning per pair of
// free bodies (not walls) that start within a kernel support of each other
// — they interact from the first step — naming both and their closest
// particles' distance (none with allow_overlap).
template <int D>
std::vector<std::string> check_overlap(const Scene& scene, const ParticleStore<D>& ps,
                                       const std::vector<std::int64_t>& body_first, const Box<D>& domain,
                                       double hfact);

// The domain box from [domain]: periodic axes get their bounds.
template <int D>
Box<D> domain_from_scene(const Scene& scene);

}  // namespace rubble
