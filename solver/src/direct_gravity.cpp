// Direct-summation self-gravity; see rubble/gravity/direct.hpp.
#include "rubble/gravity/direct.hpp"

namespace rubble {

void direct_gravity(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n, KernelType kernel, Real G,
                    Vec<3>* acc, Real* phi) {
#pragma omp parallel for schedule(dynamic, 64) if (n > 256)
  for (std::size_t a = 0; a < n; ++a) {
    const GravityField f = direct_field_of_particle(x, m, eps, n, kernel, a);
    acc[a] = f.a * G;
    if (phi) phi[a] = f.phi * G;
  }
}

GravityField direct_field_at(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n, KernelType kernel,
                             const Vec<3>& at, Real eps_at) {
  GravityField f{Vec<3>::zero(), Real(0)};
  for (std::size_t b = 0; b < n; ++b) gravity_pair_add(kernel, at - x[b], m[b], eps_at, eps ? eps[b] : Real(0), f);
  return f;
}

}  // namespace rubble
