#pragma once
// Barnes-Hut self-gravity on the GPU as a library call, outside a run: the
// device octree that `--backend cuda` runs use (solver/src/cuda/
// cuda_stepper.cu), for benchmarks (benchmarks/throughput.cpp) and checks.
// Without -DRUBBLE_CUDA=ON the call throws RunError.
#include <cstddef>
#include <cstdint>

#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

struct DeviceGravityTiming {
  double build_seconds = 0;  // keys, sort, tree levels and moments (device-synchronised)
  double walk_seconds = 0;   // one walk per particle
  std::uint32_t nodes = 0;
};

// acc[i] and phi[i] (may be null) of n particles (host arrays; eps may be
// null: point masses), times gravity.G, with gravity.theta, order and
// leaf_size; one walk per particle (no groups).
DeviceGravityTiming cuda_barnes_hut_field(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n,
                                          const GravityConfig& gravity, KernelType kernel, Vec<3>* acc, Real* phi);

}  // namespace rubble
