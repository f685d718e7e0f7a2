// rubble_throughput: how fast the solver runs, in the units issue #6 asks
// for (docs/gpu.md). Each --case starts a measurement; the options after it
// belong to that case:
//
//   rubble_throughput [--backend cpu|cuda] [--json FILE]
//       --case hydro3d --n N --steps K [--repeat R]
//       --case rings [--spacing DX] [--steps K] [--scene FILE] [--repeat R]
//       --case barnes_hut --n N [--theta T] [--repeat R]
//       [--case ...]
// Defaults: rings spacing 0.0375 and 200 steps, theta 0.5; --repeat (best
// of R) 1 for the stepped cases, 3 for barnes_hut.
//
// hydro3d: a 3-D ideal gas (gamma 5/3, rho 1, p 1) filling the periodic
//   unit cube on a cubic lattice of side L (N rounded to L^3, L even), the
//   two halves x < 1/2 and x > 1/2 sliding past each other at +-0.1 along y
//   (a gentle shear layer, so that the particles move and the viscosity
//   works); summation density, cubic spline, leapfrog.
// rings: the colliding rubber rings of validation/rubber_rings, with the
//   spacing of both rings set by --set exactly as the rung does.
// Both run through rubble::parse_scene / load_scene_file and
//   rubble::run_scene (write_output = false, quiet), like any run. The end
//   time is K Courant steps of the initial state (estimated from the scene
//   with the solver's own physics functions), so a run takes about K steps;
//   the steps actually taken are reported. Each case runs twice: once for
//   about one step (set-up: particle generation, sort, first evaluation) and
//   once for K steps (best of --repeat each); the rate is
//   N x (extra steps) / (extra wall time),
//   i.e. set-up excluded; the rate with set-up included is reported too.
//   A tiny run of the same case first warms the backend up (thread pool,
//   device context, kernel modules) so that neither timed run pays for it.
//   Device resident: with write_output = false a run writes no snapshot and
//   no conserved.csv row, so the CUDA backend copies its state to the host
//   once, at the end (FinalState::device_to_host_bytes); both timed runs pay
//   that copy, so the difference holds steps only. The case reports the
//   device-to-host bytes per extra step (0 when the state stays on the
//   device; a NOTE otherwise) and, on cuda, the host synchronisations per
//   step (cuda_backend_counts()).
// Device memory (cuda): the peak of the device's memory in use
//   (cudaMemGetInfo, sampled every 2 ms by a second host thread while each
//   timed run lasts) less what was in use before it, divided by N:
//   device_bytes_per_particle. It counts everything the run holds on the
//   device (the particle store, the state check's copy, the neighbour grid,
//   sort and reduction buffers, the octree) in the driver's allocation
//   granularity (2 MiB), so it means something from about 1e5 particles
//   up. On cpu: '-' (the state is in host memory; not measured).
// barnes_hut: a Plummer sphere of N equal masses (G = 1, no softening) and
//   rubble::Octree with the solver's defaults (quadrupole, leaves of 8,
//   groups of 32) at --theta; build + walk, best of --repeat; the rate is
//   N / (build + walk) particles per second. With --backend cuda: the
//   device octree (rubble/gravity/device_gravity.hpp, one walk per particle,
//   leaves of 8), timed the same way.
//
// Output: one line per case,
//   RESULT case=NAME status=ok|failed backend=B threads=T precision=P key=value ...
// (space-separated, no spaces inside a value; the case's own keys include
// measured_on, the backend that actually did the work, n, rate and
// rate_unit), and with --json FILE the same
// numbers as a JSON document. Exit status: 0 if every case ran, 1 if one
// failed (the others still run), 2 on bad usage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#ifdef RUBBLE_HAVE_CUDA
#include <cuda_runtime.h>

#include <atomic>
#include <thread>
#endif

#include "../verification/common/record.hpp"
#include "rubble/core/error.hpp"
#include "rubble/core/real.hpp"
#include "rubble/gravity/octree.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/solid.hpp"
#include "rubble/physics/timestep.hpp"
#include "rubble/gravity/device_gravity.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene_parser.hpp"

#ifndef RUBBLE_COMMIT
#define RUBBLE_COMMIT "unknown"
#endif
#ifndef RUBBLE_VERSION
#define RUBBLE_VERSION "unknown"
#endif
#ifndef RUBBLE_SOURCE_DIR
#define RUBBLE_SOURCE_DIR "."
#endif

using rubble::Real;
using rubble::verification::Json;

namespace {

// Bad command line: message, exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* kUsage =
    "usage: rubble_throughput [--backend cpu|cuda] [--json FILE]\n"
    "           --case hydro3d --n N --steps K [--repeat R]\n"
    "           --case rings [--spacing DX] [--steps K] [--scene FILE] [--repeat R]\n"
    "           --case barnes_hut --n N [--theta T] [--repeat R]\n"
    "           [--case ...]\n"
    "Each --case starts a measurement; the options after it belong to it.\n"
    "--backend defaults to $RUBBLE_BACKEND (cpu when unset). Details: docs/gpu.md.\n";

struct CaseArgs {
  std::string name;
  double n = 0;           // hydro3d, barnes_hut: particles asked for
  double spacing = 0.0375;  // rings
  long steps = 0;         // hydro3d, rings
  std::string scene = std::string(RUBBLE_SOURCE_DIR) + "/validation/rubber_rings/rubber_rings.toml";
  double theta = 0.5;     // barnes_hut
  int repeat = 0;         // 0: the case's default (barnes_hut 3, the others 1)
  std::vector<std::string> given;  // options given, to reject those of another case
};

struct Args {
  rubble::Backend backend = rubble::Backend::Cpu;  // parse_args: --backend, else $RUBBLE_BACKEND
  std::string json;
  std::vector<CaseArgs> cases;
};

double number(const std::string& option, const std::string& value) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != value.size() || !std::isfinite(v)) throw UsageError(option + ": '" + value + "' is not a number");
  return v;
}

long whole(const std::string& option, const std::string& value, long min) {
  const double v = number(option, value);
  if (v != std::floor(v) || v < double(min) || v > 1e15)
    throw UsageError(option + ": '" + value + "' must be a whole number >= " + std::to_string(min));
  return long(v);
}

Args parse_args(int argc, char** argv) {
  Args a;
  a.backend = rubble::default_backend();  // throws InputError for a bad RUBBLE_BACKEND
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--help" || k == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError("missing value after " + k);
      return argv[++i];
    };
    if (k == "--backend") {
      if (!a.cases.empty()) throw UsageError("--backend applies to every case: give it before the first --case");
      a.backend = rubble::parse_backend(next(), "rubble_throughput --backend");
      continue;
    }
    if (k == "--json") {
      if (!a.cases.empty()) throw UsageError("--json applies to every case: give it before the first --case");
      a.json = next();
      continue;
    }
    if (k == "--case") {
      CaseArgs c;
      c.name = next();
      if (c.name != "hydro3d" && c.name != "rings" && c.name != "barnes_hut")
        throw UsageError("--case: unknown case '" + c.name + "' (hydro3d, rings, barnes_hut)");
      a.cases.push_back(c);
      continue;
    }
    if (a.cases.empty()) throw UsageError("unknown option " + k + " (case options follow a --case)");
    CaseArgs& c = a.cases.back();
    const bool hydro = c.name == "hydro3d", rings = c.name == "rings", bh = c.name == "barnes_hut";
    const bool fits = (k == "--n" && (hydro || bh)) || (k == "--steps" && (hydro || rings)) ||
                      ((k == "--spacing" || k == "--scene") && rings) || (k == "--theta" && bh) || k == "--repeat";
    if (!fits) throw UsageError("option " + k + " does not belong to --case " + c.name);
    c.given.push_back(k);
    if (k == "--n") c.n = double(whole(k, next(), 1));
    else if (k == "--steps") c.steps = whole(k, next(), 2);
    else if (k == "--spacing") {
      c.spacing = number(k, next());
      if (!(c.spacing > 0)) throw UsageError("--spacing must be > 0");
    } else if (k == "--scene") c.scene = next();
    else if (k == "--theta") {
      c.theta = number(k, next());
      if (c.theta < 0 || c.theta > 1) throw UsageError("--theta must be in [0, 1]");
    } else if (k == "--repeat") c.repeat = int(whole(k, next(), 1));
  }
  if (a.cases.empty()) throw UsageError("no --case given");
  for (const CaseArgs& c : a.cases) {
    auto has = [&](const char* o) { return std::find(c.given.begin(), c.given.end(), o) != c.given.end(); };
    if ((c.name == "hydro3d" || c.name == "barnes_hut") && !has("--n"))
      throw UsageError("--case " + c.name + " needs --n");
    if (c.name == "hydro3d" && !has("--steps")) throw UsageError("--case hydro3d needs --steps");
  }
  for (CaseArgs& c : a.cases) {
    if (c.name == "rings" && c.steps == 0) c.steps = 200;
    if (c.repeat == 0) c.repeat = c.name == "barnes_hut" ? 3 : 1;
  }
  return a;
}

int threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string fmt(double v, const char* f = "%.6g") {
  char b[48];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// One finished measurement: the RESULT line's fields, in order, and the
// same as JSON.
struct Result {
  std::vector<std::pair<std::string, std::string>> text;
  std::vector<std::pair<std::string, Json>> json;
  void add(const std::string& k, const std::string& v) {
    text.emplace_back(k, v);
    json.emplace_back(k, Json(v));
  }
  void add(const std::string& k, double v, const char* f = "%.6g") {
    text.emplace_back(k, fmt(v, f));
    json.emplace_back(k, Json(v));
  }
  void add(const std::string& k, long long v) {
    text.emplace_back(k, std::to_string(v));
    json.emplace_back(k, Json(v));
  }
  void add_none(const std::string& k) {  // not measured: '-' on the RESULT line, null in the JSON
    text.emplace_back(k, "-");
    json.emplace_back(k, Json());
  }
};

// The device memory a run holds at its peak, in bytes (see the header):
// started before the run, stop() after it. -1 where not measured (cpu
// backend, a CPU-only build, no device), 0 when no sample saw the run's
// memory (a run shorter than the sampling interval).
class DeviceMemoryWatch {
 public:
  explicit DeviceMemoryWatch(rubble::Backend backend) {
#ifdef RUBBLE_HAVE_CUDA
    if (backend != rubble::Backend::Cuda) return;
    baseline_ = used();
    if (baseline_ < 0) return;
    peak_.store(baseline_);
    thread_ = std::thread([this] {
      while (!stop_.load()) {
        sample();
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    });
#else
    (void)backend;
#endif
  }
  ~DeviceMemoryWatch() { stop(); }
  DeviceMemoryWatch(const DeviceMemoryWatch&) = delete;
  DeviceMemoryWatch& operator=(const DeviceMemoryWatch&) = delete;

  std::int64_t stop() {
#ifdef RUBBLE_HAVE_CUDA
    if (thread_.joinable()) {
      stop_.store(true);
      thread_.join();
    }
    if (baseline_ < 0) return -1;
    return std::max<std::int64_t>(0, peak_.load() - baseline_);
#else
    return -1;
#endif
  }

 private:
#ifdef RUBBLE_HAVE_CUDA
  // the device's memory in use (all processes), -1 if it cannot be asked
  static std::int64_t used() {
    std::size_t free_b = 0, total_b = 0;
    if (cudaMemGetInfo(&free_b, &total_b) != cudaSuccess) {
      cudaGetLastError();  // clear it: the run reports its own errors
      return -1;
    }
    return std::int64_t(total_b - free_b);
  }
  void sample() {
    const std::int64_t u = used();
    std::int64_t p = peak_.load();
    while (u > p && !peak_.compare_exchange_weak(p, u)) {
    }
  }
  std::int64_t baseline_ = -1;
  std::atomic<std::int64_t> peak_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
#endif
};

// Host synchronisations of the CUDA backend so far (0 on cpu).
std::int64_t host_synchronisations() {
#ifdef RUBBLE_HAVE_CUDA
  return rubble::cuda_backend_counts().host_synchronisations;
#else
  return 0;
#endif
}

// The device-memory fields of a case: bytes in all, and per particle.
void add_device_memory(Result& r, std::int64_t bytes, double n, rubble::Backend backend) {
  if (bytes > 0) {
    r.add("device_bytes", (long long)bytes);
    r.add("device_bytes_per_particle", double(bytes) / n, "%.4g");
  } else {
    r.add_none("device_bytes");
    r.add_none("device_bytes_per_particle");
    std::printf("NOTE: device memory not measured: %s\n",
                backend != rubble::Backend::Cuda ? "the cpu backend keeps the state in host memory"
                : bytes == 0 ? "no sample saw the run's memory (too short a run)"
                             : "cudaMemGetInfo failed");
  }
}

// ---- time-stepped cases (hydro3d, rings) --------------------------------------

// The Courant step of the initial state: the smallest over the bodies of
// C hM / (c + 0.6 alpha c) (physics/timestep.hpp with mu = 0: bodies at
// rest relative to themselves), c the sound speed of the body's density and
// internal energy (the longitudinal wave speed for solids), hM the Monaghan
// smoothing length of its lattice. An estimate only: the run's own limit
// decides each step, and the steps taken are what is reported.
template <int D>
double initial_courant_dt(const rubble::Scene& scene) {
  const rubble::SimulationConfig& sim = scene.simulation;
  const double hfact = sim.hfact > 0 ? sim.hfact : rubble::kernel_default_hfact(sim.kernel);
  double dt = 1e300;
  for (const rubble::BodyConfig& b : scene.bodies) {
    if (b.shape == rubble::BodyShape::Polytrope)
      throw std::runtime_error("the step estimate does not handle polytrope bodies");
    const rubble::MaterialConfig& mat = scene.materials.at(std::size_t(b.material_id));
    const rubble::EosParams eos = rubble::eos_params_from_material(mat);
    const Real rho = Real(b.density);
    const Real u = b.internal_energy >= 0 ? Real(b.internal_energy)
                                          : rubble::eos_internal_energy_from_pressure(eos, rho, Real(b.pressure));
    Real c = std::sqrt(rubble::eos_evaluate(eos, rho, u).c2);
    if (mat.shear_modulus > 0) c = rubble::elastic_signal_speed(c, Real(mat.shear_modulus), rho);
    const double cell = std::pow(rubble::lattice_cell_volume<D>(b.lattice, b.spacing), 1.0 / D);
    const Real hM = rubble::monaghan_h<D>(sim.kernel, Real(hfact * cell));
    dt = std::min(dt, double(rubble::courant_dt(Real(sim.courant), hM, c, Real(mat.viscosity.alpha),
                                                Real(mat.viscosity.beta), Real(0))));
  }
  return dt;
}

double initial_courant_dt(const rubble::Scene& scene) {
  switch (scene.simulation.dimension) {
    case 1: return initial_courant_dt<1>(scene);
    case 2: return initial_courant_dt<2>(scene);
    default: return initial_courant_dt<3>(scene);
  }
}

// What a timed run leaves (the final particle arrays are dropped at once:
// at 8e6 particles they hold about 1 GB).
struct Timed {
  double wall = 0;
  long long steps = 0, particle_evaluations = 0, n = 0;
  long long device_to_host_bytes = 0, host_synchronisations = 0;
  std::int64_t device_bytes = -1;  // DeviceMemoryWatch
  std::string backend;
};

Timed timed_run(const rubble::Scene& scene, rubble::Backend backend) {
  rubble::RunOptions opt;
  opt.backend = backend;
  opt.write_output = false;  // no snapshot, no conserved.csv: nothing leaves the device until the end
  opt.quiet = true;
  const std::int64_t syncs0 = host_synchronisations();
  DeviceMemoryWatch memory(backend);
  const auto t0 = std::chrono::steady_clock::now();
  const rubble::FinalState fs = rubble::run_scene(scene, opt);
  Timed r;
  r.wall = seconds_since(t0);
  r.device_bytes = memory.stop();
  r.host_synchronisations = host_synchronisations() - syncs0;
  r.steps = fs.steps;
  r.particle_evaluations = fs.particle_evaluations;
  r.n = (long long)fs.m.size();
  r.device_to_host_bytes = fs.device_to_host_bytes;
  r.backend = fs.backend;
  return r;
}

// A scene with the given end time (no snapshots, no output interval that
// would cut steps short). `load` parses the scene with extra overrides.
template <class Load>
rubble::Scene scene_until(const Load& load, double end_time) {
  return load({"simulation.end_time=" + fmt(end_time, "%.17g"), "output.interval=0", "output.snapshots=false"});
}

// Runs the scene for about one and about K steps (each `repeat` times,
// keeping the shortest wall time) and fills the rate fields.
template <class Load>
void measure_steps(const Load& load, const Load& load_tiny, long steps, int repeat, rubble::Backend backend,
                   Result& r) {
  const double dt = initial_courant_dt(load({}));
  if (!(dt > 0 && dt < 1e299)) throw std::runtime_error("could not estimate the time step of the scene");
  timed_run(scene_until(load_tiny, dt), backend);  // warm-up, not timed
  const rubble::Scene short_scene = scene_until(load, 0.5 * dt), long_scene = scene_until(load, double(steps) * dt);
  Timed one, many;
  std::int64_t device_bytes = -1;
  for (int rep = 0; rep < repeat; ++rep) {
    Timed a = timed_run(short_scene, backend);
    Timed b = timed_run(long_scene, backend);
    device_bytes = std::max({device_bytes, a.device_bytes, b.device_bytes});
    if (rep == 0 || a.wall < one.wall) one = std::move(a);
    if (rep == 0 || b.wall < many.wall) many = std::move(b);
  }
  const double n = double(many.n);
  const long long extra_steps = many.steps - one.steps;
  const double extra_wall = many.wall - one.wall;
  if (extra_steps < 1) throw std::runtime_error("the long run took no more steps than the short one");
  // Too short a run to time against the noise of the machine: no rate.
  const double step_s = extra_wall > 0 ? extra_wall / double(extra_steps) : NAN;
  const double evals = double(many.particle_evaluations - one.particle_evaluations) / n;
  r.add("measured_on", many.backend);
  r.add("n", many.n);
  r.add("steps", many.steps);
  r.add("evaluations_per_step", evals / double(extra_steps), "%.3g");
  r.add("dt_estimate", dt, "%.4g");
  r.add("repeat", (long long)repeat);
  r.add("wall_s", many.wall, "%.4g");
  r.add("setup_s", std::isfinite(step_s) ? std::max(0.0, one.wall - double(one.steps) * step_s) : NAN, "%.4g");
  r.add("step_s", step_s, "%.4g");
  r.add("rate", n / step_s, "%.4g");
  r.add("rate_with_setup", n * double(many.steps) / many.wall, "%.4g");
  r.add("rate_unit", "particle_steps_per_s");
  // Device resident: the long run's extra steps copied nothing to the host
  // (both runs download the final state once).
  const double d2h_per_step = double(many.device_to_host_bytes - one.device_to_host_bytes) / double(extra_steps);
  r.add("d2h_bytes_per_step", d2h_per_step, "%.4g");
  r.add("d2h_bytes_final_state", many.device_to_host_bytes);
  if (backend == rubble::Backend::Cuda)
    r.add("host_syncs_per_step",
          double(many.host_synchronisations - one.host_synchronisations) / double(extra_steps), "%.3g");
  add_device_memory(r, device_bytes, n, backend);
  if (d2h_per_step != 0)
    std::printf("NOTE: %.4g bytes per step copied from the device to the host: the steps were not device resident\n",
                d2h_per_step);
  if (!std::isfinite(step_s))
    std::printf("NOTE: the %lld-step run was not slower than the short one (too short to time): no rate\n",
                many.steps);
}

void run_hydro3d(const CaseArgs& c, rubble::Backend backend, Result& r) {
  // lattice side: the even number nearest to cbrt(N), at least 8 (a
  // periodic axis must be longer than 2.5 h = 2.5 * 2.4 dx)
  const long side = std::max(8L, 2 * std::lround(std::cbrt(c.n) / 2));
  auto scene_text = [](long s) {
    const std::string dx = fmt(1.0 / double(s), "%.17g");
    return "[simulation]\n"
           "dimension = 3\n"
           "end_time = 1.0\n"
           "integrator = \"leapfrog\"\n"
           "kernel = \"cubic_spline\"\n"
           "density = \"summation\"\n"
           "courant = 0.3\n"
           "[materials.gas]\n"
           "eos = \"ideal_gas\"\n"
           "gamma = 1.6666666666666667\n"
           "viscosity = { alpha = 1.0, beta = 2.0 }\n"
           "[[bodies]]\n"
           "shape = \"box\"\nmaterial = \"gas\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 1.0, 1.0]\n"
           "spacing = " + dx + "\ndensity = 1.0\npressure = 1.0\nvelocity = [0.0, 0.1, 0.0]\n"
           "[[bodies]]\n"
           "shape = \"box\"\nmaterial = \"gas\"\nmin = [0.5, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n"
           "spacing = " + dx + "\ndensity = 1.0\npressure = 1.0\nvelocity = [0.0, -0.1, 0.0]\n"
           "[domain]\n"
           "periodic = [true, true, true]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n";
  };
  using Load = std::function<rubble::Scene(const std::vector<std::string>&)>;
  const std::string text = scene_text(side), tiny = scene_text(8);
  const Load load = [&](const std::vector<std::string>& sets) { return rubble::parse_scene(text, "hydro3d", sets); };
  const Load load_tiny = [&](const std::vector<std::string>& sets) {
    return rubble::parse_scene(tiny, "hydro3d (warm-up)", sets);
  };
  r.add("n_requested", (long long)c.n);
  r.add("lattice", std::to_string(side) + "^3");
  measure_steps(load, load_tiny, c.steps, c.repeat, backend, r);
}

void run_rings(const CaseArgs& c, rubble::Backend backend, Result& r) {
  if (!std::filesystem::exists(c.scene))
    throw rubble::InputError(c.scene, "", "no such scene file (--scene, or the source tree's rubber-ring scene)");
  using Load = std::function<rubble::Scene(const std::vector<std::string>&)>;
  auto loader = [&](double dx) {
    return Load([dx, &c](const std::vector<std::string>& extra) {
      // the rung's overrides (validation/rubber_rings/rubber_rings_rung.cpp)
      std::vector<std::string> sets = {"bodies.0.spacing=" + fmt(dx, "%.17g"), "bodies.1.spacing=" + fmt(dx, "%.17g")};
      sets.insert(sets.end(), extra.begin(), extra.end());
      return rubble::load_scene_file(c.scene, sets);
    });
  };
  r.add("spacing", c.spacing);
  measure_steps(loader(c.spacing), loader(0.3), c.steps, c.repeat, backend, r);
}

// Plummer sphere, scale radius 1, total mass 1: radii from the inverse of
// M(<r)/M = r^3 / (1 + r^2)^(3/2) (Aarseth, Hénon & Wielen 1974), redrawn
// beyond r = 10; isotropic directions. Fixed seed.
std::vector<rubble::Vec<3>> plummer_sphere(std::size_t n) {
  std::mt19937_64 rng(0x7412ULL + n);
  auto u01 = [&]() { return double(rng() >> 11) * 0x1.0p-53; };
  std::vector<rubble::Vec<3>> x(n);
  for (auto& p : x) {
    double r = 0;
    do {
      const double q = u01();
      r = q > 0 ? 1.0 / std::sqrt(std::pow(q, -2.0 / 3.0) - 1.0) : 0.0;
    } while (!(r <= 10.0));
    const double z = 2 * u01() - 1, phi = 2 * std::numbers::pi * u01();
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    p[0] = Real(r * s * std::cos(phi));
    p[1] = Real(r * s * std::sin(phi));
    p[2] = Real(r * z);
  }
  return x;
}

// The device octree (rubble/gravity/device_gravity.hpp: the one --backend
// cuda runs use; one walk per particle), timed by the library call itself.
void run_barnes_hut_device(const CaseArgs& c, Result& r) {
  const std::size_t n = std::size_t(c.n);
  if (n < 2) throw std::runtime_error("--n must be at least 2 for a tree");
  const std::vector<rubble::Vec<3>> x = plummer_sphere(n);
  const std::vector<Real> m(n, Real(1.0 / double(n)));
  std::vector<rubble::Vec<3>> acc(n);
  rubble::GravityConfig g;  // quadrupole, leaves of 8, G = 1 below
  g.mode = rubble::GravityMode::BarnesHut;
  g.G = 1;
  g.theta = c.theta;
  double best_build = 1e300, best_walk = 1e300;
  std::uint32_t nodes = 0;
  // warm-up (device context, kernel modules), not timed: a small tree
  const std::size_t n_warm = std::min<std::size_t>(n, 4096);
  rubble::cuda_barnes_hut_field(x.data(), m.data(), nullptr, n_warm, g, rubble::KernelType::CubicSpline, acc.data(),
                                nullptr);
  std::int64_t device_bytes = -1;
  for (int rep = 0; rep < c.repeat; ++rep) {
    DeviceMemoryWatch memory(rubble::Backend::Cuda);
    const rubble::DeviceGravityTiming t =
        rubble::cuda_barnes_hut_field(x.data(), m.data(), nullptr, n, g, rubble::KernelType::CubicSpline, acc.data(),
                                      nullptr);
    device_bytes = std::max(device_bytes, memory.stop());
    best_build = std::min(best_build, t.build_seconds);
    best_walk = std::min(best_walk, t.walk_seconds);
    nodes = t.nodes;
  }
  for (const auto& a : acc)
    if (!std::isfinite(double(a[0])) || !std::isfinite(double(a[1])) || !std::isfinite(double(a[2])))
      throw std::runtime_error("the tree walk gave a non-finite acceleration");
  r.add("measured_on", "cuda");
  r.add("n", (long long)n);
  r.add("theta", c.theta);
  r.add("order", "quadrupole");
  r.add("leaf_size", (long long)g.leaf_size);
  r.add("group_size", 1LL);
  r.add("nodes", (long long)nodes);
  r.add("repeat", (long long)c.repeat);
  r.add("build_s", best_build, "%.4g");
  r.add("walk_s", best_walk, "%.4g");
  r.add("rate", double(n) / (best_build + best_walk), "%.4g");
  r.add("rate_unit", "particles_per_s");
  add_device_memory(r, device_bytes, double(n), rubble::Backend::Cuda);
}

void run_barnes_hut(const CaseArgs& c, rubble::Backend backend, Result& r) {
  if (backend == rubble::Backend::Cuda) {
    run_barnes_hut_device(c, r);
    return;
  }
  const std::size_t n = std::size_t(c.n);
  if (n < 2) throw std::runtime_error("--n must be at least 2 for a tree");
  const std::vector<rubble::Vec<3>> x = plummer_sphere(n);
  const std::vector<Real> m(n, Real(1.0 / double(n)));
  std::vector<rubble::Vec<3>> acc(n);
  rubble::OctreeOptions opt;  // the solver's defaults: quadrupole, leaves of 8, groups of 32
  opt.theta = Real(c.theta);
  double best_build = 1e300, best_walk = 1e300;
  double interactions = 0;
  std::size_t nodes = 0;
  for (int rep = 0; rep < c.repeat; ++rep) {
    rubble::Octree tree(opt);
    auto t0 = std::chrono::steady_clock::now();
    tree.build(x.data(), m.data(), nullptr, n);
    best_build = std::min(best_build, seconds_since(t0));
    t0 = std::chrono::steady_clock::now();
    tree.field(Real(1), acc.data(), nullptr);
    best_walk = std::min(best_walk, seconds_since(t0));
    const rubble::WalkCounts& wc = tree.last_counts();
    interactions = double(wc.multipoles + wc.pairs) / double(n);
    nodes = tree.node_count();
  }
  for (const auto& a : acc)
    if (!std::isfinite(double(a[0])) || !std::isfinite(double(a[1])) || !std::isfinite(double(a[2])))
      throw std::runtime_error("the tree walk gave a non-finite acceleration");
  r.add("measured_on", "cpu");
  r.add("n", (long long)n);
  r.add("theta", c.theta);
  r.add("order", "quadrupole");
  r.add("leaf_size", (long long)opt.leaf_size);
  r.add("group_size", (long long)opt.group_size);
  r.add("nodes", (long long)nodes);
  r.add("interactions_per_particle", interactions, "%.4g");
  r.add("repeat", (long long)c.repeat);
  r.add("build_s", best_build, "%.4g");
  r.add("walk_s", best_walk, "%.4g");
  r.add("rate", double(n) / (best_build + best_walk), "%.4g");
  r.add("rate_unit", "particles_per_s");
  add_device_memory(r, -1, double(n), backend);
}

std::string result_line(const Result& r) {
  std::string line = "RESULT";
  for (const auto& [k, v] : r.text) {
    std::string value = v.empty() ? "-" : v;
    for (char& ch : value)
      if (ch == ' ' || ch == '\t' || ch == '\n') ch = '_';
    line += " " + k + "=" + value;
  }
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse_args(argc, argv);
    if (!rubble::backend_built(args.backend))
      throw UsageError(std::string("--backend ") + rubble::backend_name(args.backend) +
                       ": this build has no such backend (configure with -DRUBBLE_CUDA=ON for cuda)");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "rubble_throughput: error: %s\n%s", e.what(), kUsage);
    return 2;
  } catch (const rubble::InputError& e) {  // parse_backend
    std::fprintf(stderr, "rubble_throughput: error: %s\n", e.what());
    return 2;
  }

  const std::string backend = rubble::backend_name(args.backend);
  const std::string precision = sizeof(Real) == 8 ? "double" : "float";
  std::printf("rubble_throughput %s (commit %s), backend %s, %s precision, %d OpenMP threads\n", RUBBLE_VERSION,
              RUBBLE_COMMIT, backend.c_str(), precision.c_str(), threads());
  std::fflush(stdout);

  std::vector<Json> records;
  int failures = 0;
  for (const CaseArgs& c : args.cases) {
    Result r;
    r.add("case", c.name);
    Result body;
    std::string error;
    try {
      if (c.name == "hydro3d") run_hydro3d(c, args.backend, body);
      else if (c.name == "rings") run_rings(c, args.backend, body);
      else run_barnes_hut(c, args.backend, body);
    } catch (const std::exception& e) {
      error = e.what();
    }
    r.add("status", error.empty() ? "ok" : "failed");
    r.add("backend", backend);
    r.add("threads", (long long)threads());
    r.add("precision", precision);
    for (std::size_t i = 0; i < body.text.size(); ++i) {
      r.text.push_back(body.text[i]);
      r.json.push_back(body.json[i]);
    }
    if (!error.empty()) {
      ++failures;
      std::fprintf(stderr, "rubble_throughput: error: --case %s: %s\n", c.name.c_str(), error.c_str());
      r.json.emplace_back("error", Json(error));
    }
    std::printf("%s\n", result_line(r).c_str());
    std::fflush(stdout);
    records.push_back(Json::object(r.json));
  }

  if (!args.json.empty()) {
    const Json doc = Json::object({{"program", "rubble_throughput"},
                                   {"version", RUBBLE_VERSION},
                                   {"commit", RUBBLE_COMMIT},
                                   {"backend", backend},
                                   {"precision", precision},
                                   {"threads", threads()},
                                   {"results", Json::array(records)}});
    const std::filesystem::path path(args.json);
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    std::ofstream f(path);
    f << doc.str() << "\n";
    if (!f) {
      std::fprintf(stderr, "rubble_throughput: error: --json %s: cannot write the file\n", args.json.c_str());
      return 1;
    }
  }
  return failures ? 1 : 0;
}
