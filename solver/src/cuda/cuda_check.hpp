#pragma once
// Every CUDA API call and kernel launch is checked (issue #6 item 3): an
// error stops the run with a RunError naming the call, the file and line,
// and CUDA's message.
#include <cuda_runtime.h>

#include <cstdlib>
#include <string>

#include "rubble/core/error.hpp"

namespace rubble::cuda {

inline void check(cudaError_t err, const char* call, const char* file, int line) {
  if (err == cudaSuccess) return;
  throw RunError(std::string("CUDA error in ") + call + " (" + file + ":" + std::to_string(line) +
                 "): " + cudaGetErrorName(err) + ": " + cudaGetErrorString(err));
}

// Whether every kernel launch is synchronised and checked: at build time
// with -DRUBBLE_CUDA_SYNC_CHECK, or at run time with the environment
// variable RUBBLE_CUDA_SYNC_CHECK set to anything but "" or "0" (ci/gpu/check
// sets it for the parity test). Off, a fault inside a kernel surfaces at the
// next synchronising call, named after that call.
inline bool sync_check_enabled() {
#ifdef RUBBLE_CUDA_SYNC_CHECK
  return true;
#else
  static const bool on = [] {
    const char* e = std::getenv("RUBBLE_CUDA_SYNC_CHECK");
    return e != nullptr && *e != '\0' && std::string(e) != "0";
  }();
  return on;
#endif
}

}  // namespace rubble::cuda

// Wrap a CUDA runtime call: RUBBLE_CUDA(cudaMalloc(&p, bytes)). Kernel
// launches are checked by for_each_index (cuda_stepper.cu), and with
// sync_check_enabled() also synchronised and checked after each.
#define RUBBLE_CUDA(call) ::rubble::cuda::check((call), #call, __FILE__, __LINE__)
