#pragma once
// RUBBLE_HD marks a function callable from host and device code.
// Every physics formula carries it, so the CPU (OpenMP) drivers, the CUDA
// drivers and the unit tests all call the very same function
// (DESIGN.md principle 1: one formula, one place).
#if defined(__CUDACC__)
#define RUBBLE_HD __host__ __device__
#define RUBBLE_HD_INLINE __host__ __device__ inline
#else
#define RUBBLE_HD
#define RUBBLE_HD_INLINE inline
#endif
