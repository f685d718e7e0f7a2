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
