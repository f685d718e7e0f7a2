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

struct RunOptions {
  std::string out_dir;        // where snapshots and conserved.csv go
  bool write_output = true;   // false: run in memory only (tests, benchmarks)
  bool progress = false;      // progress bar (terminal) or plain lines
  bool quiet = false;         // no progress output at all
};

// Final particle state, flattened (vector fields N x D, row-major).
struct FinalState {
  int dimension = 0;
  double time = 0;
  std::int64_t steps = 0;
  double wall_seconds = 0;
  std::vector<double> x, v;
  std::vector<double> m, rho, p, u, h, cs;
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
