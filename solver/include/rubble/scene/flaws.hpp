#pragma once
// Weibull flaws for tensile damage, drawn as Benz & Asphaug do (1994,
// Icarus 107:98; 1995, Comput. Phys. Commun. 87:253; physics/damage.hpp):
// flaw j = 1, 2, ... of a body of volume V activates at the strain
// eps_j = (j/(k V))^(1/m) and goes to a particle picked uniformly at random,
// until every particle holds at least one flaw (about N ln N flaws for N
// particles), or at least `min_per_particle` (about N (M + ln N) for M >> 1;
// Spheral's weibullFlawDistributionBenzAsphaug has the same option,
// minFlawsPerNode): the flaws stay those of the body's Weibull population,
// drawn further up in strain. Per particle the draw keeps the count and the smallest and
// largest activation strain (the first and last flaw it received).
//
// Reproducible: the generator is std::mt19937_64 (its output sequence is
// fixed by the C++ standard) seeded with (seed, stream) through
// std::seed_seq, and a particle is picked from one 64-bit draw r as
// floor(r n / 2^64) (no library distribution, whose algorithm the standard
// leaves open). The same seed, stream and particle count give the same flaws
// on every platform.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rubble {

struct FlawSet {
  std::vector<std::int32_t> count;  // flaws per particle (>= 1)
  std::vector<double> eps_min;      // smallest activation strain of each particle
  std::vector<double> eps_max;      // largest
  std::int64_t total = 0;           // flaws drawn
};

// n >= 1 particles of equal volume making up a body of volume `volume`
// [m^3]; k [m^-3] and m the Weibull constants (> 0); every particle gets at
// least min_per_particle flaws (values below 1 count as 1).
FlawSet draw_weibull_flaws(std::size_t n, double k, double m, double volume, std::uint64_t seed, std::uint64_t stream,
                           std::int32_t min_per_particle = 1);

}  // namespace rubble
