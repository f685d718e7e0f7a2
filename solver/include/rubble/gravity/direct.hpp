#pragma once
// Direct summation of self-gravity: every pair, O(N^2). The reference the
// Barnes-Hut tree is judged against (verification/barnes_hut/), and a run
// mode of its own for small N (scene: gravity.mode = "direct").
// The pair interaction is gravity_pair() of physics/gravity.hpp, the same
// function the tree uses at its leaves, with the same softening.
#include <cstddef>

#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/gravity.hpp"
#include "rubble/physics/kernel_type.hpp"

namespace rubble {

// The field per unit G on particle a from all others, summed in index
// order: the loop body of both backends' direct summation.
RUBBLE_HD_INLINE GravityField direct_field_of_particle(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n,
                                                       KernelType kernel, std::size_t a) {
  GravityField f{Vec<3>::zero(), Real(0)};
  const Vec<3> xa = x[a];
  const Real ea = eps ? eps[a] : Real(0);
  for (std::size_t b = 0; b < n; ++b) {
    if (b == a) continue;
    gravity_pair_add(kernel, xa - x[b], m[b], ea, eps ? eps[b] : Real(0), f);
  }
  return f;
}

// Acceleration acc[i] and potential phi[i] (may be nullptr) of every
// particle due to all others, multiplied by G. eps: softening lengths
// (support radii of `kernel`), nullptr for point masses. OpenMP-parallel
// over the targets; each sum runs over the sources in index order, so the
// result does not depend on the thread count.
void direct_gravity(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n, KernelType kernel, Real G,
                    Vec<3>* acc, Real* phi);

// Field per unit G at an arbitrary point x with softening length eps.
GravityField direct_field_at(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n, KernelType kernel,
                             const Vec<3>& at, Real eps_at = Real(0));

}  // namespace rubble
