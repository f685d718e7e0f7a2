#pragma once
// The library's front door: read a scene, run it, get the final state.
// The `rubble` program and the verification rungs both go through here, so
// a rung exercises exactly the pipeline a user runs.
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/scene/scene.hpp"

namespace rubble {

// Parse and validate a scene. `overrides` are "dotted.key=value" strings
// (the --set option), applied to the TOML tree before validation; the value
// is parsed as TOML (so 0.5, true, "text", [1, 2] all work).
// Throws InputError naming the file, the key and the problem.
Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides = {});
Scene parse_scene(const std::string& text, const std::string& file_label,
                  const std::vector<std::string>& overrides = {});

// Where the particles live and the right-hand side is evaluated. `cpu`
// (OpenMP) is always built; `cuda` only with -DRUBBLE_CUDA=ON.
enum class Backend { Cpu, Cuda };

// "cpu" / "cuda".
const char* backend_name(Backend b);
// Parses "cpu" / "cuda"; throws InputError(where, "backend", ...) otherwise.
Backend parse_backend(const std::string& name, const std::string& where);
// Whether this build has the backend (cpu: always).
bool backend_built(Backend b);
// The backend of runs that do not name one: RUBBLE_BACKEND from the
// environment ("cpu" or "cuda"; how the whole ctest ladder runs on a GPU
// host, ci/gpu/check), cpu when unset.
Backend default_backend();
// The GPU this process sees ("none (CPU-only build)" without CUDA).
std::string gpu_description();

struct RunOptions {
  std::string out_dir;        // where snapshots and conserved.csv go
  bool write_output = true;   // false: run in memory only (tests, benchmarks)
  bool progress = false;      // progress bar (terminal) or plain lines
  bool quiet = false;         // no progress output at all
  Backend backend = default_backend();
};

// Final particle state, flattened (vector fields N x D, row-major).
struct FinalState {
  std::string backend = "cpu";  // the backend that ran it (records name it)
  // CUDA backend: bytes copied from the device to the host over the run
  // (snapshots, diagnostics and this final state only; 0 on the CPU).
  std::int64_t device_to_host_bytes = 0;
  int dimension = 0;
  double time = 0;
  std::int64_t steps = 0;
  double wall_seconds = 0;
  std::vector<double> x, v;
  std::vector<double> m, rho, p, u, h, cs;
  std::vector<double> alpha;  // porous runs: the distention (empty otherwise)
  std::vector<double> eps_p;  // runs with plasticity: accumulated plastic strain (empty otherwise)
  std::vector<int> material_id;
  std::vector<int> boundary;  // runs with boundary particles: the kFreeParticle ... kBoundaryExtrapolated flags (empty otherwise)
  // Kernel-gradient correction (solids, simulation.kernel_correction):
  // particle evaluations where the correction matrix was ill-conditioned and
  // the identity was used, out of all particle evaluations of the run.
  std::int64_t correction_fallbacks = 0;
  std::int64_t particle_evaluations = 0;
};

// Run the scene to its end time. Throws InputError for bad input found while
// setting up, RunError if the run cannot go on (non-finite values, dt collapse).
FinalState run_scene(const Scene& scene, const RunOptions& options);

}  // namespace rubble
