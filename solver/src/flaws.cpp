// Weibull flaws (rubble/scene/flaws.hpp).
#include "rubble/scene/flaws.hpp"

#include <cmath>
#include <random>

namespace rubble {

namespace {
__extension__ typedef unsigned __int128 Wide;  // floor(r n / 2^64) without overflow
}

FlawSet draw_weibull_flaws(std::size_t n, double k, double m, double volume, std::uint64_t seed, std::uint64_t stream,
                           std::int32_t min_per_particle) {
  FlawSet f;
  f.count.assign(n, 0);
  f.eps_min.assign(n, 0.0);
  f.eps_max.assign(n, 0.0);
  std::seed_seq seq{std::uint32_t(seed), std::uint32_t(seed >> 32), std::uint32_t(stream), std::uint32_t(stream >> 32)};
  std::mt19937_64 rng(seq);
  const double kV = k * volume, inv_m = 1.0 / m;
  const std::int32_t target = min_per_particle > 1 ? min_per_particle : 1;
  std::size_t short_of = n;  // particles that hold fewer than `target` flaws yet
  while (short_of > 0) {
    ++f.total;
    const std::size_t i = std::size_t((static_cast<Wide>(rng()) * n) >> 64);
    const double eps = std::pow(double(f.total) / kV, inv_m);
    if (f.count[i] == 0) f.eps_min[i] = eps;
    if (++f.count[i] == target) --short_of;
    f.eps_max[i] = eps;
  }
  return f;
}

}  // namespace rubble
