// The `rubble` command-line program.
//
//   rubble run SCENE.toml [--out DIR] [--backend cpu] [--set key=value ...] [--quiet]
//   rubble info
//
// Exit codes: 0 success, 1 unexpected error, 2 bad input or usage (the scene,
// the options, an output directory that would be overwritten), 3 a run that
// could not go on (RunError).
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "rubble/core/error.hpp"
#include "rubble/core/real.hpp"
#include "rubble/run.hpp"

#ifndef RUBBLE_VERSION
#define RUBBLE_VERSION "unknown"
#endif
#ifndef RUBBLE_COMMIT
#define RUBBLE_COMMIT "unknown"
#endif

namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string scene;
  std::string out;
  std::string backend = "cpu";
  std::vector<std::string> sets;
  bool quiet = false;
};

// Validate the scene first, then claim the output directory (never
// overwriting anything), then run.
int run_command(const RunArgs& args) {
  if (args.backend == "cuda") {
    std::cerr << "rubble: error: --backend cuda: this build has no CUDA backend (available: cpu)\n";
    return 2;
  }

  const rubble::Scene scene = rubble::load_scene_file(args.scene, args.sets);

  const fs::path out = args.out.empty() ? fs::path("out") / fs::path(args.scene).stem() : fs::path(args.out);
  if (fs::exists(out)) {
    if (!fs::is_directory(out))
      throw rubble::InputError(out.string(), "",
                               "the output path exists and is not a directory; choose another --out DIR");
    if (!fs::is_empty(out))
      throw rubble::InputError(out.string(), "",
                               "the output directory exists and is not empty; its contents would be "
                               "overwritten. Choose another --out DIR (or move the old one away)");
  }
  fs::create_directories(out);

  rubble::RunOptions options;
  options.out_dir = out.string();
  options.write_output = true;
  options.progress = isatty(2) != 0;
  options.quiet = args.quiet;
  const rubble::FinalState final_state = rubble::run_scene(scene, options);

  if (!args.quiet)
    std::cout << "rubble: done: t = " << final_state.time << " s after " << final_state.steps << " steps in "
              << final_state.wall_seconds << " s; output in " << out.string() << "\n";
  return 0;
}

int info_command() {
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  std::cout << "rubble " << RUBBLE_VERSION << " (commit " << RUBBLE_COMMIT << ")\n"
            << "backends:        cpu\n"
            << "precision:       " << (sizeof(rubble::Real) == 8 ? "double" : "float") << "\n"
            << "OpenMP threads:  " << threads
#ifndef _OPENMP
            << " (built without OpenMP)"
#endif
            << "\n"
            << "GPU seen:        none (CPU-only build)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rubble: a compact SPH solver for solids, regolith and planetary impacts"};
  app.require_subcommand(1);

  RunArgs run_args;
  CLI::App* run = app.add_subcommand("run", "Run a scene (TOML file) to its end time");
  run->add_option("SCENE", run_args.scene, "The scene file (TOML); keys are documented in docs/scene.md")
      ->required();
  run->add_option("--out", run_args.out,
                  "Output directory for snapshots and conserved.csv (default: out/<scene file stem>); "
                  "must not exist or be empty");
  run->add_option("--backend", run_args.backend, "Compute backend")
      ->check(CLI::IsMember({"cpu", "cuda"}))
      ->capture_default_str();
  run->add_option("--set", run_args.sets,
                  "Override a scene key, e.g. --set simulation.end_time=0.5 or --set bodies.0.spacing=0.01 "
                  "(value parsed as TOML, else taken as a string; repeatable)")
      ->allow_extra_args(false);
  run->add_flag("-q,--quiet", run_args.quiet, "No progress output");

  app.add_subcommand("info", "Show version, backends, precision, OpenMP threads and GPU");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is a "ParseError" with code 0
  }

  try {
    if (*run) return run_command(run_args);
    return info_command();
  } catch (const rubble::InputError& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    return 2;
  } catch (const rubble::RunError& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    return 1;
  }
}
