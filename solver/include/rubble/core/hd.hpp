#pragma once
// RUBBLE_HD marks a function callable from host and device code.
// Every physics formula carries it, so the CPU (OpenMP) drivers, the CUDA
// drivers and the unit tests all call the very same function
// (DESIGN.md principle 1: one formula, one place).
//
// RUBBLE_HD_SMALL marks the few-flop operations of the small vector and
// matrix types (core/vec.hpp, core/mat.hpp), which must always be inlined:
// measured on the granular column (2-D solid, g++ 12 -O3), g++ kept the
// 2 x 2 matrix-vector product out of line in the stress pair loop, 8.6 % of
// the run in calls (docs/performance.md, "Small operations inlined").
#if defined(__CUDACC__)
#define RUBBLE_HD __host__ __device__
#define RUBBLE_HD_INLINE __host__ __device__ inline
#define RUBBLE_HD_SMALL __host__ __device__ __forceinline__
#else
#define RUBBLE_HD
#define RUBBLE_HD_INLINE inline
#if defined(__GNUC__)
#define RUBBLE_HD_SMALL inline __attribute__((always_inline))
#else
#define RUBBLE_HD_SMALL inline
#endif
#endif

// RUBBLE_LAMBDA marks a loop body written once for both backends, as
//   be.for_each("eos", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { ... });
// (rubble/drivers/step_sequence.hpp): under nvcc an extended __device__
// lambda that the CUDA backend launches as a kernel, otherwise a plain
// lambda that the CPU backend runs in an OpenMP loop. It captures by value
// only plain data (views, pointers, numbers): never `this`.
#if defined(__CUDACC__)
#define RUBBLE_LAMBDA __device__
#else
#define RUBBLE_LAMBDA
#endif
