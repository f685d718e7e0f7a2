// run_scene: set up particles from the scene, step them to the end time,
// write snapshots, the XDMF index and conserved.csv.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "hydro_cpu.hpp"
#ifdef RUBBLE_HAVE_CUDA
#include "cuda/cuda_stepper.hpp"
#endif
#include "rubble/core/error.hpp"
#include "rubble/gravity/device_gravity.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/io/conserved_log.hpp"
#include "rubble/io/progress.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/io/xdmf.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"

#ifndef RUBBLE_VERSION
#define RUBBLE_VERSION "0.0.0"
#endif
#ifndef RUBBLE_COMMIT
#define RUBBLE_COMMIT "unknown"
#endif

namespace rubble {
namespace {

// Writes snapshots NAME.NNNN.h5, NAME.xdmf and conserved.csv into out_dir.
template <int D>
class OutputWriter {
 public:
  OutputWriter(const Scene& scene, const RunOptions& opt)
      : scene_(scene), enabled_(opt.write_output), dir_(opt.out_dir) {
    if (!enabled_) return;
    std::filesystem::create_directories(dir_);
    xdmf_ = std::make_unique<XdmfWriter>((dir_ / (scene.output.name + ".xdmf")).string(), D);
    log_ = std::make_unique<ConservedLog>((dir_ / "conserved.csv").string(), D);
  }

  bool enabled() const { return enabled_; }
  // Whether snapshot() writes anything: the host state is fetched (on the
  // CUDA backend, downloaded) only then.
  bool writes_snapshots() const { return enabled_ && scene_.output.snapshots; }
  void log(const ConservedRecord& r) {
    if (enabled_) log_->append(r);
  }

  void snapshot(const ParticleStore<D>& ps, double t, std::int64_t step) {
    if (!enabled_ || !scene_.output.snapshots) return;
    char name[512];
    std::snprintf(name, sizeof name, "%s.%04d.h5", scene_.output.name.c_str(), count_++);
    write_file(ps, t, step, name);
    xdmf_->add_snapshot(name, t, ps.n, snapshot_fields<D>(ps));
    xdmf_->write();
  }

  // A snapshot of the state that stopped the run, beside the regular ones.
  void diagnostic(const ParticleStore<D>& ps, double t, std::int64_t step) {
    if (enabled_) write_file(ps, t, step, scene_.output.name + ".failed.h5");
  }

 private:
  void write_file(const ParticleStore<D>& ps, double t, std::int64_t step, const std::string& name) {
    write_snapshot<D>((dir_ / name).string(), ps, SnapshotMeta{t, step, scene_.text, RUBBLE_VERSION, RUBBLE_COMMIT});
  }

  const Scene& scene_;
  bool enabled_;
  std::filesystem::path dir_;
  int count_ = 0;
  std::unique_ptr<XdmfWriter> xdmf_;
  std::unique_ptr<ConservedLog> log_;
};

// A periodic axis must be long enough that no particle's kernel (with the
// neighbour search's 15 % skin) overlaps a second image of another particle.
template <int D>
void check_periodic_room(const Scene& scene, const Box<D>& domain, const ParticleStore<D>& ps) {
  Real h_max = 0;
  for (std::size_t i = 0; i < ps.n; ++i) h_max = std::max(h_max, ps.h[i]);
  for (int k = 0; k < D; ++k) {
    if (!domain.periodic[k]) continue;
    if (Real(2.5) * h_max >= domain.length(k))
      throw InputError(scene.file, "domain.max",
                       "periodic length " + std::to_string(domain.length(k)) + " along axis " + std::to_string(k) +
                           " is too short for the largest smoothing length " + std::to_string(h_max) +
                           " (needs more than 2.5 h): enlarge the domain or refine the spacing");
  }
}

// The CPU backend behind the time loop's interface (the CUDA one is
// solver/src/cuda/cuda_stepper.hpp): the particles live in `ps`.
template <int D>
class CpuStepper {
 public:
  CpuStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain) : ps_(ps), sys_(scene, ps, domain) {
    for (int k = 0; k < D; ++k) g_[k] = Real(scene.simulation.gravity[k]);
    sys_.sort_particles();
    sys_.evaluate();
  }
  void sort_particles() { sys_.sort_particles(); }
  double dt_limit() { return double(sys_.dt_limit()); }
  void leapfrog(double dt) { leapfrog_step<D>(sys_, ps_, Real(dt)); }
  Rk2Result rk2(double dt, double tol, double dt_min) {
    return rk2_adaptive_step<D>(sys_, ps_, Real(dt), Real(tol), Real(dt_min));
  }
  void damp(double f) {
    const Real fr = Real(f);
#pragma omp parallel for if (ps_.n > 4096)
    for (std::size_t i = 0; i < ps_.n; ++i) ps_.v[i] *= fr;
  }
  // Index of the first particle with a non-finite state, or n.
  std::size_t first_non_finite() {
    const StoreView<D> s = ps_.view();
    for (std::size_t i = 0; i < ps_.n; ++i)
      if (!finite_particle<D>(s, i)) return i;
    return ps_.n;
  }
  ConservedRecord conserved(double t, std::int64_t step, double dt) {
    return measure_conserved<D>(ps_, t, step, dt, g_);
  }
  const ParticleStore<D>& host() { return ps_; }  // the state, on the host
  std::size_t size() const { return ps_.n; }
  std::int64_t bytes_downloaded() const { return 0; }  // the state never leaves the host
  std::int64_t correction_fallbacks() const { return sys_.correction_fallbacks(); }
  std::int64_t evaluations() const { return sys_.evaluations(); }
  bool solid() const { return sys_.solid(); }
  static constexpr const char* name = "cpu";

 private:
  ParticleStore<D>& ps_;
  HydroCpu<D> sys_;
  Vec<D> g_ = Vec<D>::zero();  // simulation.gravity (its potential energy)
};

template <int D, class Stepper>
FinalState run_loop(const Scene& scene, const RunOptions& opt, Stepper& sys,
                    std::chrono::steady_clock::time_point wall_start) {
  const SimulationConfig& sim = scene.simulation;
  OutputWriter<D> out(scene, opt);
  Progress progress(sim.end_time, opt.progress && !opt.quiet);
  const double t_end = sim.end_time;
  const double dt_min = sim.dt_min > 0 ? sim.dt_min : 1e-12 * t_end;
  const double out_interval = scene.output.interval > 0 ? scene.output.interval : t_end;
  double t = 0, next_output = std::min(out_interval, t_end);
  double dt_proposal = sim.dt_initial > 0 ? sim.dt_initial : sys.dt_limit();
  std::int64_t step = 0;
  if (out.writes_snapshots()) out.snapshot(sys.host(), t, step);
  if (out.enabled()) out.log(sys.conserved(t, step, 0));

  constexpr int kSortEvery = 16;  // re-sort along the space-filling curve
  while (t < t_end * (1 - 1e-12)) {
    if (step >= sim.max_steps)
      throw RunError("reached simulation.max_steps = " + std::to_string(sim.max_steps) + " at t = " + std::to_string(t));
    // Sorting permutes every field, rates included, so the state needs no
    // new evaluation; neighbour lists are rebuilt at each evaluation anyway.
    if (step > 0 && step % kSortEvery == 0) sys.sort_particles();
    const double limit = sys.dt_limit();
    double dt = std::min(limit, next_output - t);
    const bool damped = sim.damping_time > 0 && t < sim.damping_end * (1 - 1e-12);
    if (damped) dt = std::min(dt, sim.damping_end - t);  // the damped phase ends on a step
    if (sim.integrator == Integrator::Leapfrog) {
      sys.leapfrog(dt);
    } else {
      dt = std::min(dt, dt_proposal);
      const Rk2Result r = sys.rk2(dt, sim.rk2_tolerance, dt_min);
      dt = r.dt_taken;
      dt_proposal = r.dt_next;
    }
    t += dt;
    ++step;
    // Relaxation (simulation.damping_time, damping_end): v *= exp(-dt/tau).
    if (damped) sys.damp(std::exp(-dt / sim.damping_time));

    // checked where the state lives (a device reduction on the CUDA backend):
    // the host copy is fetched only for a snapshot, a diagnostic or the end
    const std::size_t bad = sys.first_non_finite();
    if (bad < sys.size()) {
      out.diagnostic(sys.host(), t, step);
      throw RunError("non-finite value in particle " + std::to_string(bad) + " at t = " + std::to_string(t) +
                     " (step " + std::to_string(step) + "); diagnostic snapshot written");
    }
    if (dt < dt_min && t < t_end * (1 - 1e-12) && next_output - t > dt_min) {
      out.diagnostic(sys.host(), t, step);
      throw RunError("time step collapsed to " + std::to_string(dt) + " < dt_min at t = " + std::to_string(t) +
                     "; diagnostic snapshot written");
    }
    if (out.enabled()) out.log(sys.conserved(t, step, dt));
    progress.update(t, dt, step);
    if (t >= next_output * (1 - 1e-12)) {
      if (out.writes_snapshots()) out.snapshot(sys.host(), t, step);
      next_output = std::min(next_output + out_interval, t_end);
    }
  }
  progress.finish();

  const ParticleStore<D>& ps = sys.host();
  FinalState fs;
  fs.backend = Stepper::name;
  fs.device_to_host_bytes = sys.bytes_downloaded();
  fs.dimension = D;
  fs.time = t;
  fs.steps = step;
  fs.x.reserve(ps.n * D);
  fs.v.reserve(ps.n * D);
  for (std::size_t i = 0; i < ps.n; ++i) {
    for (int k = 0; k < D; ++k) {
      fs.x.push_back(ps.x[i][k]);
      fs.v.push_back(ps.v[i][k]);
    }
  }
  fs.m.assign(ps.m.begin(), ps.m.end());
  fs.rho.assign(ps.rho.begin(), ps.rho.end());
  fs.p.assign(ps.p.begin(), ps.p.end());
  fs.u.assign(ps.u.begin(), ps.u.end());
  fs.h.assign(ps.h.begin(), ps.h.end());
  fs.cs.assign(ps.cs.begin(), ps.cs.end());
  fs.alpha.assign(ps.alpha.begin(), ps.alpha.end());
  fs.eps_p.assign(ps.eps_p.begin(), ps.eps_p.end());
  fs.material_id.assign(ps.material_id.begin(), ps.material_id.end());
  if (!ps.boundary.empty()) fs.boundary.assign(ps.boundary.begin(), ps.boundary.end());
  fs.correction_fallbacks = sys.correction_fallbacks();
  fs.particle_evaluations = sys.evaluations() * std::int64_t(ps.n);
  if (sim.kernel_correction && sys.solid() && !opt.quiet)
    std::fprintf(stderr, "kernel-gradient correction: %lld of %lld particle evaluations fell back to the identity\n",
                 static_cast<long long>(fs.correction_fallbacks), static_cast<long long>(fs.particle_evaluations));
  fs.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return fs;
}

template <int D>
FinalState run_dimension(const Scene& scene, const RunOptions& opt) {
  const auto wall_start = std::chrono::steady_clock::now();
  const SimulationConfig& sim = scene.simulation;
  const double hfact = sim.hfact > 0 ? sim.hfact : kernel_default_hfact(sim.kernel);
  if (!backend_built(opt.backend))
    throw RunError(std::string("backend '") + backend_name(opt.backend) +
                   "' is not in this build (configure with -DRUBBLE_CUDA=ON on a machine with nvcc)");

  FieldNeeds needs;
  needs.summation_density = sim.density == DensityForm::Summation;
  needs.continuity_density = sim.density == DensityForm::Continuity;
  needs.gravity = scene.gravity.mode != GravityMode::Off;
  for (const MaterialConfig& m : scene.materials) needs.solid = needs.solid || m.shear_modulus > 0;
  for (const BodyConfig& b : scene.bodies) {
    needs.boundary = needs.boundary || b.boundary != BoundaryKind::None;
    needs.free_slip = needs.free_slip || b.wall_free_slip;
  }
  needs.xsph = sim.xsph > 0;
  for (const MaterialConfig& m : scene.materials) {
    needs.porosity = needs.porosity || m.porosity.enabled;
    needs.plasticity = needs.plasticity || m.plasticity.model != PlasticityType::None;
    // every Drucker-Prager material stores eps_v: its tension-cracking
    // opening persists (and so does dilatant flow, psi > 0)
    needs.inelastic_volume = needs.inelastic_volume || m.plasticity.model == PlasticityType::DruckerPrager;
  }
  ParticleStore<D> ps;
  generate_bodies<D>(scene, hfact, needs, ps);

  const Box<D> domain = domain_from_scene<D>(scene);
  check_periodic_room<D>(scene, domain, ps);
#ifdef RUBBLE_HAVE_CUDA
  if (opt.backend == Backend::Cuda) {
    CudaStepper<D> sys(scene, ps, domain);
    return run_loop<D>(scene, opt, sys, wall_start);
  }
#endif
  CpuStepper<D> sys(scene, ps, domain);
  return run_loop<D>(scene, opt, sys, wall_start);
}

}  // namespace

const char* backend_name(Backend b) { return b == Backend::Cuda ? "cuda" : "cpu"; }

Backend parse_backend(const std::string& name, const std::string& where) {
  if (name == "cpu") return Backend::Cpu;
  if (name == "cuda") return Backend::Cuda;
  throw InputError(where, "backend", "unknown backend '" + name + "'; expected cpu or cuda");
}

bool backend_built(Backend b) {
#ifdef RUBBLE_HAVE_CUDA
  (void)b;
  return true;
#else
  return b == Backend::Cpu;
#endif
}

#ifndef RUBBLE_HAVE_CUDA
std::string gpu_description() { return "none (CPU-only build)"; }

DeviceGravityTiming cuda_barnes_hut_field(const Vec<3>*, const Real*, const Real*, std::size_t, const GravityConfig&,
                                          KernelType, Vec<3>*, Real*) {
  throw RunError("cuda_barnes_hut_field: this build has no CUDA backend (configure with -DRUBBLE_CUDA=ON)");
}
#endif

Backend default_backend() {
  const char* env = std::getenv("RUBBLE_BACKEND");
  if (!env || !*env) return Backend::Cpu;
  return parse_backend(env, "environment variable RUBBLE_BACKEND");
}

FinalState run_scene(const Scene& scene, const RunOptions& options) {
  switch (scene.simulation.dimension) {
    case 1: return run_dimension<1>(scene, options);
    case 2: return run_dimension<2>(scene, options);
    case 3: return run_dimension<3>(scene, options);
    default: throw InputError(scene.file, "simulation.dimension", "must be 1, 2 or 3");
  }
}

}  // namespace rubble
