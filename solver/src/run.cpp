// run_scene: set up particles from the scene, step them to the end time,
// write snapshots, the XDMF index and conserved.csv.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "hydro_cpu.hpp"
#include "rubble/core/error.hpp"
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

template <int D>
bool all_finite(const ParticleStore<D>& ps, std::size_t& bad) {
  for (std::size_t i = 0; i < ps.n; ++i) {
    bool ok = std::isfinite(ps.u[i]) && std::isfinite(ps.rho[i]) && std::isfinite(ps.h[i]);
    for (int k = 0; k < D; ++k) ok = ok && std::isfinite(ps.x[i][k]) && std::isfinite(ps.v[i][k]);
    if (!ok) {
      bad = i;
      return false;
    }
  }
  return true;
}

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

  void log(const ParticleStore<D>& ps, double t, std::int64_t step, double dt) {
    if (enabled_) log_->append(measure_conserved<D>(ps, t, step, dt));
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

template <int D>
FinalState run_dimension(const Scene& scene, const RunOptions& opt) {
  const auto wall_start = std::chrono::steady_clock::now();
  const SimulationConfig& sim = scene.simulation;
  const double hfact = sim.hfact > 0 ? sim.hfact : kernel_default_hfact(sim.kernel);

  FieldNeeds needs;
  needs.summation_density = sim.density == DensityForm::Summation;
  needs.continuity_density = sim.density == DensityForm::Continuity;
  needs.gravity = scene.gravity.mode != GravityMode::Off;
  for (const MaterialConfig& m : scene.materials) needs.solid = needs.solid || m.shear_modulus > 0;
  for (const BodyConfig& b : scene.bodies) needs.boundary = needs.boundary || b.boundary != BoundaryKind::None;
  needs.xsph = sim.xsph > 0;
  ParticleStore<D> ps;
  generate_bodies<D>(scene, hfact, needs, ps);

  const Box<D> domain = domain_from_scene<D>(scene);
  check_periodic_room<D>(scene, domain, ps);
  HydroCpu<D> sys(scene, ps, domain);
  sys.sort_particles();
  sys.evaluate();

  OutputWriter<D> out(scene, opt);
  Progress progress(sim.end_time, opt.progress && !opt.quiet);
  const double t_end = sim.end_time;
  const double dt_min = sim.dt_min > 0 ? sim.dt_min : 1e-12 * t_end;
  const double out_interval = scene.output.interval > 0 ? scene.output.interval : t_end;
  double t = 0, next_output = std::min(out_interval, t_end);
  double dt_proposal = sim.dt_initial > 0 ? sim.dt_initial : double(sys.dt_limit());
  std::int64_t step = 0;
  out.snapshot(ps, t, step);
  out.log(ps, t, step, 0);

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
      leapfrog_step<D>(sys, ps, Real(dt));
    } else {
      dt = std::min(dt, dt_proposal);
      const Rk2Result r = rk2_adaptive_step<D>(sys, ps, Real(dt), Real(sim.rk2_tolerance), Real(dt_min));
      dt = r.dt_taken;
      dt_proposal = r.dt_next;
    }
    t += dt;
    ++step;
    // Relaxation (simulation.damping_time, damping_end): v *= exp(-dt/tau).
    if (damped) {
      const Real f = Real(std::exp(-dt / sim.damping_time));
#pragma omp parallel for if (ps.n > 4096)
      for (std::size_t i = 0; i < ps.n; ++i) ps.v[i] *= f;
    }

    std::size_t bad = 0;
    if (!all_finite(ps, bad)) {
      out.diagnostic(ps, t, step);
      throw RunError("non-finite value in particle " + std::to_string(bad) + " at t = " + std::to_string(t) +
                     " (step " + std::to_string(step) + "); diagnostic snapshot written");
    }
    if (dt < dt_min && t < t_end * (1 - 1e-12) && next_output - t > dt_min) {
      out.diagnostic(ps, t, step);
      throw RunError("time step collapsed to " + std::to_string(dt) + " < dt_min at t = " + std::to_string(t) +
                     "; diagnostic snapshot written");
    }
    out.log(ps, t, step, dt);
    progress.update(t, dt, step);
    if (t >= next_output * (1 - 1e-12)) {
      out.snapshot(ps, t, step);
      next_output = std::min(next_output + out_interval, t_end);
    }
  }
  progress.finish();

  FinalState fs;
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
  fs.correction_fallbacks = sys.correction_fallbacks();
  fs.particle_evaluations = sys.evaluations() * std::int64_t(ps.n);
  if (sim.kernel_correction && sys.solid() && !opt.quiet)
    std::fprintf(stderr, "kernel-gradient correction: %lld of %lld particle evaluations fell back to the identity\n",
                 static_cast<long long>(fs.correction_fallbacks), static_cast<long long>(fs.particle_evaluations));
  fs.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return fs;
}

}  // namespace

FinalState run_scene(const Scene& scene, const RunOptions& options) {
  switch (scene.simulation.dimension) {
    case 1: return run_dimension<1>(scene, options);
    case 2: return run_dimension<2>(scene, options);
    case 3: return run_dimension<3>(scene, options);
    default: throw InputError(scene.file, "simulation.dimension", "must be 1, 2 or 3");
  }
}

}  // namespace rubble
