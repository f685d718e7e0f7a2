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

// Wrap a CUDA runtime call: RUBBLE_CUDA(cudaMalloc(&p, bytes)). Kernel
// launches are checked by for_each_index (cuda_stepper.cu), and with
// RUBBLE_CUDA_SYNC_CHECK defined also synchronised and checked after each.
#define RUBBLE_CUDA(call) ::rubble::cuda::check((call), #call, __FILE__, __LINE__)
