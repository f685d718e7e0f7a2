// The `rubble` command-line program.
//
//   rubble run SCENE.toml [--out DIR] [--backend cpu] [--set key=value ...] [--quiet]
//              [--max-wall-time T] [--checkpoint-every T] [--timings]
//   rubble run --restart DIR/NAME.NNNN.h5 [--out DIR] [--set simulation.end_time=T ...]
//   rubble info
//   rubble eos MATERIAL --rho A:B:N --u C:D:M[:log] [--format table|csv] [--set key=value ...]
//
// Exit codes: 0 success, 1 unexpected error, 2 bad input or usage (the scene,
// the options, an output directory that would be overwritten), 3 a run that
// could not go on (RunError), 4 a run stopped early with a checkpoint to
// resume from (SIGINT, SIGTERM, --max-wall-time), 5 output that could not be
// written (OutputError: the OS's reason is in the message).
#include <unistd.h>

#include <algorithm>
#include <cmath>
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
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene_parser.hpp"

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
  std::string restart;  // a snapshot to resume from (instead of SCENE)
  std::string out;
  std::string backend;  // empty: RUBBLE_BACKEND from the environment, else cpu
  std::vector<std::string> sets;
  std::string max_wall_time, checkpoint_every;
  bool quiet = false;
  bool timings = false;  // --timings
};

// A wall-clock duration: seconds ("3600", "90.5") or H:MM:SS ("11:55:00",
// as batch systems write limits); > 0.
double parse_duration(const std::string& text, const std::string& option) {
  const std::string usage = "expected seconds (e.g. 3600) or H:MM:SS (e.g. 11:55:00), got '" + text + "'";
  double total = 0;
  std::size_t start = 0;
  int parts = 0;
  for (;;) {
    const auto colon = text.find(':', start);
    const std::string part = text.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    std::size_t used = 0;
    double x = -1;
    try {
      x = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (part.empty() || used != part.size() || !std::isfinite(x) || x < 0) throw rubble::InputError(option, "", usage);
    total = total * 60 + x;
    ++parts;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  if (parts > 3 || !(total > 0)) throw rubble::InputError(option, "", usage + " (a positive duration)");
  return total;
}

// An output directory a new run may write into: absent or empty.
void claim_output_directory(const fs::path& out) {
  if (fs::exists(out)) {
    if (!fs::is_directory(out))
      throw rubble::InputError(out.string(), "",
                               "the output path exists and is not a directory; choose another --out DIR");
    if (!fs::is_empty(out))
      throw rubble::InputError(out.string(), "",
                               "the output directory exists and is not empty; its contents would be "
                               "overwritten. Choose another --out DIR (or move the old one away)");
  }
}

// Validate the scene first, then claim the output directory (never
// overwriting anything), then run.
int run_command(const RunArgs& args) {
  const rubble::Backend backend =
      args.backend.empty() ? rubble::default_backend() : rubble::parse_backend(args.backend, "--backend");
  if (!rubble::backend_built(backend)) {
    std::cerr << "rubble: error: --backend " << rubble::backend_name(backend)
              << ": this build has no CUDA backend (available: cpu; configure with -DRUBBLE_CUDA=ON)\n";
    return 2;
  }

  const bool resume = !args.restart.empty();
  if (resume == !args.scene.empty())
    throw rubble::InputError("rubble run", "", resume ? "give either SCENE or --restart SNAPSHOT, not both"
                                                      : "give a SCENE file (or --restart SNAPSHOT to resume a run)");
  rubble::RunOptions options;
  if (!args.max_wall_time.empty()) options.max_wall_seconds = parse_duration(args.max_wall_time, "--max-wall-time");
  if (!args.checkpoint_every.empty())
    options.checkpoint_every_seconds = parse_duration(args.checkpoint_every, "--checkpoint-every");

  const rubble::Scene scene =
      resume ? rubble::load_restart_scene(args.restart, args.sets) : rubble::load_scene_file(args.scene, args.sets);

  fs::path out;
  if (!resume) {
    out = args.out.empty() ? fs::path("out") / fs::path(args.scene).stem() : fs::path(args.out);
    claim_output_directory(out);
  } else {
    // Resume into the snapshot's own directory (default) or a new one.
    fs::path from = fs::path(args.restart).parent_path();
    if (from.empty()) from = ".";
    out = args.out.empty() ? from : fs::path(args.out);
    std::error_code ec;
    if (fs::equivalent(out, from, ec)) {
      // the run's own files after the restart point would be overwritten
      const int next = rubble::read_snapshot_meta(args.restart).restart.next_snapshot;
      for (const auto& entry : fs::directory_iterator(out)) {
        const std::string name = entry.path().filename().string();
        const std::string stem = scene.output.name + ".";
        if (name.size() != stem.size() + 7 || name.rfind(stem, 0) != 0 || name.substr(name.size() - 3) != ".h5") continue;
        const std::string digits = name.substr(stem.size(), 4);
        if (digits.find_first_not_of("0123456789") != std::string::npos) continue;
        if (std::stoi(digits) >= next)
          throw rubble::InputError(entry.path().string(), "",
                                   "exists: the run went on past the restart snapshot, and resuming here would "
                                   "overwrite it. Resume into a new directory with --out DIR (or move the later "
                                   "snapshots away)");
      }
    } else {
      claim_output_directory(out);
    }
  }
  // the run makes the directory once the scene and its initial state have
  // passed every check, so bad input leaves none behind

  options.out_dir = out.string();
  options.write_output = true;
  options.progress = isatty(2) != 0;
  options.quiet = args.quiet;
  options.backend = backend;
  options.restart_from = args.restart;
  rubble::install_stop_signal_handlers();
  const rubble::FinalState final_state = rubble::run_scene(scene, options);

  // --timings: where the wall time went, on every run that returns (a
  // finished one, and one stopped by a signal or --max-wall-time)
  const auto print_timings = [&] {
    if (!args.timings) return;
    std::printf("rubble: where the time went (wall seconds, share of %.3g s):\n", final_state.wall_seconds);
    for (const auto& [phase, seconds] : final_state.phase_seconds)
      std::printf("  %-40s %10.3f  %5.1f %%\n", phase.c_str(), seconds, 100 * seconds / final_state.wall_seconds);
    if (final_state.neighbour_searches >= 0)
      std::printf("  neighbour searches: %lld in %lld evaluations\n",
                  static_cast<long long>(final_state.neighbour_searches),
                  static_cast<long long>(final_state.particle_evaluations / std::max<std::size_t>(1, final_state.m.size())));
    std::fflush(stdout);
  };
  if (!final_state.stopped.empty()) {
    print_timings();
    std::cerr << "rubble: stopped by " << final_state.stopped << " at t = " << final_state.time << " s (step "
              << final_state.steps << "); checkpoint " << final_state.checkpoint << "\n"
              << "rubble: resume with: rubble run --restart " << final_state.checkpoint << "\n";
    return rubble::kExitStopped;
  }
  if (!args.quiet)
    std::cout << "rubble: done: t = " << final_state.time << " s after " << final_state.steps << " steps in "
              << final_state.wall_seconds << " s; output in " << out.string() << "\n";
  print_timings();
  return 0;
}

// ---- rubble eos: tabulate p, c_s and the regime of a material (issue #3) ----

struct EosArgs {
  std::string material;
  std::string rho, u;
  std::string format = "table";
  std::vector<std::string> sets;
};

// "A:B:N" (N points from A to B, ends included; N = 1 needs A = B) with an
// optional ":log" for logarithmic spacing; A > 0, or A >= 0 if zero_allowed.
std::vector<double> parse_range(const std::string& text, const std::string& option, bool zero_allowed,
                                bool negative_allowed = false) {
  const std::string usage = "expected A:B:N or A:B:N:log (N points from A to B), got '" + text + "'";
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const auto colon = text.find(':', start);
    parts.push_back(text.substr(start, colon == std::string::npos ? std::string::npos : colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  if (parts.size() != 3 && parts.size() != 4) throw rubble::InputError(option, "", usage);
  const bool log = parts.size() == 4;
  if (log && parts[3] != "log") throw rubble::InputError(option, "", usage + "; the 4th part may only be 'log'");
  auto number = [&](const std::string& s, const char* what) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (s.empty() || used != s.size() || !std::isfinite(x))
      throw rubble::InputError(option, "", std::string(what) + " '" + s + "' is not a finite number; " + usage);
    return x;
  };
  const double a = number(parts[0], "A"), b = number(parts[1], "B");
  const double nd = number(parts[2], "N");
  if (nd != std::floor(nd) || nd < 1 || nd > 1e6)
    throw rubble::InputError(option, "", "N = '" + parts[2] + "' must be a whole number from 1 to 1e6; " + usage);
  const long n = static_cast<long>(nd);
  if (!negative_allowed && (zero_allowed ? a < 0 : a <= 0))
    throw rubble::InputError(option, "", std::string("A must be ") + (zero_allowed ? ">= 0" : "> 0") + ", got " + parts[0]);
  if (log && a <= 0) throw rubble::InputError(option, "", "log spacing needs A > 0, got " + parts[0]);
  if (n == 1 && a != b) throw rubble::InputError(option, "", "N = 1 needs A = B (one point); " + usage);
  if (n > 1 && !(b > a)) throw rubble::InputError(option, "", "B must be > A, got " + parts[0] + ":" + parts[1]);
  std::vector<double> v(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) {
    const double f = n == 1 ? 0.0 : double(i) / double(n - 1);
    v[i] = log ? a * std::pow(b / a, f) : a + (b - a) * f;
  }
  if (n > 1) v.back() = b;
  return v;
}

// ---- rubble strength: tabulate a material's yield surface ----------------

struct StrengthArgs {
  std::string material;
  std::string p, damage = "0:1:3", u = "0:0:1";
  std::string format = "table";
  std::vector<std::string> sets;
};

// The largest sqrt(J2) of the material's yield surface over (p, D, u)
// (physics/plasticity.hpp: yield_limit_sqrt_j2, the limit the return
// enforces; the Collins surface reads D and u).
int strength_command(const StrengthArgs& args) {
  const std::vector<double> p = parse_range(args.p, "--p", true, true);
  const std::vector<double> damage = parse_range(args.damage, "--damage", true);
  const std::vector<double> u = parse_range(args.u, "--u", true);
  if (damage.back() > 1) throw rubble::InputError("--damage", "", "damage lies in [0, 1], got up to " + args.damage);
  if (double(p.size()) * double(damage.size()) * double(u.size()) > 1e7)
    throw rubble::InputError("--p/--damage/--u", "", "more than the 1e7 rows a table may have; use fewer points");
  const rubble::MaterialConfig m = rubble::load_material(args.material, args.sets);
  if (m.plasticity.model == rubble::PlasticityModel::None)
    throw rubble::InputError(m.library_file.empty() ? args.material : m.library_file, "plasticity",
                             "the material has no yield surface to tabulate (no [plasticity] table)");
  const rubble::PlasticityParams pp = rubble::plasticity_params_from_config(m.plasticity);
  const bool csv = args.format == "csv";
  if (csv) {
    std::printf("p,damage,u,sqrt_J2_max\n");
  } else {
    std::printf("# %s: yield surface, from %s\n# source: %s\n", m.name.c_str(), m.library_file.c_str(),
                m.source.c_str());
    std::printf("# sqrt_J2_max: the largest sqrt(J2) it admits (von Mises: Y/sqrt(3)); p [Pa], u [J/kg]\n");
    std::printf("%15s %8s %15s %15s\n", "p", "damage", "u", "sqrt_J2_max");
  }
  for (double e : u)
    for (double d : damage)
      for (double q : p) {
        const double y = double(rubble::yield_limit_sqrt_j2(pp, rubble::Real(q), rubble::Real(d), rubble::Real(e)));
        if (csv) std::printf("%.17g,%.17g,%.17g,%.17g\n", q, d, e, y);
        else std::printf("%15.7e %8.4f %15.7e %15.7e\n", q, d, e, y);
      }
  return std::fflush(stdout) == 0 ? 0 : 1;
}

// The regime, plus the add-ons that changed the value: compressed,
// expanded_cold+cutoff+c2_floor, ...
std::string regime_label(const rubble::EosState& s) {
  std::string r = rubble::eos_regime_name(s.regime);
  if (s.limited & rubble::kEosTensionCutOff) r += "+cutoff";
  if (s.limited & rubble::kEosPressureFloor) r += "+p_min";
  if (s.limited & rubble::kEosSoundSpeedFloor) r += "+c2_floor";
  if (s.limited & rubble::kEosMinSoundSpeed) r += "+cs_min";
  if (s.limited & rubble::kEosEnergyFloor) r += "+u_floor";
  return r;
}

int eos_command(const EosArgs& args) {
  const std::vector<double> rho = parse_range(args.rho, "--rho", false);
  const std::vector<double> u = parse_range(args.u, "--u", true);
  constexpr double kMaxRows = 1e7;  // ~1 GB of CSV: more is a mistake, not a table
  if (double(rho.size()) * double(u.size()) > kMaxRows)
    throw rubble::InputError("--rho/--u", "",
                             std::to_string(rho.size()) + " x " + std::to_string(u.size()) +
                                 " states is more than the 1e7 rows a table may have; use fewer points");
  const rubble::MaterialConfig m = rubble::load_material(args.material, args.sets);
  const rubble::EosParams eos = rubble::eos_params_from_material(m);
  const bool csv = args.format == "csv";
  if (csv) {
    std::printf("rho,u,p,c_s,regime\n");
  } else {
    std::printf("# %s: %s EOS, from %s\n# source: %s\n", m.name.c_str(), rubble::eos_kind_name(m.eos),
                m.library_file.c_str(), m.source.c_str());
    if (m.units == "SI") std::printf("# units: rho [kg/m^3], u [J/kg], p [Pa], c_s [m/s]\n");
    else std::printf("# units: %s\n", m.units.c_str());
    std::printf("%15s %15s %15s %15s  %s\n", "rho", "u", "p", "c_s", "regime");
  }
  long nonfinite = 0;
  for (double r : rho)
    for (double e : u) {
      const rubble::EosState s = rubble::eos_evaluate(eos, rubble::Real(r), rubble::Real(e));
      const double cs = s.c2 > 0 ? std::sqrt(double(s.c2)) : std::isnan(double(s.c2)) ? double(s.c2) : 0.0;
      std::string label = regime_label(s);
      // a state outside the EOS's range of numbers is flagged, never silent
      if (!std::isfinite(double(s.p)) || !std::isfinite(cs)) {
        label += "+NONFINITE";
        ++nonfinite;
      }
      if (csv)
        std::printf("%.17g,%.17g,%.17g,%.17g,%s\n", r, e, double(s.p), cs, label.c_str());
      else
        std::printf("%15.7e %15.7e %15.7e %15.7e  %s\n", r, e, double(s.p), cs, label.c_str());
    }
  if (nonfinite > 0)
    std::fprintf(stderr,
                 "rubble: warning: %ld of %zu states give a non-finite pressure or sound speed (marked +NONFINITE): "
                 "outside the range of numbers this EOS can represent\n",
                 nonfinite, rho.size() * u.size());
  return std::fflush(stdout) == 0 ? 0 : 1;
}

int info_command() {
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  std::cout << "rubble " << RUBBLE_VERSION << " (commit " << RUBBLE_COMMIT << ")\n"
            << "backends:        cpu" << (rubble::backend_built(rubble::Backend::Cuda) ? ", cuda" : "") << "\n"
            << "precision:       " << (sizeof(rubble::Real) == 8 ? "double" : "float") << "\n"
            << "OpenMP threads:  " << threads
#ifndef _OPENMP
            << " (built without OpenMP)"
#endif
            << "\n"
            << "GPU seen:        " << rubble::gpu_description() << "\n"
            << "memory free:     "
            << (rubble::available_memory_bytes() > 0 ? rubble::format_bytes(rubble::available_memory_bytes())
                                                     : std::string("unknown"))
            << " (a run refuses a scene whose estimate exceeds it; RUBBLE_MEMORY_LIMIT overrides)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rubble: a compact SPH solver for solids, regolith and planetary impacts"};
  app.require_subcommand(1);

  RunArgs run_args;
  CLI::App* run = app.add_subcommand("run", "Run a scene (TOML file) to its end time");
  run->add_option("SCENE", run_args.scene, "The scene file (TOML); keys are documented in docs/scene.md");
  run->add_option("--restart", run_args.restart,
                  "Resume from a snapshot or checkpoint this program wrote (DIR/NAME.NNNN.h5 or "
                  "DIR/NAME.checkpoint.h5) instead of starting SCENE; output continues in DIR unless --out "
                  "names a new directory; --set may then change only simulation.end_time, simulation.max_steps "
                  "and output.*");
  run->add_option("--max-wall-time", run_args.max_wall_time,
                  "Stop cleanly with a checkpoint before this wall time has passed: seconds or H:MM:SS (exit code 4)");
  run->add_option("--checkpoint-every", run_args.checkpoint_every,
                  "Also write the checkpoint NAME.checkpoint.h5 every so many wall seconds (or H:MM:SS)");
  run->add_option("--out", run_args.out,
                  "Output directory for snapshots and conserved.csv (default: out/<scene file stem>); "
                  "must not exist or be empty");
  run->add_option("--backend", run_args.backend,
                  "Compute backend: cpu or cuda (default: $RUBBLE_BACKEND, else cpu)")
      ->check(CLI::IsMember({"cpu", "cuda"}));
  run->add_option("--set", run_args.sets,
                  "Override a scene key, e.g. --set simulation.end_time=0.5 or --set bodies.0.spacing=0.01 "
                  "(value parsed as TOML, else taken as a string; repeatable)")
      ->allow_extra_args(false);
  run->add_flag("-q,--quiet", run_args.quiet, "No progress output");
  run->add_flag("--timings", run_args.timings,
                "At the end, print where the wall time went: set-up, neighbour search, density, EOS, forces, "
                "integration, output, ...");

  app.add_subcommand("info", "Show version, backends, precision, OpenMP threads and GPU");

  EosArgs eos_args;
  CLI::App* eos = app.add_subcommand(
      "eos", "Tabulate pressure, sound speed and regime of a material over a (rho, u) grid (docs/user-guide.md)");
  eos->add_option("MATERIAL", eos_args.material,
                  "A library material (reference_data/materials/NAME.toml, or $RUBBLE_MATERIALS) or a file NAME.toml")
      ->required();
  eos->add_option("--rho", eos_args.rho, "Densities A:B:N (N points from A to B) or A:B:N:log")->required();
  eos->add_option("--u", eos_args.u, "Specific internal energies C:D:M or C:D:M:log")->required();
  eos->add_option("--format", eos_args.format, "Output: an aligned table or CSV")
      ->check(CLI::IsMember({"table", "csv"}))
      ->capture_default_str();
  eos->add_option("--set", eos_args.sets,
                  "Override a material key, e.g. --set tillotson.A=3e10 or --set rho_limit=0.9 (repeatable)")
      ->allow_extra_args(false);

  StrengthArgs strength_args;
  CLI::App* strength = app.add_subcommand(
      "strength", "Tabulate a material's yield surface, the largest sqrt(J2) over pressure, damage and u "
                  "(docs/user-guide.md)");
  strength->add_option("MATERIAL", strength_args.material,
                       "A library material (reference_data/materials/NAME.toml, or $RUBBLE_MATERIALS) or a file NAME.toml")
      ->required();
  strength->add_option("--p", strength_args.p, "Pressures A:B:N (may be negative: tension) or A:B:N:log")->required();
  strength->add_option("--damage", strength_args.damage, "Damage values A:B:N in [0, 1]")->capture_default_str();
  strength->add_option("--u", strength_args.u, "Specific internal energies C:D:M")->capture_default_str();
  strength->add_option("--format", strength_args.format, "Output: an aligned table or CSV")
      ->check(CLI::IsMember({"table", "csv"}))
      ->capture_default_str();
  strength->add_option("--set", strength_args.sets,
                       "Override a material key, e.g. --set plasticity.cohesion=1e7 (repeatable)")
      ->allow_extra_args(false);

  // CLI11 would only say that a subcommand is required: name the word.
  if (argc > 1 && argv[1][0] != '-') {
    const std::string word = argv[1];
    if (word != "run" && word != "eos" && word != "strength" && word != "info") {
      std::cerr << "rubble: error: unknown command '" << word
                << "'; expected run, eos, strength or info (rubble --help)\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is a "ParseError" with code 0
  }

  try {
    if (*run) return run_command(run_args);
    if (*eos) return eos_command(eos_args);
    if (*strength) return strength_command(strength_args);
    return info_command();
  } catch (const rubble::InputError& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    return 2;
  } catch (const rubble::RunError& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    // --timings on a failed run too (issue #50 item 6)
    if (*run && run_args.timings && !e.phase_seconds.empty()) {
      std::printf("rubble: where the time went before the failure (wall seconds, share of %.3g s):\n", e.wall_seconds);
      for (const auto& [phase, seconds] : e.phase_seconds)
        std::printf("  %-40s %10.3f  %5.1f %%\n", phase.c_str(), seconds, 100 * seconds / e.wall_seconds);
      std::fflush(stdout);
    }
    return 3;
  } catch (const rubble::OutputError& e) {
    std::cerr << "rubble: error: output: " << e.what() << "\n";
    return 5;
  } catch (const std::exception& e) {
    std::cerr << "rubble: error: " << e.what() << "\n";
    return 1;
  }
}
