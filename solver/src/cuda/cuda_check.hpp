#pragma once
// Every CUDA API call and kernel launch is checked (issue #6 item 3): an
// error stops the run with a RunError naming the call, the file and line,
// and CUDA's message.
#include <cuda_runtime.h>

#include <string>

#include "rubble/core/error.hpp"

namespace rubble::cuda {

inline void check(cudaError_t err, const char* call, const char* file, int line) {
  if (err == cudaSuccess) return;
  throw RunError(std::string("CUDA error in ") + call + " (" + file + ":" + std::to_string(line) +
                 "): " + cudaGetErrorName(err) + ": " + cudaGetErrorString(err));
}

}  // namespace rubble::cuda

// Wrap a CUDA runtime call: RUBBLE_CUDA(cudaMalloc(&p, bytes));
#define RUBBLE_CUDA(call) ::rubble::cuda::check((call), #call, __FILE__, __LINE__)

// After a kernel launch: the launch error, and with RUBBLE_CUDA_SYNC_CHECK
// defined (debug builds, compute-sanitizer runs) the kernel's own error too.
#ifdef RUBBLE_CUDA_SYNC_CHECK
#define RUBBLE_CUDA_LAUNCHED(name)                                              \
  do {                                                                          \
    ::rubble::cuda::check(cudaGetLastError(), "launch of " name, __FILE__, __LINE__); \
    ::rubble::cuda::check(cudaDeviceSynchronize(), "kernel " name, __FILE__, __LINE__); \
  } while (0)
#else
#define RUBBLE_CUDA_LAUNCHED(name) ::rubble::cuda::check(cudaGetLastError(), "launch of " name, __FILE__, __LINE__)
#endif
