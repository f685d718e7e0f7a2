#pragma once
// Self-gravity of the particles as a scene asks for it ([gravity]): off,
// direct summation, or the Barnes-Hut octree; softening from each particle's
// smoothing length or a fixed length; the scene's G. The CPU driver calls
// compute() once per evaluation of the right-hand side (cpu_stepper.cpp).
#include <cstddef>
#include <vector>

#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/gravity/octree.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

class SelfGravity {
 public:
  // kernel: the SPH kernel, whose shape softens gravity as well.
  SelfGravity(const GravityConfig& config, KernelType kernel);

  bool enabled() const { return config_.mode != GravityMode::Off; }
  const GravityConfig& config() const { return config_; }

  // Acceleration acc[i] and potential phi[i] (both including G) of n
  // particles with positions x, masses m and smoothing lengths (support
  // radii) h. Softening: eps_i = h_i, or the fixed length.
  void compute(const Vec<3>* x, const Real* m, const Real* h, std::size_t n, Vec<3>* acc, Real* phi);

  const Octree& tree() const { return tree_; }

 private:
  GravityConfig config_;
  KernelType kernel_;
  Octree tree_;
  std::vector<Real> eps_;
};

}  // namespace rubble
