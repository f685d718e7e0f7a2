#pragma once
// The library's front door: read a scene, run it, get the final state.
// The `rubble` program and the verification rungs both go through here, so
// a rung exercises exactly the pipeline a user runs.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rubble/io/conserved_sums.hpp"
#include "rubble/scene/scene.hpp"
#include "rubble/scene/scene_parser.hpp"

namespace rubble {

// Reading scenes: load_scene_file, parse_scene (rubble/scene/scene_parser.hpp).

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

// What the CUDA backend has asked of the device so far in this process
// (issue #15 item 5; process-wide because the stepper, its octree and the
// benchmark's Barnes-Hut entry all count, and one host thread drives them).
//   device_allocations     cudaMalloc calls: device buffers growing and the
//                          caching allocator behind Thrust's temporary
//                          storage filling up. Flat once a run's buffers
//                          have reached their size (after its first step):
//                          nothing is allocated inside a step.
//   host_synchronisations  calls that make the host wait for the device:
//                          a reduction's result, the octree's level counts,
//                          a device-to-host copy. The count per step is
//                          tabled at the top of cuda_stepper.cu.
// Neither counts the synchronisations of RUBBLE_CUDA_SYNC_CHECK (a debug
// mode) or the implicit one of cudaFree when a buffer grows.
struct CudaBackendCounts {
  std::int64_t device_allocations = 0;
  std::int64_t host_synchronisations = 0;
};
CudaBackendCounts cuda_backend_counts();  // zeros in a CPU-only build

struct RunOptions {
  std::string out_dir;        // where snapshots and conserved.csv go
  bool write_output = true;   // false: run in memory only (tests, benchmarks)
  bool progress = false;      // progress bar (terminal) or plain lines
  bool quiet = false;         // no progress output at all
  Backend backend = default_backend();
  // Resume from this snapshot (issue #13; `rubble run --restart`): the scene
  // must be load_restart_scene()'s of the same file. Empty: a fresh run.
  std::string restart_from = {};
  // Stop cleanly, with a checkpoint, before this much wall time has passed
  // since the run began (0: no limit).
  double max_wall_seconds = 0;
  // Also write the checkpoint NAME.checkpoint.h5 every so many wall-clock
  // seconds (0: never).
  double checkpoint_every_seconds = 0;
  // CPU backend, continuity density: keep the neighbour lists across
  // evaluations while they hold every interacting pair (the default; the
  // results are the same bit for bit). false: search at every evaluation,
  // for the test that compares the two.
  bool keep_neighbour_lists = true;
};

// Exit status of `rubble run` when a run stopped early with a checkpoint
// (a signal, --max-wall-time); docs/user-guide.md lists all exit codes.
inline constexpr int kExitStopped = 4;

// The scene a snapshot was written under, for resuming from it: the scene
// text, --set overrides and library material files as the run read them at
// its start, all carried by the snapshot, so nothing on disk changes a
// resumed run. `extra_overrides` may only change simulation.end_time,
// simulation.max_steps and output.* (the physics stays as it was); anything
// else is an InputError, as is a snapshot without restart data.
Scene load_restart_scene(const std::string& snapshot, const std::vector<std::string>& extra_overrides = {});

// SIGINT and SIGTERM then ask a running run_scene to stop after its current
// step with a checkpoint (FinalState::stopped); a second signal ends the
// process at once. `rubble run` installs them; library users may.
void install_stop_signal_handlers();

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
  // Where the wall time went, in seconds, in the order the loop does it:
  // set-up (scene to first evaluation), then per step the sort, the
  // time-step limit, the state checks, the step itself split into the
  // right-hand side's parts (neighbour search, density and h, EOS, forces,
  // end of step; CPU backend only) and the integration (the rest of the
  // step), and output. `rubble run --timings` prints it.
  std::vector<std::pair<std::string, double>> phase_seconds;
  // neighbour searches over the run (an evaluation searches once, or again
  // when a smoothing length outgrows its search radius); -1 where the
  // backend does not count them
  std::int64_t neighbour_searches = -1;
  // Why the run stopped before end_time ("SIGINT", "SIGTERM", "the wall-time
  // limit"), or empty when it reached end_time; then `checkpoint` is the
  // snapshot to resume from.
  std::string stopped;
  std::string checkpoint;
  // The energy bookkeeping (drivers/step_sequence.hpp): the work of walls and
  // the internal-energy floor's additions, and the steps the energy watchdog
  // took again with a shorter step.
  EnergyBooks books;
  std::int64_t energy_retries = 0;
};

// Run the scene to its end time. Throws InputError for bad input found while
// setting up, RunError if the run cannot go on (non-finite values, dt collapse).
FinalState run_scene(const Scene& scene, const RunOptions& options);

}  // namespace rubble
