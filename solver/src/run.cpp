// run_scene: set up particles from the scene, step them to the end time,
// write snapshots, the XDMF index and conserved.csv.
#include <fcntl.h>
#include <signal.h>  // sigaction (POSIX)
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#ifdef RUBBLE_HAVE_CUDA
#include "cuda/cuda_stepper.hpp"
#endif
#include "rubble/core/error.hpp"
#include "rubble/drivers/cpu_stepper.hpp"
#include "rubble/drivers/state_check.hpp"
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

// Where the time loop starts: t = 0 for a fresh run, or the state a
// restart snapshot recorded (RestartState).
struct LoopStart {
  double t = 0;
  std::int64_t step = 0;
  double dt_proposal = 0;   // 0: from simulation.dt_initial or the step limit
  double next_output = 0;   // 0: the first output time
  int next_snapshot = 0;    // number of the next NAME.NNNN.h5
  bool resumed = false;
  std::filesystem::path from_dir;  // the restart snapshot's directory
  EnergyBooks books;               // the energy bookkeeping so far
  std::vector<double> tool_state;  // the rigid tools' states (RestartState::tool_state)
  CollisionSetup collision;        // [collision]: held = launched at damping_end
};

// Relaxation in each body's own frame (simulation.damping_frame = "body"):
// each free body's velocities about its mean velocity times f; the bodies
// of a held [collision] are also held in place (mean velocity -> 0).
template <int D, class Stepper>
void damp_each_body(Stepper& sys, const Scene& scene, const std::vector<std::int64_t>& first, double f, bool held) {
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    if (scene.bodies[b].boundary != BoundaryKind::None) continue;
    const auto lo = std::int32_t(first[b]), hi = std::int32_t(first[b + 1]);
    const BodySums<D> s = sys.body_sums(lo, hi);
    if (!(s.m > 0)) continue;
    const Vec<D> mean = s.mv * Real(1 / s.m);
    const auto& c = scene.collision.target;
    const auto& i = scene.collision.impactor;
    const bool hold = held && (std::find(c.begin(), c.end(), int(b)) != c.end() ||
                               std::find(i.begin(), i.end(), int(b)) != i.end());
    sys.damp_body(lo, hi, f, mean, hold ? Vec<D>{} : mean);
  }
}

// The launch of a held [collision] at damping_end: each body of the target
// and of the impactor gets its side's orbital velocity and spin about the
// side's centre of mass as it is now.
template <int D, class Stepper>
void launch_collision(Stepper& sys, const Scene& scene, const CollisionSetup& setup,
                      const std::vector<std::int64_t>& first) {
  auto launch = [&](const std::vector<int>& bodies, const std::array<double, 3>& v, const std::array<double, 3>& w) {
    BodySums<D> g;
    for (int b : bodies) g = BodySumOp<D>{}(g, sys.body_sums(std::int32_t(first[b]), std::int32_t(first[b + 1])));
    const Vec<D> com = g.mx * Real(1 / g.m);
    Vec<D> V;
    Vec<3> spin;
    for (int k = 0; k < D; ++k) V[k] = Real(v[k]);
    for (int k = 0; k < 3; ++k) spin[k] = Real(w[k]);
    for (int b : bodies) sys.add_body_velocity(std::int32_t(first[b]), std::int32_t(first[b + 1]), V, spin, com);
  };
  launch(scene.collision.target, setup.velocity_target, scene.collision.spin_target);
  launch(scene.collision.impactor, setup.velocity_impactor, scene.collision.spin_impactor);
}

// The loop's own state beyond the particles, as a snapshot records it.
struct LoopState {
  double dt_proposal = 0;
  double next_output = 0;
  EnergyBooks books;               // the stepper's, as of the snapshot
  std::vector<double> tool_state;  // the rigid tools', as of the snapshot
  template <class Stepper>
  void take(Stepper& sys) {
    books = sys.energy_books();
    tool_state = sys.tool_state();
  }
};

// boundary_forces.csv (docs/user-guide.md, "Forces on walls and tools"):
// for each boundary body, the force and torque that the other particles
// exert on it (StepSequence::held_force, from wall_force), the torque about
// its reference point: a rigid tool's rotation centre (a driven tool's
// centre of mass), else the centroid of its particles; and that point's
// motion (a tool's angle and angular velocity, 0 for other bodies).
std::string boundary_forces_header(int dim) {
  const char* axis[3] = {"x", "y", "z"};
  std::string h = "time,step,body";
  for (int k = 0; k < dim; ++k) h += std::string(",force_") + axis[k];
  if (dim == 2) h += ",torque_z";
  if (dim == 3) h += ",torque_x,torque_y,torque_z";
  for (int k = 0; k < dim; ++k) h += std::string(",point_") + axis[k];
  h += ",angle";
  for (int k = 0; k < dim; ++k) h += std::string(",velocity_") + axis[k];
  h += ",angular_velocity";
  return h;
}

// regions.csv (docs/user-guide.md, "Measuring regions"): for each
// [[regions]] entry, the count and mass of the free particles inside it,
// in all and by material.
std::string regions_header(const Scene& scene) {
  std::string h = "time,step,region,count,mass";
  for (const MaterialConfig& m : scene.materials) h += ",mass_" + m.name;
  return h;
}

template <int D, class Stepper>
std::vector<std::string> region_lines(const Scene& scene, Stepper& sys, double t, std::int64_t step) {
  std::vector<std::string> lines;
  for (const MeasureRegionConfig& r : scene.regions) {
    int tool = -1;  // the followed body's number among the rigid tools
    if (r.follow >= 0) {
      tool = 0;
      for (int b = 0; b < r.follow; ++b) tool += scene.bodies[std::size_t(b)].rigid_tool() ? 1 : 0;
    }
    const RegionSums sums = sys.region_sums(r.region, tool);
    double total = 0;
    for (std::size_t m = 0; m < scene.materials.size(); ++m) total += sums.mass[m];
    CsvLine line;
    line.put(t);
    line.put(step);
    line.put(r.name);
    line.put(std::int64_t(sums.count));
    line.put(total);
    for (std::size_t m = 0; m < scene.materials.size(); ++m) line.put(sums.mass[m]);
    lines.push_back(line.text);
  }
  return lines;
}

template <int D, class Stepper>
std::vector<std::string> boundary_force_lines(const Scene& scene, Stepper& sys, const std::vector<std::int64_t>& first,
                                              double t, std::int64_t step) {
  std::vector<std::string> lines;
  const std::vector<double> tools = sys.tool_state();
  std::size_t tool = 0;
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const BodyConfig& body = scene.bodies[b];
    if (body.boundary == BoundaryKind::None) continue;
    const auto lo = std::int32_t(first[b]), hi = std::int32_t(first[b + 1]);
    Vec<D> point, V;
    double angle = 0, omega = 0;
    if (body.rigid_tool()) {
      const double* y = tools.data() + tool++ * kRigidStateValues<D>;
      for (int k = 0; k < D; ++k) {
        point[k] = Real(y[k]);
        V[k] = Real(y[D + 1 + k]);
      }
      angle = y[D];
      omega = y[2 * D + 1];
    } else {
      const BodySums<D> s = sys.body_sums(lo, hi);
      point = s.mx * Real(1 / s.m);
      V = s.mv * Real(1 / s.m);
    }
    const ForceSums<D> f = sys.held_force(lo, hi, point);
    CsvLine line;
    line.put(t);
    line.put(step);
    line.put(std::int64_t(b));
    for (int k = 0; k < D; ++k) line.put(f.F[k]);
    if (D == 2) line.put(f.T[2]);
    if (D == 3)
      for (int k = 0; k < 3; ++k) line.put(f.T[k]);
    for (int k = 0; k < D; ++k) line.put(double(point[k]));
    line.put(angle);
    for (int k = 0; k < D; ++k) line.put(double(V[k]));
    line.put(omega);
    lines.push_back(line.text);
  }
  return lines;
}

// One run at a time per output directory: an exclusive flock() on
// DIR/.rubble.lock, held until the run ends (the OS releases it if the
// process dies, so no stale lock survives a crash). The file holds the pid.
class DirectoryLock {
 public:
  static constexpr const char* kName = ".rubble.lock";
  explicit DirectoryLock(const std::filesystem::path& dir) {
    path_ = (dir / kName).string();
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw OutputError("cannot create the lock file '" + path_ + "': " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char pid[32] = {0};
      const ssize_t got = ::read(fd_, pid, sizeof pid - 1);
      ::close(fd_);
      fd_ = -1;
      throw InputError(dir.string(), "",
                       "another rubble run" + (got > 0 ? " (pid " + std::string(pid, std::size_t(got)) + ")" : std::string()) +
                           " is writing into this directory; wait for it or choose another --out DIR");
    }
    const std::string me = std::to_string(::getpid());
    if (::ftruncate(fd_, 0) != 0 || ::write(fd_, me.data(), me.size()) != ssize_t(me.size())) {
      // the pid is for messages only: the lock itself is held
    }
  }
  // The file goes with the lock: a finished run leaves no trace of it.
  ~DirectoryLock() {
    if (fd_ < 0) return;
    ::unlink(path_.c_str());
    ::close(fd_);
  }
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

 private:
  std::string path_;
  int fd_ = -1;
};

// Writes snapshots NAME.NNNN.h5, the checkpoint NAME.checkpoint.h5,
// NAME.xdmf and conserved.csv into out_dir. Every file it writes carries
// the restart group, so a run can resume from any of them.
template <int D>
class OutputWriter {
 public:
  OutputWriter(const Scene& scene, const RunOptions& opt, const LoopStart& start, std::vector<std::int64_t> body_first)
      : scene_(scene), enabled_(opt.write_output), dir_(opt.out_dir), count_(start.next_snapshot),
        body_first_(std::move(body_first)) {
    if (!enabled_) return;
    std::error_code ec;
    created_ = std::filesystem::create_directories(dir_, ec);
    if (ec) throw OutputError("cannot create the output directory '" + dir_.string() + "': " + ec.message());
    try {
      open(start);
    } catch (...) {
      // a directory this run made and could not use is not left behind
      lock_.reset();
      if (created_) std::filesystem::remove_all(dir_, ec);
      throw;
    }
  }

 private:
  void open(const LoopStart& start) {
    lock_ = std::make_unique<DirectoryLock>(dir_);
    if (!start.resumed) {  // a new run starts in an empty directory (the check in main may be stale)
      for (const auto& e : std::filesystem::directory_iterator(dir_))
        if (e.path().filename() != DirectoryLock::kName)
          throw InputError(dir_.string(), "", "the output directory is not empty (" + e.path().filename().string() +
                                                  "); choose another --out DIR");
    }
    guarded([&] { xdmf_ = std::make_unique<XdmfWriter>((dir_ / (scene_.output.name + ".xdmf")).string(), D); });
    const std::string csv = (dir_ / "conserved.csv").string();
    const std::string forces = (dir_ / "boundary_forces.csv").string();
    const bool walls = std::any_of(scene_.bodies.begin(), scene_.bodies.end(),
                                   [](const BodyConfig& b) { return b.boundary != BoundaryKind::None; });
    const std::string regions = (dir_ / "regions.csv").string();
    const bool measured = !scene_.regions.empty();
    if (!start.resumed) {
      guarded([&] { log_ = std::make_unique<ConservedLog>(csv, D); });
      if (walls) guarded([&] { forces_ = std::make_unique<CsvLog>(forces, boundary_forces_header(D)); });
      if (measured) guarded([&] { regions_ = std::make_unique<CsvLog>(regions, regions_header(scene_)); });
      return;
    }
    // Resumed: into the restart snapshot's own directory, the run's
    // snapshots up to it stay in the index and conserved.csv keeps its rows
    // up to the restart step; into a new directory, conserved.csv starts
    // with the old run's rows up to the restart step (when they exist).
    std::error_code ec;
    const bool same_dir = std::filesystem::equivalent(dir_, start.from_dir, ec);
    if (same_dir) {
      for (int k = 0; k < count_; ++k) {
        const std::string name = snapshot_filename(scene_.output.name, k);
        if (!std::filesystem::exists(dir_ / name)) continue;
        const SnapshotSummary sum = read_snapshot_summary<D>((dir_ / name).string());
        xdmf_->add_snapshot(name, sum.time, sum.n, sum.fields);
      }
    }
    guarded([&] {
      log_ = std::make_unique<ConservedLog>(csv, D, (start.from_dir / "conserved.csv").string(), start.step);
    });
    if (walls)
      guarded([&] {
        forces_ = std::make_unique<CsvLog>(forces, boundary_forces_header(D),
                                           (start.from_dir / "boundary_forces.csv").string(), start.step);
      });
    if (measured)
      guarded([&] {
        regions_ = std::make_unique<CsvLog>(regions, regions_header(scene_), (start.from_dir / "regions.csv").string(),
                                            start.step);
      });
  }

 public:
  bool enabled() const { return enabled_; }
  // Whether snapshot() writes anything: the host state is fetched (on the
  // CUDA backend, downloaded) only then.
  bool writes_snapshots() const { return enabled_ && scene_.output.snapshots; }
  void log(const ConservedRecord& r) {
    if (enabled_) guarded([&] { log_->append(r); });
  }
  // Whether boundary_forces.csv is written (a run with boundary bodies).
  bool logs_forces() const { return enabled_ && forces_ != nullptr; }
  void log_forces(const std::vector<std::string>& lines) {
    if (logs_forces()) guarded([&] { for (const std::string& l : lines) forces_->append_line(l); });
  }
  // Whether regions.csv is written (a scene with [[regions]]).
  bool logs_regions() const { return enabled_ && regions_ != nullptr; }
  void log_regions(const std::vector<std::string>& lines) {
    if (logs_regions()) guarded([&] { for (const std::string& l : lines) regions_->append_line(l); });
  }

  // The next regular snapshot; `loop` is the state after it (the next
  // output time already advanced).
  void snapshot(const ParticleStore<D>& ps, double t, std::int64_t step, const LoopState& loop) {
    if (!enabled_ || !scene_.output.snapshots) return;
    const std::string name = snapshot_filename(scene_.output.name, count_++);
    write_file(ps, t, step, name, restart_state(loop, false));
    xdmf_->add_snapshot(name, t, ps.n, snapshot_fields<D>(ps));
    guarded([&] { xdmf_->write(); });
  }

  // NAME.checkpoint.h5 (replaced atomically by each new one): a restart
  // point between regular outputs. Returns its path ("" without output).
  std::string checkpoint(const ParticleStore<D>& ps, double t, std::int64_t step, const LoopState& loop) {
    if (!enabled_) return {};
    const std::string name = scene_.output.name + ".checkpoint.h5";
    write_file(ps, t, step, name, restart_state(loop, true));
    return (dir_ / name).string();
  }

  // NAME.failed.h5, beside the regular snapshots: the state of a run that
  // could not go on. Returns its path ("" without output).
  std::string diagnostic(const ParticleStore<D>& ps, double t, std::int64_t step) {
    if (!enabled_) return {};
    write_file(ps, t, step, scene_.output.name + ".failed.h5", std::nullopt);
    return (dir_ / (scene_.output.name + ".failed.h5")).string();
  }

  // Wall seconds the slowest snapshot write took so far.
  double slowest_write() const { return slowest_write_; }

 private:
  RestartState restart_state(const LoopState& loop, bool checkpoint) const {
    RestartState r;
    r.dt_proposal = loop.dt_proposal;
    r.next_output = loop.next_output;
    r.next_snapshot = count_;
    r.checkpoint = checkpoint;
    r.scene_file = scene_.file;
    r.scene_source = scene_.source_text;
    r.overrides = scene_.overrides;
    r.libraries = scene_.libraries;
    r.body_first_id = body_first_;
    r.books = loop.books;
    r.tool_state = loop.tool_state;
    return r;
  }

  void write_file(const ParticleStore<D>& ps, double t, std::int64_t step, const std::string& name,
                  const std::optional<RestartState>& restart) {
    const auto start = std::chrono::steady_clock::now();
    SnapshotMeta meta;
    meta.time = t;
    meta.step = step;
    meta.scene_text = scene_.text;
    meta.version = RUBBLE_VERSION;
    meta.commit = RUBBLE_COMMIT;
    if (restart) {
      meta.restartable = true;
      meta.restart = *restart;
    }
    guarded([&] { write_snapshot<D>((dir_ / name).string(), ps, meta); });
    slowest_write_ = std::max(slowest_write_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  // Writers report failures as std::runtime_error with the OS's reason:
  // they become OutputErrors (exit status 5).
  template <class F>
  static void guarded(F&& f) {
    try {
      f();
    } catch (const InputError&) {
      throw;
    } catch (const OutputError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw OutputError(e.what());
    }
  }

  const Scene& scene_;
  bool enabled_;
  std::filesystem::path dir_;
  bool created_ = false;                 // this run made the directory
  std::unique_ptr<DirectoryLock> lock_;  // held while the run writes
  int count_ = 0;
  std::vector<std::int64_t> body_first_;
  double slowest_write_ = 0;
  std::unique_ptr<XdmfWriter> xdmf_;
  std::unique_ptr<CsvLog> forces_;  // boundary_forces.csv (boundary bodies only)
  std::unique_ptr<CsvLog> regions_;  // regions.csv ([[regions]] only)
  std::unique_ptr<ConservedLog> log_;
};

// SIGINT / SIGTERM received (install_stop_signal_handlers), 0 if none.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void rubble_stop_handler(int sig) { g_stop_signal = sig; }

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
                       "periodic length " + fmt_g(domain.length(k)) + " along axis " + std::to_string(k) +
                           " is too short for the largest smoothing length " + fmt_g(h_max) +
                           " (needs more than 2.5 h): enlarge the domain or refine the spacing");
  }
}


// "particle 17 of bodies[1] (id 417) at x = (0.1, 0.2)": a particle as the
// user knows it, by body and original index, never by its sorted index.
template <int D>
std::string describe_particle(const ParticleStore<D>& ps, std::size_t i, const std::vector<std::int64_t>& body_first) {
  const std::int64_t id = ps.id.empty() ? std::int64_t(i) : ps.id[i];
  const std::size_t body = body_of_id(body_first, id);
  const std::int64_t first = body_first.empty() ? 0 : body_first[body];
  std::string text = "particle " + std::to_string(id - first) + " of bodies[" + std::to_string(body) + "] (id " +
                     std::to_string(id) + ") at x = (";
  for (int k = 0; k < D; ++k) text += (k ? ", " : "") + fmt_g(ps.x[i][k]);
  return text + ")";
}

// The faulty field's value(s) of particle i, e.g. "rho = -3.2".
template <int D>
std::string fault_value(const ParticleStore<D>& ps, std::size_t i, int fault) {
  auto vec = [&](const Vec<D>& v) {
    std::string t = "(";
    for (int k = 0; k < D; ++k) t += (k ? ", " : "") + fmt_g(v[k]);
    return t + ")";
  };
  switch (fault) {
    case kFaultPosition: return "x = " + vec(ps.x[i]);
    case kFaultVelocity: return "v = " + vec(ps.v[i]);
    case kFaultDensity: return "rho = " + fmt_g(ps.rho[i]);
    case kFaultSmoothingLength: return "h = " + fmt_g(ps.h[i]);
    case kFaultInternalEnergy: return "u = " + fmt_g(ps.u[i]);
    case kFaultPressure: return "p = " + fmt_g(ps.p[i]);
    case kFaultSoundSpeed: return "cs = " + fmt_g(ps.cs[i]);
    case kFaultDistention: return "alpha = " + fmt_g(ps.alpha[i]);
    case kFaultPlasticStrain: return "eps_p = " + fmt_g(ps.eps_p[i]);
    case kFaultInelasticVolume: return "eps_v = " + fmt_g(ps.eps_v[i]);
    case kFaultAcceleration: return "dvdt = " + vec(ps.dvdt[i]);
    case kFaultEnergyRate: return "dudt = " + fmt_g(ps.dudt[i]);
    case kFaultDensityRate: return "drhodt = " + fmt_g(ps.drhodt[i]);
    default: return std::string(state_fault_field(fault)) + " not finite";
  }
}

// The first particle of `ps` that fails the state check, described; empty
// if none does.
// The first particle that fails the state check: who it is (describe_particle)
// and what is wrong ("invalid rho (rho = -3; must be finite and > 0)");
// both empty when every particle passes.
struct Fault {
  std::string particle, problem;
  int fault = kStateOk;
  std::size_t index = 0;
};
// `materials`: the run's (the internal-energy floor of each EOS).
template <int D>
Fault find_fault(const ParticleStore<D>& ps, const std::vector<std::int64_t>& body_first,
                 const std::vector<MaterialParams>& materials) {
  const StoreView<D> s = const_cast<ParticleStore<D>&>(ps).view();  // read only
  RhsContext<D> c;
  c.s = s;
  c.mat = materials.data();
  for (std::size_t i = 0; i < ps.n; ++i) {
    const int fault = particle_fault<D>(s, std::uint32_t(i), u_min_particle<D>(c, std::uint32_t(i)));
    if (fault == kStateOk) continue;
    return Fault{describe_particle<D>(ps, i, body_first),
                 std::string("invalid ") + state_fault_field(fault) + " (" + fault_value<D>(ps, i, fault) +
                     "; must be " + state_fault_requirement(fault) + ")",
                 fault, i};
  }
  return {};
}

template <int D>
std::string first_fault(const ParticleStore<D>& ps, const std::vector<std::int64_t>& body_first,
                        const std::vector<MaterialParams>& materials, int* fault_out = nullptr,
                        std::size_t* index_out = nullptr) {
  const Fault f = find_fault<D>(ps, body_first, materials);
  if (fault_out) *fault_out = f.fault;
  if (index_out) *index_out = f.index;
  return f.particle.empty() ? std::string() : f.problem + " in " + f.particle;
}

// The initial state (before anything is written): a failing particle is
// bad input, named by its body's key that set the faulty value.
template <int D>
void check_initial_state(const Scene& scene, const ParticleStore<D>& ps, const std::vector<std::int64_t>& body_first) {
  int fault = kStateOk;
  std::size_t i = 0;
  const std::string what = first_fault<D>(ps, body_first, material_params_from_scene(scene), &fault, &i);
  if (what.empty()) return;
  const std::size_t body = body_of_id(body_first, ps.id[i]);
  const BodyConfig& b = scene.bodies[body];
  std::string key = "bodies[" + std::to_string(body) + "]";
  if (fault == kFaultVelocity) key += ".velocity";
  else if (fault == kFaultPosition) key += b.shape == BodyShape::Box ? ".max" : ".center";
  else if (fault == kFaultInternalEnergy) key += b.pressure >= 0 ? ".pressure" : ".internal_energy";
  else if (b.shape == BodyShape::Layered) key += ".layers";
  else if (b.shape != BodyShape::Polytrope) key += ".density";
  else key += ".mass";
  throw InputError(scene.file, key, "the initial state is unusable: " + what);
}

template <int D, class Stepper>
FinalState run_loop(const Scene& scene, const RunOptions& opt, Stepper& sys, const LoopStart& start,
                    const std::vector<std::int64_t>& body_first, std::chrono::steady_clock::time_point wall_start) {
  const SimulationConfig& sim = scene.simulation;
  // the first evaluation's p, c_s and rates, before anything is written
  if (!start.resumed && sys.first_non_finite() < sys.size()) check_initial_state<D>(scene, sys.host(), body_first);
  OutputWriter<D> out(scene, opt, start, body_first);
  Progress progress(sim.end_time, opt.progress && !opt.quiet);
  const double t_end = sim.end_time;
  const double dt_min = sim.dt_min > 0 ? sim.dt_min : 1e-12 * t_end;
  const double out_interval = scene.output.interval > 0 ? scene.output.interval : t_end;
  double t = start.t;
  std::int64_t step = start.step;
  LoopState loop;
  if (!start.resumed) {
    loop.next_output = std::min(out_interval, t_end);
    loop.dt_proposal = sim.dt_initial > 0 ? sim.dt_initial : sys.dt_limit();
    loop.take(sys);
    if (out.writes_snapshots()) out.snapshot(sys.host(), t, step, loop);
    if (out.enabled()) out.log(sys.conserved(t, step, 0));
    if (out.logs_forces()) out.log_forces(boundary_force_lines<D>(scene, sys, body_first, t, step));
    if (out.logs_regions()) out.log_regions(region_lines<D>(scene, sys, t, step));
  } else {
    sys.set_energy_books(start.books);
    sys.set_tool_state(start.tool_state);
    loop.dt_proposal = start.dt_proposal;
    // an end_time extended on resuming moves the next output past t
    loop.next_output = std::min(start.next_output, t_end);
    while (loop.next_output <= t * (1 + 1e-12) && loop.next_output < t_end)
      loop.next_output = std::min(loop.next_output + out_interval, t_end);
  }

  // Clean stops: a signal, the wall-time limit (with room for two of the
  // slowest steps and the slowest write so far), periodic checkpoints.
  const auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(); };
  double slowest_step = 0, last_wall = wall();
  double next_checkpoint = opt.checkpoint_every_seconds > 0 ? last_wall + opt.checkpoint_every_seconds : 0;
  std::string stopped, checkpoint;

  // A step that failed: the last good state (the stepper's copy from
  // before the step) goes to NAME.failed.h5, and the message leads with the
  // particle that failed (of the failing state: its body, id and position),
  // then when, what is wrong with it, and what noticed it (`cause`, e.g. the
  // neighbour search's own words, which name an internal array index).
  double good_t = t;
  std::int64_t good_step = step;
  const std::vector<MaterialParams> materials = material_params_from_scene(scene);
  // "; the last good state (...) is in FILE", after writing it
  auto last_good_note = [&] {
    const std::string file = out.diagnostic(sys.last_good(), good_t, good_step);
    return file.empty() ? std::string()
                        : "; the last good state (t = " + fmt_g(good_t) + " s, step " + std::to_string(good_step) +
                              ") is in " + file;
  };
  auto fail = [&](const std::string& cause, const std::string& when) {
    const Fault f = find_fault<D>(sys.host(), body_first, materials);
    const std::string where = last_good_note();
    if (f.particle.empty()) return RunError(cause + " " + when + where);
    return RunError(f.particle + ", " + when + ": " + f.problem + " (" + cause + ")" + where);
  };

  // where the time goes (FinalState::phase_seconds)
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  double set_up = wall(), t_sort = 0, t_limit = 0, t_checks = 0, t_step = 0, t_output = 0;
  constexpr bool kRhsPhases = requires { sys.rhs_phase_seconds(); };
  RhsPhaseSeconds rhs_before{};
  if constexpr (kRhsPhases) rhs_before = sys.rhs_phase_seconds();

  // where the time went so far (FinalState::phase_seconds; a failed run's RunError)
  const auto phases = [&] {
    std::vector<std::pair<std::string, double>> ph = {
        {"set-up", set_up}, {"sort", t_sort}, {"time-step limit", t_limit}, {"state checks", t_checks}};
    if constexpr (kRhsPhases) {
      const RhsPhaseSeconds& r = sys.rhs_phase_seconds();
      const double nb = r.neighbours - rhs_before.neighbours, de = r.density - rhs_before.density,
                   eo = r.eos - rhs_before.eos, fo = r.forces - rhs_before.forces,
                   es = r.end_step - rhs_before.end_step;
      ph.insert(ph.end(), {{"neighbour search", nb},
                           {"density and h", de},
                           {"EOS", eo},
                           {"forces", fo},
                           {"end of step", es},
                           {"integration", t_step - (nb + de + eo + fo + es)}});
    } else {
      ph.push_back({"step (right-hand side and integration)", t_step});
    }
    ph.push_back({"output", t_output});
    return ph;
  };

  constexpr int kSortEvery = 16;  // re-sort along the space-filling curve
  try {
    while (t < t_end * (1 - 1e-12)) {
      if (step >= sim.max_steps)
        throw RunError("reached simulation.max_steps = " + std::to_string(sim.max_steps) + " at t = " + fmt_g(t) + " s");
      // Sorting permutes every field, rates included, so the state needs no
      // new evaluation; neighbour lists are rebuilt at each evaluation anyway.
      auto t0 = Clock::now();
      if (step > 0 && step % kSortEvery == 0) sys.sort_particles();
      t_sort += since(t0);
      t0 = Clock::now();
      sys.keep_good();
      t_checks += since(t0);
      good_t = t;
      good_step = step;
      t0 = Clock::now();
      const double limit = sys.dt_limit();
      t_limit += since(t0);
      double dt = std::min(limit, loop.next_output - t);
      // the step the physics allows, before it is shortened to land on an
      // output or the end of damping: what simulation.dt_min bounds
      double dt_physics = limit;
      const bool damped = sim.damping_time > 0 && t < sim.damping_end * (1 - 1e-12);
      if (damped) dt = std::min(dt, sim.damping_end - t);  // the damped phase ends on a step
      const double t_before = t;
      t0 = Clock::now();
      try {
        if (sim.integrator == Integrator::Leapfrog) {
          sys.leapfrog(dt);
        } else {
          dt_physics = std::min(limit, loop.dt_proposal);
          dt = std::min(dt, loop.dt_proposal);
          const Rk2Result r = sys.rk2(dt, sim.rk2_tolerance, dt_min);
          if (r.rejections > 0) dt_physics = std::min(dt_physics, double(r.dt_taken));  // error control cut it
          dt = r.dt_taken;
          loop.dt_proposal = r.dt_next;
        }
      } catch (const EnergyJumpError& e) {
        // the energy watchdog: the particles that gained the most, as they are after the step
        std::string who;
        const ParticleStore<D>& now = sys.host();
        for (std::size_t k = 0; k < e.particles.size(); ++k)
          who += (k ? "; " : "") + describe_particle<D>(now, e.particles[k], body_first) + " gained " +
                 fmt_g(e.gains[k]) + " J";
        throw RunError("in step " + std::to_string(step + 1) + " from t = " + fmt_g(t) + " s, " + e.what() +
                       "; the particles that gained the most: " + who + last_good_note());
      } catch (const RunError& e) {
        // inside the step: the neighbour search or the smoothing-length iteration
        throw fail(e.what(), "in step " + std::to_string(step + 1) + " from t = " + fmt_g(t) + " s");
      }
      t_step += since(t0);
      t += dt;
      ++step;
      // Relaxation (simulation.damping_time, damping_end): v *= exp(-dt/tau),
      // every velocity or each body's about its own mean ("body"); a held
      // [collision] is launched when the damped phase ends
      if (damped) {
        const double f = std::exp(-dt / sim.damping_time);
        if (sim.damping_frame == DampingFrame::Body) damp_each_body<D>(sys, scene, body_first, f, start.collision.held);
        else sys.damp(f);
        if (start.collision.held && t >= sim.damping_end * (1 - 1e-12)) {
          launch_collision<D>(sys, scene, start.collision, body_first);
          if (!opt.quiet) std::fprintf(stderr, "rubble: t = %g s: relaxation over, the bodies launched\n", t);
        }
      }

      // checked where the state lives (a device reduction on the CUDA backend):
      // the host copy is fetched only for a snapshot, a diagnostic or the end
      t0 = Clock::now();
      if (sys.first_non_finite() < sys.size())
        throw fail("the state check failed", "at t = " + fmt_g(t) + " s (step " + std::to_string(step) + ")");
      t_checks += since(t0);
      if (dt_physics < dt_min && t < t_end * (1 - 1e-12)) {
        const std::string file = out.diagnostic(sys.host(), t, step);
        throw RunError("time step collapsed to " + fmt_g(dt_physics) + " s < dt_min = " + fmt_g(dt_min) +
                       " s at t = " + fmt_g(t) + " s (step " + std::to_string(step) + ")" +
                       (file.empty() ? "" : "; the state is in " + file));
      }
      progress.update(t, dt, step);
      const bool output_time = t >= loop.next_output * (1 - 1e-12);
      // conserved.csv: a row per output.conserved_interval crossed (a function
      // of t alone, so a resumed run logs the same rows), at every snapshot
      // and at the end
      const double ci = scene.output.conserved_interval;
      t0 = Clock::now();
      if (out.enabled() && (ci <= 0 || std::floor(t / ci) != std::floor(t_before / ci) || output_time ||
                            t >= t_end * (1 - 1e-12))) {
        out.log(sys.conserved(t, step, dt));
        if (out.logs_forces()) out.log_forces(boundary_force_lines<D>(scene, sys, body_first, t, step));
        if (out.logs_regions()) out.log_regions(region_lines<D>(scene, sys, t, step));
      }
      if (output_time) {
        loop.next_output = std::min(loop.next_output + out_interval, t_end);
        loop.take(sys);
        if (out.writes_snapshots()) out.snapshot(sys.host(), t, step, loop);
      }
      t_output += since(t0);

      const double now = wall();
      slowest_step = std::max(slowest_step, now - last_wall);
      last_wall = now;
      if (t >= t_end * (1 - 1e-12)) break;
      if (g_stop_signal != 0) stopped = g_stop_signal == SIGINT ? "SIGINT" : g_stop_signal == SIGTERM ? "SIGTERM" : "a signal";
      else if (opt.max_wall_seconds > 0 && now + 2 * slowest_step + out.slowest_write() >= opt.max_wall_seconds)
        stopped = "the wall-time limit";
      loop.take(sys);
      if (!stopped.empty()) {
        t0 = Clock::now();
        checkpoint = out.checkpoint(sys.host(), t, step, loop);
        t_output += since(t0);
        break;
      }
      if (next_checkpoint > 0 && now >= next_checkpoint) {
        t0 = Clock::now();
        out.checkpoint(sys.host(), t, step, loop);
        t_output += since(t0);
        next_checkpoint = wall() + opt.checkpoint_every_seconds;
      }
    }
  } catch (RunError& e) {  // a failed run: its timings go with the error (--timings)
    e.phase_seconds = phases();
    e.wall_seconds = wall();
    throw;
  }
  progress.finish();
  // The copy of the final state below comes on top of what the stepper
  // holds: let it free what the loop needed (CPU: the last good state, the
  // neighbour lists; issue #14, peak memory per particle).
  if constexpr (requires { sys.release_work_memory(); }) sys.release_work_memory();

  FinalState fs;
  fs.phase_seconds = phases();
  if constexpr (kRhsPhases) fs.neighbour_searches = sys.neighbour_searches();

  const ParticleStore<D>& ps = sys.host();
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
  fs.books = sys.energy_books();
  fs.energy_retries = sys.energy_retries();
  if (!opt.quiet && fs.books.floor_events > 0)
    std::fprintf(stderr,
                 "rubble: internal-energy floor: u was raised to its EOS's floor in %lld particle-steps, adding %g J "
                 "(booked in conserved.csv: floor_energy)\n",
                 static_cast<long long>(fs.books.floor_events), fs.books.floor_energy);
  if (!opt.quiet && fs.energy_retries > 0)
    std::fprintf(stderr, "rubble: energy watchdog: %lld steps taken again with a shorter step\n",
                 static_cast<long long>(fs.energy_retries));
  fs.stopped = stopped;
  fs.checkpoint = checkpoint;
  fs.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return fs;
}

template <int D>
FinalState run_dimension(const Scene& scene, const RunOptions& opt) {
  const auto wall_start = std::chrono::steady_clock::now();
  const SimulationConfig& sim = scene.simulation;
  const double hfact = smoothing_factor(sim);
  if (!backend_built(opt.backend))
    throw RunError(std::string("backend '") + backend_name(opt.backend) +
                   "' is not in this build (configure with -DRUBBLE_CUDA=ON on a machine with nvcc)");

  const Features needs = features_of_scene(scene);
  ParticleStore<D> ps;
  LoopStart start;
  std::vector<std::int64_t> body_first;
  if (opt.restart_from.empty()) {
    CollisionSetup collision;
    body_first = generate_bodies<D>(scene, hfact, needs, ps, &collision);
    start.collision = collision;
    check_initial_state<D>(scene, ps, body_first);  // x, v, rho, h, u as generated
    if (scene.collision.enabled && !opt.quiet) std::fprintf(stderr, "rubble: %s\n", collision_report(collision).c_str());
    for (const std::string& w : check_overlap<D>(scene, ps, body_first, domain_from_scene<D>(scene), hfact))
      std::fprintf(stderr, "rubble: warning: %s\n", w.c_str());
    if (!opt.quiet)
      for (const MaterialConfig& m : scene.materials)
        if (m.stiffness_scale < 1)
          std::fprintf(stderr,
                       "rubble: simulation.quasi_static_sound_speed: materials.%s softened, K0 and G times %.4g "
                       "(K0 = %.4g Pa, G = %.4g Pa)\n",
                       m.name.c_str(), m.stiffness_scale, double(m.murnaghan.K0), m.shear_modulus);
    if (!opt.quiet && opt.write_output) {
      const std::size_t per = bytes_per_particle<D>(scene, needs, hfact);
      std::fprintf(stderr, "rubble: %zu particles, about %s of memory (%zu bytes each)\n", ps.n,
                   format_bytes(double(per) * double(ps.n)).c_str(), per);
    }
  } else {
    SnapshotMeta meta;
    read_restart<D>(opt.restart_from, ps, meta);
    // the snapshot must hold exactly the fields this scene's run allocates
    ParticleStore<D> layout;
    layout.allocate(1, needs);
    if (layout.allocated_fields() != ps.allocated_fields()) {
      std::string have, want;
      for (const std::string& f : ps.allocated_fields()) have += (have.empty() ? "" : ", ") + f;
      for (const std::string& f : layout.allocated_fields()) want += (want.empty() ? "" : ", ") + f;
      throw InputError(opt.restart_from, "", "holds the fields {" + have + "} but its scene runs with {" + want + "}");
    }
    if (meta.time >= sim.end_time * (1 - 1e-12))
      throw InputError(opt.restart_from, "simulation.end_time",
                       "the snapshot is at t = " + fmt_g(meta.time) + " s, not before end_time = " + fmt_g(sim.end_time) +
                           " s: nothing to integrate (extend the run with --set simulation.end_time=T)");
    if (scene.collision.enabled && sim.damping_time > 0 && meta.time < sim.damping_end * (1 - 1e-12))
      throw InputError(opt.restart_from, "simulation.damping_end",
                       "the snapshot is at t = " + fmt_g(meta.time) + " s, before the [collision]'s launch at damping_end = " +
                           fmt_g(sim.damping_end) + " s; resuming during the relaxation is not supported yet: "
                           "run the scene again from the start");
    start.t = meta.time;
    start.step = meta.step;
    start.dt_proposal = meta.restart.dt_proposal;
    start.next_output = meta.restart.next_output;
    start.next_snapshot = meta.restart.next_snapshot;
    start.resumed = true;
    start.books = meta.restart.books;
    start.tool_state = meta.restart.tool_state;
    start.from_dir = std::filesystem::path(opt.restart_from).parent_path();
    if (start.from_dir.empty()) start.from_dir = ".";
    body_first = meta.restart.body_first_id;
  }

  const Box<D> domain = domain_from_scene<D>(scene);
  check_periodic_room<D>(scene, domain, ps);
  // The first evaluation runs in the stepper's constructor: a state it
  // cannot evaluate is bad input.
  auto initial = [&](auto make) {
    try {
      return make();
    } catch (const RunError& e) {
      throw InputError(scene.file, "bodies", std::string("the initial state cannot be evaluated: ") + e.what());
    }
  };
#ifdef RUBBLE_HAVE_CUDA
  if (opt.backend == Backend::Cuda) {
    auto sys = initial([&] { return std::make_unique<CudaStepper<D>>(scene, ps, domain, start.resumed); });
    return run_loop<D>(scene, opt, *sys, start, body_first, wall_start);
  }
#endif
  auto sys = initial(
      [&] { return std::make_unique<CpuStepper<D>>(scene, ps, domain, start.resumed, opt.keep_neighbour_lists); });
  return run_loop<D>(scene, opt, *sys, start, body_first, wall_start);
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

CudaBackendCounts cuda_backend_counts() { return {}; }

DeviceGravityTiming cuda_barnes_hut_field(const Vec<3>*, const Real*, const Real*, std::size_t, const GravityConfig&,
                                          KernelType, Vec<3>*, Real*) {
  throw RunError("cuda_barnes_hut_field: this build has no CUDA backend (configure with -DRUBBLE_CUDA=ON)");
}
#endif

Scene load_restart_scene(const std::string& snapshot, const std::vector<std::string>& extra_overrides) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(snapshot, ec)) throw InputError(snapshot, "", "no such snapshot file");
  SnapshotMeta meta;
  try {
    meta = read_snapshot_meta(snapshot);
  } catch (const std::runtime_error& e) {
    throw InputError(snapshot, "", std::string("cannot read it as a snapshot: ") + e.what());
  }
  if (!meta.restartable)
    throw InputError(snapshot, "",
                     "has no restart data (a diagnostic .failed.h5 snapshot, or one written before restarts existed)");
  // Only the run's extent and its output may change on resuming.
  for (const std::string& o : extra_overrides) {
    const std::string key = o.substr(0, o.find('='));
    const bool allowed = key == "simulation.end_time" || key == "simulation.max_steps" || key.rfind("output.", 0) == 0;
    if (!allowed)
      throw InputError(snapshot, key,
                       "--set " + o + ": a resumed run keeps the physics it started with; only simulation.end_time, "
                       "simulation.max_steps and output.* may be changed");
  }
  std::vector<std::string> overrides = meta.restart.overrides;
  overrides.insert(overrides.end(), extra_overrides.begin(), extra_overrides.end());
  Scene scene = parse_scene(meta.restart.scene_source, meta.restart.scene_file, overrides, &meta.restart.libraries);
  if (scene.simulation.dimension != meta.dimension)
    throw InputError(snapshot, "simulation.dimension",
                     "the snapshot holds a " + std::to_string(meta.dimension) + "-D state but its scene says " +
                         std::to_string(scene.simulation.dimension) + "-D");
  return scene;
}

void install_stop_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = rubble_stop_handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;  // a second signal takes the default action: the process ends at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

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
