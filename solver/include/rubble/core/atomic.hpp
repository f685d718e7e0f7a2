#pragma once
// Counting from inside a loop body that both backends run (core/hd.hpp:
// RUBBLE_LAMBDA): an atomic add on the device, a relaxed atomic add on the
// host (OpenMP threads). Order does not matter to a count.
#include "rubble/core/hd.hpp"

namespace rubble {

RUBBLE_HD_INLINE void atomic_increment(unsigned long long* count) {
#if defined(__CUDA_ARCH__)
  atomicAdd(count, 1ull);
#else
  __atomic_fetch_add(count, 1ull, __ATOMIC_RELAXED);
#endif
}

}  // namespace rubble
