#pragma once
// The step, written once for both backends (issue #51): what one
// evaluation of the right-hand side does and in which order, what happens
// at the end of an accepted step, the two integrators (integrate/), the
// state check and the time-step limit. The backend supplies only what
// differs between a CPU and a GPU: its particle and neighbour loops, its
// reductions, where arrays live, the sort along the space-filling curve,
// the neighbour search, self-gravity, and (CPU) loops that take each pair
// once. The loop bodies are the RUBBLE_HD functions of particle_rates.hpp;
// each runs here as a RUBBLE_LAMBDA (core/hd.hpp), which the CPU backend
// calls in an OpenMP loop and the CUDA backend launches as a kernel.
//
// What a backend B<D> provides (CpuBackend in solver/src/cpu_backend.hpp,
// CudaBackend in solver/src/cuda/cuda_stepper.cu):
//   template <class T> using Array    resize(n), data(), size()
//   using Store                      a copy of the whole store (RK2 stages)
//   using Neighbours, OwnNeighbours  the `each` its neighbour loops pass
//   size(), view(), materials()      the store and the material table as
//                                    the loop bodies read them
//   for_each(what, n, f)             f(i) for i < n
//   for_each_neighbours(what, f)     f(i, Neighbours) for every particle,
//                                    the pairs of the last search
//   for_each_in_own_radius(what, R, f)  the same, offering each particle
//                                    only the b within its own R (summation
//                                    density's Newton iterations)
//   reduce(n, f, init, op)           op over f(i)
//   integrator_scratch(), save_state, restore_state, view_of
//   sort(domain)                     space-filling-curve order
//   search(R, keepable)              pairs within max(R_a, R_b)
//   search_still_holds(R)            whether the last keepable search still
//                                    lists every pair that can interact
//   self_gravity(view)               a_grav and phi (3-D)
//   hydro_pair_once(c), solid_gradients_pair_once(c, count),
//   solid_forces_pair_once(c)        a backend's own pair loops (false:
//                                    none, the gather loops here run)
//   zero(array), read_count(array)   a counter set to 0, read on the host
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rubble/core/atomic.hpp"
#include "rubble/core/box.hpp"
#include "rubble/core/error.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/drivers/state_check.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/io/conserved_sums.hpp"
#include "rubble/neighbors/search_radius.hpp"
#include "rubble/physics/rigid_body.hpp"

namespace rubble {

// Wall seconds spent in each part of the right-hand side, summed over the
// run (what `rubble run --timings` and the benchmarks print). On the CUDA
// backend the clock reads the host's launches, not the device's work.
struct RhsPhaseSeconds {
  double neighbours = 0;  // neighbour search
  double density = 0;     // summation density and h (or h from continuity density)
  double eos = 0;         // pressure and sound speed (and the plastic return in an evaluation)
  double forces = 0;      // rates: pressure, viscosity, conductivity, stress, gravity, XSPH, walls
  double end_step = 0;    // porosity, plasticity and shifting after a step
};

// Adds the wall time of its scope to `sum`.
class ScopedSeconds {
 public:
  explicit ScopedSeconds(double& sum) : sum_(sum), start_(std::chrono::steady_clock::now()) {}
  ~ScopedSeconds() { sum_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  ScopedSeconds(const ScopedSeconds&) = delete;
  ScopedSeconds& operator=(const ScopedSeconds&) = delete;

 private:
  double& sum_;
  std::chrono::steady_clock::time_point start_;
};

// The state check after a step and the next step's time-step limit read
// the same state: one reduction.
struct StateCheck {
  std::size_t first_bad;  // the first particle with a non-finite value (n: none)
  Real dt;                // the smallest per-particle time-step limit
};

struct StateCheckMin {
  RUBBLE_HD StateCheck operator()(const StateCheck& a, const StateCheck& b) const {
    return {a.first_bad < b.first_bad ? a.first_bad : b.first_bad, a.dt < b.dt ? a.dt : b.dt};
  }
};

struct CountSum {
  RUBBLE_HD unsigned long long operator()(unsigned long long a, unsigned long long b) const { return a + b; }
};
struct DoubleSum {
  RUBBLE_HD double operator()(double a, double b) const { return a + b; }
};
// The velocity of a rigid motion at r from its centre: V + w x r (w in 3-D only).
template <int D>
RUBBLE_HD inline Vec<D> rigid_velocity(Vec<D> V, const Vec<3>& w, const Vec<D>& r) {
  if constexpr (D == 3) {
    V[0] += w[1] * r[2] - w[2] * r[1];
    V[1] += w[2] * r[0] - w[0] * r[2];
    V[2] += w[0] * r[1] - w[1] * r[0];
  }
  return V;
}

struct EnergySumOp {
  RUBBLE_HD EnergySums operator()(const EnergySums& a, const EnergySums& b) const { return a + b; }
};

// The internal-energy floor's work in one pass: energy added and particles raised.
struct FloorSums {
  double energy;
  unsigned long long count;
};
struct FloorSumOp {
  RUBBLE_HD FloorSums operator()(const FloorSums& a, const FloorSums& b) const {
    return {a.energy + b.energy, a.count + b.count};
  }
};

// A particle's energy gain over a step, for the one that gained the most.
struct Gain {
  double gain;
  std::uint32_t index;
};
struct GainMax {
  RUBBLE_HD Gain operator()(const Gain& a, const Gain& b) const {
    return a.gain > b.gain || (a.gain == b.gain && a.index < b.index) ? a : b;
  }
};


// Every member function that holds a loop body is public: nvcc's extended
// lambdas may not live in private member functions.
template <int D, class Backend>
class StepSequence {
 public:
  template <class T>
  using Array = typename Backend::template Array<T>;
  using Neighbours = typename Backend::Neighbours;
  using OwnNeighbours = typename Backend::OwnNeighbours;

  StepSequence(const RunPhysics& physics, Backend& backend, const Box<D>& domain)
      : ph_(physics), on_(physics.on), be_(backend), domain_(domain) {
    for (int k = 0; k < D; ++k) g_[k] = physics.body_force[k];
    const std::size_t n = be_.size();
    search_radius_.resize(n);
    if (on_.summation_density) flags_.resize(n);
    if (on_.solid && on_.artificial_stress) art_R_.resize(n);
    fallbacks_.resize(1);
    be_.zero(fallbacks_);
    energy_tolerance_ = physics.energy_step_tolerance;
    if (on_.rigid_tools) init_tools();
  }

  // ---- what the integrators ask of a system (integrate/)
  std::size_t size() const { return be_.size(); }
  StoreView<D> view() const { return be_.view(); }
  const Box<D>& domain() const { return domain_; }
  auto& integrator_scratch() { return be_.integrator_scratch(); }
  template <class F>
  void for_each(const char* what, std::size_t n, F f) {
    be_.for_each(what, n, f);
  }
  template <class T, class F, class Op>
  T reduce(std::size_t n, F f, T init, Op op) {
    return be_.reduce(n, f, init, op);
  }
  template <class S>
  void save_state(S& copy) {
    be_.save_state(copy);
  }
  template <class S>
  void restore_state(const S& copy) {
    be_.restore_state(copy);
  }
  template <class S>
  StoreView<D> view_of(S& copy) {
    return be_.view_of(copy);
  }

  // ---- the time loop's interface
  // Sorting permutes the particles: the watchdog's per-particle energies of
  // the step's start are measured again before the next step.
  void sort_particles() {
    be_.sort(domain_);
    energy_known_ = false;
  }
  // One leapfrog step. The energy watchdog cannot retry it (that would need
  // a copy of the whole state kept every step): a step beyond its bound stops
  // the run (EnergyJumpError).
  void leapfrog(Real dt) {
    dt_known_ = false;
    const double p0 = books_.wall_power;
    begin_step();
    leapfrog_step<D>(*this, dt, on_.staggered);
    // the held particles' work with the kicks' weights: dt/2 at each end
    const double work = on_.boundary ? 0.5 * double(dt) * (p0 + powers_.back()) : 0.0;
    if (!energy_step_ok(work)) throw energy_jump(dt, 0);
  }
  // One accepted rk2_adaptive step. A step the energy watchdog refuses is
  // taken again from its start (the integrator's copy of y_n, rates
  // included) with a quarter of the step, down to dt_min; there it stops the
  // run (EnergyJumpError). The retries count as rejections.
  Rk2Result rk2(Real dt, Real tol, Real dt_min) {
    int retries = 0;
    for (;;) {
      dt_known_ = false;
      const double p0 = books_.wall_power;
      begin_step();
      Rk2Result r = rk2_adaptive_step<D>(*this, dt, tol, dt_min);
      // Heun's weights: dt/2 on k1 (the step's start) and on k2, the
      // accepted attempt's first evaluation (then k3 and the next k1)
      const double work =
          on_.boundary ? 0.5 * double(r.dt_taken) * (p0 + powers_[powers_.size() - 3]) : 0.0;
      if (energy_step_ok(work)) {
        r.rejections += retries;
        return r;
      }
      if (r.dt_taken <= dt_min) throw energy_jump(r.dt_taken, retries);
      restore_state(be_.integrator_scratch().y0);
      if (on_.rigid_tools) rigid_rk2_restore();
      books_.wall_power = p0;
      ++energy_retries_;
      ++retries;
      dt = std::max(r.dt_taken / Real(4), dt_min);
    }
  }
  // Relaxation: every free particle's velocity times f (energy leaves on
  // purpose: the watchdog measures its start again). Boundary particles keep
  // their prescribed motion (a moving wall damped once would crawl for ever).
  void damp(Real f) {
    dt_known_ = false;
    energy_known_ = false;
    const StoreView<D> s = view();
    be_.for_each("damping", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) {
      if (!(s.boundary && s.boundary[i] != kFreeParticle)) s.v[i] *= f;
    });
    if (on_.rigid_tools) {  // a driven tool is damped as a whole; a prescribed one keeps its motion
      for (Tool& t : tools_)
        if (t.spec.driven) {
          t.y.V *= f;
          t.y.omega *= f;
        }
      place_tools();
    }
  }

  // ---- bodies as wholes: relaxation in each body's own frame and the
  // launch of a [collision] after it (issue #52 item 2). A body is the
  // particles whose id lies in [lo, hi) (the body_first ranges).
  BodySums<D> body_sums(std::int32_t lo, std::int32_t hi) {
    const StoreView<D> s = view();
    return be_.reduce(
        size(),
        [=] RUBBLE_LAMBDA(std::uint32_t i) {
          BodySums<D> r;
          if (s.id[i] < lo || s.id[i] >= hi) return r;
          r.m = double(s.m[i]);
          for (int k = 0; k < D; ++k) {
            r.mx[k] = Real(double(s.m[i]) * double(s.x[i][k]));
            r.mv[k] = Real(double(s.m[i]) * double(s.v[i][k]));
          }
          return r;
        },
        BodySums<D>{}, BodySumOp<D>{});
  }
  // The body's velocities about its mean velocity `mean` times f, about
  // `keep`: v = keep + f (v - mean) (keep = mean: damped in its own frame;
  // keep = 0: also held in place).
  void damp_body(std::int32_t lo, std::int32_t hi, Real f, Vec<D> mean, Vec<D> keep) {
    dt_known_ = false;
    energy_known_ = false;
    const StoreView<D> s = view();
    be_.for_each("damping", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) {
      if (s.id[i] >= lo && s.id[i] < hi) s.v[i] = keep + f * (s.v[i] - mean);
    });
  }
  // Adds a rigid motion to the body: v += V + w x (x - centre) (w in 3-D only).
  void add_body_velocity(std::int32_t lo, std::int32_t hi, Vec<D> V, Vec<3> w, Vec<D> centre) {
    dt_known_ = false;
    energy_known_ = false;
    const StoreView<D> s = view();
    be_.for_each("launch", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) {
      if (s.id[i] >= lo && s.id[i] < hi) s.v[i] = s.v[i] + rigid_velocity<D>(V, w, s.x[i] - centre);
    });
  }

  // ---- rigid tools (issue #54 item 1; physics/rigid_body.hpp). Tool k is
  // the particles with tool == k; each integrator stage sets its state and
  // places them (the hooks below, called by integrate/).
  struct Tool {
    RigidToolSpec spec;
    Vec<3> n;                   // its axis (z in 2-D)
    double M = 0, I = 0;        // mass and moment of inertia about the axis through c
    RigidState<D> y;            // now
    RigidRates<D> k;            // the rates of the last evaluation (0 unless driven)
    RigidState<D> y0, y2, half; // the step's start, RK2's second stage, leapfrog's half step
    RigidRates<D> k0, k2;
    ForceSums<D> reaction;      // the last evaluation's force and torque (about c) on it
    Vec<D> c0;                  // c at t = 0 (a region that follows the tool is given there)
  };
  const std::vector<Tool>& tools() const { return tools_; }
  // Every tool's state as a list (kRigidStateValues per tool: what a
  // restart snapshot keeps), and a resumed run's from its snapshot.
  std::vector<double> tool_state() const {
    std::vector<double> out;
    for (const Tool& t : tools_) {
      for (int a = 0; a < D; ++a) out.push_back(double(t.y.c[a]));
      out.push_back(double(t.y.theta));
      for (int a = 0; a < D; ++a) out.push_back(double(t.y.V[a]));
      out.push_back(double(t.y.omega));
      for (int a = 0; a < D; ++a) out.push_back(double(t.c0[a]));
    }
    return out;
  }
  void set_tool_state(const std::vector<double>& list) {
    const std::size_t need = tools_.size() * std::size_t(kRigidStateValues<D>);
    if (list.size() != need)
      throw RunError("the restart snapshot holds " + std::to_string(list.size()) + " rigid-tool values, the scene's " +
                     std::to_string(tools_.size()) + " tools need " + std::to_string(need));
    std::size_t j = 0;
    for (Tool& t : tools_) {
      for (int a = 0; a < D; ++a) t.y.c[a] = Real(list[j++]);
      t.y.theta = Real(list[j++]);
      for (int a = 0; a < D; ++a) t.y.V[a] = Real(list[j++]);
      t.y.omega = Real(list[j++]);
      for (int a = 0; a < D; ++a) t.c0[a] = Real(list[j++]);
    }
    if (tools_.empty()) return;
    place_tools();
    tool_rates();  // from the snapshot's wall_force: the rates of its last evaluation
  }

  // The mass, centre and moment of inertia of each tool from its particles.
  void init_tools() {
    const StoreView<D> s = view();
    for (std::size_t t = 0; t < ph_.tools.size(); ++t) {
      Tool tool;
      tool.spec = ph_.tools[t];
      for (int a = 0; a < 3; ++a) tool.n[a] = Real(tool.spec.axis[a]);
      const std::int32_t k = std::int32_t(t);
      const Vec<3> n = tool.n;
      // sums of m, m x, m |r0 perpendicular to the axis|^2
      const BodySums<D> b = be_.reduce(
          size(),
          [=] RUBBLE_LAMBDA(std::uint32_t i) {
            BodySums<D> r;
            if (s.tool[i] != k) return r;
            r.m = double(s.m[i]);
            r.mx = s.m[i] * s.x[i];
            r.mv[0] = s.m[i] * axial_distance2<D>(n, s.tool_offset[i]);  // (the moment of inertia, in mv's slot)
            return r;
          },
          BodySums<D>{}, BodySumOp<D>{});
      if (!(b.m > 0)) throw RunError("rigid tool " + std::to_string(t) + " (bodies[" + std::to_string(tool.spec.body) + "]) holds no particle");
      tool.M = tool.spec.mass > 0 ? tool.spec.mass : b.m;
      tool.I = tool.spec.inertia > 0 ? tool.spec.inertia : double(b.mv[0]);
      if (tool.spec.driven && tool.spec.free_rotation && D > 1 && !(tool.I > 0))
        throw RunError("rigid tool " + std::to_string(t) + " (bodies[" + std::to_string(tool.spec.body) +
                       "]) has no moment of inertia about its axis; give tool_inertia or driven_rotation = false");
      // the reference point: a driven tool's centre of mass (its offsets are
      // taken from it, initial_conditions), a prescribed tool's rotation_center
      for (int a = 0; a < D; ++a) {
        tool.y.c[a] = tool.spec.driven ? Real(double(b.mx[a]) / b.m) : Real(tool.spec.centre[a]);
        tool.y.V[a] = Real(tool.spec.velocity[a]);
      }
      tool.y.omega = Real(tool.spec.angular_velocity);
      tool.c0 = tool.y.c;  // (a resumed run takes it from its snapshot)
      tools_.push_back(tool);
    }
  }

  // Every tool's pose (by value, for the placement loop).
  RigidPoses<D> poses() const {
    RigidPoses<D> p;
    p.count = int(tools_.size());
    for (std::size_t t = 0; t < tools_.size(); ++t) {
      const Tool& tool = tools_[t];
      p.pose[t] = {tool.y.c, rotation_about<D>(tool.n, tool.y.theta), tool.y.V, tool.n, tool.y.omega};
    }
    return p;
  }
  // Each tool particle at its tool's pose: x = c + R r0, v = V + omega n x R r0.
  void place_tools() {
    if (tools_.empty()) return;
    const RigidPoses<D> P = poses();
    const StoreView<D> s = view();
    const Box<D> dom = domain_;
    be_.for_each("place tools", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) {
      const int k = s.tool[i];
      if (k < 0) return;
      place_rigid_particle<D>(P.pose[k], s.tool_offset[i], s.x[i], s.v[i]);
      s.x[i] = dom.wrap(s.x[i]);
    });
  }
  // After an evaluation's hold pass: each tool's reaction (from wall_force),
  // and a driven tool's rates from it.
  void tool_rates() {
    const StoreView<D> s = view();
    const Box<D> dom = domain_;
    for (std::size_t t = 0; t < tools_.size(); ++t) {
      Tool& tool = tools_[t];
      const std::int32_t k = std::int32_t(t);
      const Vec<D> c = tool.y.c;
      tool.reaction = be_.reduce(
          size(),
          [=] RUBBLE_LAMBDA(std::uint32_t i) {
            return s.tool[i] == k ? force_sums_term<D>(dom.separation(s.x[i], c), s.wall_force[i]) : ForceSums<D>{};
          },
          ForceSums<D>{}, ForceSumOp<D>{});
      if (!tool.spec.driven) continue;
      Vec<D> F, Fa;
      bool free_axis[3];
      for (int a = 0; a < D; ++a) {
        F[a] = Real(tool.reaction.F[a]);
        Fa[a] = Real(tool.spec.applied_force[a]);
        free_axis[a] = tool.spec.free_axis[a];
      }
      double T = 0;  // about the axis
      for (int a = 0; a < 3; ++a) T += tool.reaction.T[a] * double(tool.n[a]);
      tool.k = driven_rates<D>(F, Real(T), Fa, Real(tool.spec.applied_torque), g_, Real(tool.M), Real(tool.I), free_axis,
                               tool.spec.free_rotation && D > 1);
    }
  }
  // leapfrog (integrate/leapfrog.hpp): kick to the half step and drift;
  // the evaluation sees the predicted end-of-step motion (v_{1/2} with the
  // staggered update), as the particles do
  void rigid_drift(Real dt, bool staggered) {
    const Real h = Real(0.5) * dt;
    for (Tool& t : tools_) {
      t.half.V = t.y.V + h * t.k.A;
      t.half.omega = t.y.omega + h * t.k.alpha;
      t.y.c += dt * t.half.V;
      t.y.theta += dt * t.half.omega;
      t.y.V = staggered ? t.half.V : t.half.V + h * t.k.A;
      t.y.omega = staggered ? t.half.omega : t.half.omega + h * t.k.alpha;
    }
    place_tools();
  }
  void rigid_kick(Real dt) {
    const Real h = Real(0.5) * dt;
    for (Tool& t : tools_) {
      t.y.V = t.half.V + h * t.k.A;
      t.y.omega = t.half.omega + h * t.k.alpha;
    }
    place_tools();
  }
  // rk2_adaptive (integrate/rk2_adaptive.hpp)
  void rigid_rk2_begin() {
    for (Tool& t : tools_) {
      t.y0 = t.y;
      t.k0 = t.k;
    }
  }
  void rigid_rk2_stage(Real w, bool with_k2) {
    for (Tool& t : tools_)
      t.y = rigid_combine<D>(t.y0, t.y0, t.k0, with_k2 ? &t.y2 : nullptr, with_k2 ? &t.k2 : nullptr, w);
    place_tools();
  }
  void rigid_rk2_keep_k2() {
    for (Tool& t : tools_) {
      t.y2 = t.y;
      t.k2 = t.k;
    }
  }
  void rigid_rk2_restore() {
    for (Tool& t : tools_) {
      t.y = t.y0;
      t.k = t.k0;
    }
  }

  // The free particles' mass by material inside region r ([[regions]]);
  // with tool >= 0 the region follows that tool: it is given at the tool's
  // pose at t = 0, and a particle at x is tested at c0 + R^T (x - c).
  RegionSums region_sums(const Region& r, int tool) {
    const bool follow = tool >= 0 && std::size_t(tool) < tools_.size();
    RigidPose<D> pose{};
    Vec<D> c0 = Vec<D>::zero();
    if (follow) {
      pose = poses().pose[tool];
      c0 = tools_[std::size_t(tool)].c0;
    }
    const StoreView<D> s = view();
    const Region reg = r;
    return be_.reduce(
        size(),
        [=] RUBBLE_LAMBDA(std::uint32_t i) {
          RegionSums out;
          if (s.boundary && s.boundary[i] != kFreeParticle) return out;
          const Vec<D> x = follow ? c0 + transpose(pose.R) * (s.x[i] - pose.c) : s.x[i];
          double p[3] = {0, 0, 0};
          for (int k = 0; k < D; ++k) p[k] = double(x[k]);
          if (!reg.contains<D>(p)) return out;
          const int m = s.material_id[i];
          if (m >= 0 && m < kMaxRegionMaterials) out.mass[m] = double(s.m[i]);
          out.count = 1;
          return out;
        },
        RegionSums{}, RegionSumOp{});
  }

  // The force and torque (about `point`) of the rest on the held particles
  // with id in [lo, hi), from the last evaluation (boundary_forces.csv).
  ForceSums<D> held_force(std::int32_t lo, std::int32_t hi, Vec<D> point) {
    const StoreView<D> s = view();
    const Box<D> dom = domain_;
    return be_.reduce(
        size(),
        [=] RUBBLE_LAMBDA(std::uint32_t i) {
          if (s.id[i] < lo || s.id[i] >= hi || s.boundary[i] == kFreeParticle) return ForceSums<D>{};
          return force_sums_term<D>(dom.separation(s.x[i], point), s.wall_force[i]);
        },
        ForceSums<D>{}, ForceSumOp<D>{});
  }

  // ---- energy bookkeeping (issue #50 items 1 and 2)
  // The booked work of walls and of the internal-energy floor so far.
  const EnergyBooks& energy_books() const { return books_; }
  // A resumed run carries on its restart snapshot's books.
  void set_energy_books(const EnergyBooks& b) { books_ = b; }
  // Steps the watchdog refused and the integrator took again.
  std::int64_t energy_retries() const { return energy_retries_; }
  double energy_tolerance() const { return energy_tolerance_; }

  Array<double>& e_start() { return e_[e_first_]; }
  Array<double>& e_now() { return e_[1 - e_first_]; }

  // The watchdog's sums of the current state (energy_sums_particle), each
  // particle's energy into `into`.
  template <class A>
  EnergySums measure_energy(A& into) {
    const std::size_t n = size();
    into.resize(n);
    double* e = into.data();
    const StoreView<D> s = view();
    const Vec<D> g = g_;
    return be_.reduce(
        n,
        [=] RUBBLE_LAMBDA(std::uint32_t i) {
          const EnergySums r = energy_sums_particle<D>(s, i, g);
          e[i] = r.total;
          return r;
        },
        EnergySums{}, EnergySumOp{});
  }

  // Before a step: this step's evaluations' wall powers and floor work start
  // empty; the watchdog measures the step's start if it does not know it.
  void begin_step() {
    powers_.clear();
    step_floor_ = FloorSums{0, 0};
    if (energy_tolerance_ > 0 && !energy_known_) {
      energy_start_ = measure_energy(e_start());
      energy_known_ = true;
    }
  }

  // After a step: whether the watchdog accepts it; if so the step's work is
  // booked and its end becomes the next step's start. The booked total
  // E - W_walls - E_floor may change by at most
  //   energy_step_tolerance * max(scale at the start, scale at the end)
  // (energy_sums_particle; docs/user-guide.md, "The energy watchdog"). A
  // change that is not finite is left to the state check, which names the
  // field.
  bool energy_step_ok(double work) {
    if (energy_tolerance_ > 0) {
      const EnergySums now = measure_energy(e_now());
      last_change_ = now.total - energy_start_.total - work - step_floor_.energy;
      last_bound_ = energy_tolerance_ * std::max(energy_start_.scale, now.scale);
      if (std::isfinite(last_change_) && std::fabs(last_change_) > last_bound_) return false;
      energy_start_ = now;
      e_first_ = 1 - e_first_;  // the end's energies are the next start's
    }
    books_.wall_work += work;
    books_.floor_energy += step_floor_.energy;
    books_.floor_events += std::int64_t(step_floor_.count);
    return true;
  }

  // The watchdog's stop: the step's change and bound, and the three
  // particles that gained the most over it.
  EnergyJumpError energy_jump(Real dt, int retries) {
    const std::size_t n = size();
    const double* e0 = e_start().data();
    const double* e1 = e_now().data();
    std::vector<std::size_t> who;
    std::vector<double> gains;
    std::uint32_t skip[3] = {0xffffffffu, 0xffffffffu, 0xffffffffu};
    for (int k = 0; k < 3 && std::size_t(k) < n; ++k) {
      const std::uint32_t s0 = skip[0], s1 = skip[1];
      const Gain top = be_.reduce(
          n,
          [=] RUBBLE_LAMBDA(std::uint32_t i) {
            const bool taken = i == s0 || i == s1;
            return Gain{taken ? -1e300 : e1[i] - e0[i], i};
          },
          Gain{-1e300, 0xffffffffu}, GainMax{});
      if (top.index >= n) break;
      who.push_back(top.index);
      gains.push_back(top.gain);
      skip[k] = top.index;
    }
    std::string what = "the total energy changed by " + fmt_g(last_change_) + " J in one step of " + fmt_g(double(dt)) +
                       " s, beyond the energy watchdog's bound of " + fmt_g(last_bound_) +
                       " J (simulation.energy_step_tolerance = " + fmt_g(energy_tolerance_) + " of the energy scale)";
    if (retries > 0) what += " after " + std::to_string(retries) + " retries with shorter steps";
    return EnergyJumpError(what, last_change_, last_bound_, std::move(who), std::move(gains));
  }

  // The first particle with a non-finite state (size(): none) and the time-
  // step limit of the same state, in one pass; the limit is kept for
  // dt_limit() until the state changes.
  StateCheck check_state() {
    const RhsContext<D> c = context();
    const std::size_t n = size();
    const StateCheck r = be_.reduce(
        n,
        [=] RUBBLE_LAMBDA(std::uint32_t i) {
          return StateCheck{finite_particle<D>(c.s, i, u_min_particle<D>(c, i)) ? n : std::size_t(i),
                            dt_limit_particle<D>(c, i)};
        },
        StateCheck{n, Real(1e30)}, StateCheckMin{});
    dt_cached_ = r.dt;
    dt_known_ = true;
    return r;
  }
  // Largest stable time step at the last evaluated state (Courant and force limits).
  Real dt_limit() {
    if (!dt_known_) check_state();
    return dt_cached_;
  }

  // ---- the right-hand side
  // Density (and h), pressure, sound speed, and all time derivatives at the
  // current state of the store.
  void evaluate() {
    ++evaluations_;
    dt_known_ = false;
    if (on_.summation_density) summation_density_and_h();
    else h_from_continuity_density();
    {
      const ScopedSeconds timer(phases_.eos);
      equation_of_state();
      if (on_.plasticity) plastic_return(false);
    }
    const ScopedSeconds timer(phases_.forces);
    if (on_.wall_extrapolation) wall_extrapolation();
    if (on_.solid) solid_rates();  // the feature set is fixed for the run
    else hydro_rates();
    if (on_.gravity) self_gravity();
    if (on_.body_force) body_force();
    if (on_.boundary) hold_boundaries();
    if (on_.xsph) xsph_velocity();
  }

  // The same, for a leapfrog step with the staggered stress update
  // (simulation.stress_update = "staggered", leapfrog.hpp): the store holds
  // v_{1/2} and the step's starting S and rho; between the two solid passes
  // S and rho advance by dt with pass 1's rates (staggered_update_particle),
  // so the forces are those of the step's end.
  void evaluate_staggered(Real dt) {
    struct Reset {
      Real& v;
      ~Reset() { v = Real(0); }
    } reset{stagger_dt_};
    stagger_dt_ = on_.solid ? dt : Real(0);
    if (stagger_dt_ > Real(0)) {
      const std::size_t n = size();
      stagger_Lm_.resize(n);
      stagger_du_.resize(n);
      if (art_R_.size()) as_chi_.resize(n);
    }
    evaluate();
  }

  // After the integrator's last update of a step: u up to its EOS's floor
  // (the energy added booked), porous states back onto the loading envelope, the damage cap, the viscosity switch's bounds, the
  // plastic return mapping (with plastic-strain accumulation) at the step's
  // final state, particle shifting and the Coulomb walls' anchors. Nothing
  // when none is used. alpha_start: the distention at the start of the step
  // (porous runs).
  void end_step(const Real* alpha_start, Real dt) {
    if (!(on_.porosity || on_.plasticity || on_.damage || on_.viscosity_switch || on_.wall_friction || on_.shifting ||
          on_.energy_floor))
      return;
    const ScopedSeconds timer(phases_.end_step);
    const std::size_t n = size();
    const RhsContext<D> c = context();
    if (on_.energy_floor) {  // u back to its EOS's floor, the energy added booked (energy_step_ok)
      const FloorSums f = be_.reduce(
          n,
          [=] RUBBLE_LAMBDA(std::uint32_t i) {
            const double added = energy_floor_particle<D>(c, i);
            return FloorSums{added, added > 0 ? 1ull : 0ull};
          },
          FloorSums{0, 0}, FloorSumOp{});
      step_floor_.energy += f.energy;
      step_floor_.count += f.count;
    }
    if (on_.porosity)
      be_.for_each("end-of-step porosity", n, [=] RUBBLE_LAMBDA(std::uint32_t i) {
        porosity_end_step_particle<D>(c, i, alpha_start);
      });
    if (on_.damage)
      be_.for_each("end-of-step damage cap", n,
                   [=] RUBBLE_LAMBDA(std::uint32_t i) { damage_end_step_particle<D>(c, i); });
    if (on_.viscosity_switch)
      be_.for_each("end-of-step viscosity switch bounds", n,
                   [=] RUBBLE_LAMBDA(std::uint32_t i) { viscosity_switch_end_step_particle<D>(c, i); });
    if (on_.plasticity || on_.porosity || on_.damage) {
      // The pressure of the final state: the plastic return works at fixed p,
      // and the stored p, c_s of a leapfrog step then belong to the state it
      // returns (snapshots, the next step limit), not to its predicted state.
      equation_of_state();
      if (on_.plasticity) plastic_return(true);
    }
    if (on_.shifting) shift_particles(dt);
    if (on_.wall_friction)  // after the shift: a shift along a wall stretches the friction spring like any motion
      be_.for_each("end-of-step wall friction anchors", n,
                   [=] RUBBLE_LAMBDA(std::uint32_t i) { wall_anchor_end_step_particle<D>(c, i); });
  }

  // ---- counters
  std::int64_t evaluations() const { return evaluations_; }
  // Kernel-gradient correction: particle evaluations where the correction
  // matrix was ill-conditioned and the identity was used instead.
  std::int64_t correction_fallbacks() const { return be_.read_count(fallbacks_); }
  const RhsPhaseSeconds& phase_seconds() const { return phases_; }

  // Frees what only the steps need (the run is over).
  void release_work_memory() {
    search_radius_ = {};
    flags_ = {};
    solid_inv_ = {};
    stagger_Lm_ = {};
    stagger_du_ = {};
    as_chi_ = {};
    shift_ = {};
    e_[0] = {};
    e_[1] = {};
  }

  // ---- the passes of an evaluation (public for nvcc, see above)
  RhsContext<D> context() {
    RhsContext<D> c;
    c.s = be_.view();
    c.mat = be_.materials();
    c.domain = domain_;
    c.kernel = ph_.kernel;
    c.hfact = ph_.hfact;
    c.summation = on_.summation_density;
    c.kernel_correction = on_.kernel_correction;
    c.stress_diffusion = on_.stress_diffusion;
    c.art_R = art_R_.size() ? art_R_.data() : nullptr;
    c.xsph_epsilon = ph_.xsph_epsilon;
    c.courant = ph_.courant;
    c.density_step_fraction = ph_.density_step_fraction;
    c.geometric_force = ph_.geometric_force;
    c.force_factor = ph_.force_factor;
    c.h_tolerance = ph_.h_tolerance;
    c.body_force = g_;
    c.has_body_force = on_.body_force;
    c.stagger_dt = stagger_dt_;
    if (stagger_dt_ > Real(0)) {
      c.stagger_Lm = stagger_Lm_.data();
      c.stagger_du = stagger_du_.data();
      c.as_chi = as_chi_.size() ? as_chi_.data() : nullptr;
    }
    return c;
  }

  // Summation density with h and rho solved together (smoothing_length.hpp),
  // over lists searched at kSearchSkin h; a particle whose h grows past its
  // search radius searches again at kRegrowSkin times the h it reached.
  void summation_density_and_h() {
    const std::size_t n = size();
    Real* R = search_radius_.data();
    int* outgrown = flags_.data();
    const StoreView<D> s = view();
    be_.for_each("search radius", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { R[i] = Real(kSearchSkin) * s.h[i]; });
    for (int attempt = 0; attempt < 8; ++attempt) {
      {
        const ScopedSeconds timer(phases_.neighbours);
        be_.search(R, false);
      }
      const RhsContext<D> c = context();
      {
        const ScopedSeconds timer(phases_.density);
        be_.for_each_in_own_radius("summation density", R, [=] RUBBLE_LAMBDA(std::uint32_t i, const OwnNeighbours& each) {
          outgrown[i] = summation_density_particle<D>(c, i, R[i], each) ? 0 : 1;
        });
      }
      // The force loop needs all pairs within max(h_a, h_b): the lists hold
      // all pairs within max(R_a, R_b), which is at least that.
      const unsigned long long grown = be_.reduce(
          n, [=] RUBBLE_LAMBDA(std::uint32_t i) { return (unsigned long long)outgrown[i]; }, 0ull, CountSum{});
      if (grown == 0) return;
      be_.for_each("grown search radius", n, [=] RUBBLE_LAMBDA(std::uint32_t i) {
        if (outgrown[i]) R[i] = Real(kRegrowSkin) * s.h[i];
      });
    }
    throw RunError("smoothing-length iteration did not settle after 8 neighbour rebuilds");
  }

  // Continuity density: h follows rho. A backend may keep its last search
  // while it still lists every pair that can interact (its entries beyond
  // both supports add nothing, so the sums are those of a new search).
  void h_from_continuity_density() {
    const std::size_t n = size();
    const RhsContext<D> c = context();
    {
      const ScopedSeconds timer(phases_.density);
      be_.for_each("h from density", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { h_from_density_particle<D>(c, i); });
    }
    Real* R = search_radius_.data();
    if (be_.search_still_holds(R)) return;
    const StoreView<D> s = c.s;
    be_.for_each("search radius", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { R[i] = Real(kSearchSkin) * s.h[i]; });
    const ScopedSeconds timer(phases_.neighbours);
    be_.search(R, true);
  }

  void equation_of_state() {
    const RhsContext<D> c = context();
    be_.for_each("equation of state", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) { eos_particle<D>(c, i); });
  }

  // Yield: S back onto the surface (accumulate: the step's plastic strain).
  void plastic_return(bool accumulate) {
    const RhsContext<D> c = context();
    be_.for_each("plastic return", size(),
                 [=] RUBBLE_LAMBDA(std::uint32_t i) { plastic_return_particle<D>(c, i, accumulate); });
  }

  // Extrapolated walls: p, S, rho, c_s of the wall particles from the free
  // particles' state of this evaluation (after their EOS and plastic return).
  void wall_extrapolation() {
    const RhsContext<D> c = context();
    be_.for_each_neighbours("wall extrapolation", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
      wall_extrapolation_particle<D>(c, i, each);
    });
  }

  // Feature set Hydro: pressure, viscosity, conductivity (and the porous
  // and switch rates).
  void hydro_rates() {
    const RhsContext<D> c = context();
    if (be_.hydro_pair_once(c)) return;
    be_.for_each_neighbours("hydro rates", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
      hydro_rates_particle<D>(c, i, each);
    });
  }

  // Feature set Solid (any material with a shear modulus; continuity
  // density). Pass 1: the velocity gradient L_a (optionally with the
  // kernel-gradient correction), the Jaumann stress rate and the
  // artificial stress tensor R_a. Pass 2: the pair forces from the full
  // stress (solid_pair). Both passes divide by every neighbour's H (kernel)
  // and pass 2 by its rho^2 (stress term): these inverses are taken once
  // per particle first (solid_inverses; the same values as at each pair).
  // With the staggered update, S and rho advance between the passes.
  void solid_rates() {
    const std::size_t n = size();
    RhsContext<D> c = context();
    solid_inv_.resize(n);
    SolidInverses* inv = solid_inv_.data();
    const StoreView<D> s = c.s;
    be_.for_each("solid inverses", n,
                 [=] RUBBLE_LAMBDA(std::uint32_t i) { inv[i] = solid_inverses(s.h[i], s.rho[i]); });
    c.solid_inv = inv;
    unsigned long long* fallbacks = fallbacks_.data();
    if (!be_.solid_gradients_pair_once(c, fallbacks))
      be_.for_each_neighbours("solid velocity gradient", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
        if (!solid_gradient_particle<D>(c, i, each)) atomic_increment(fallbacks);  // rare
      });
    const bool staggered = c.stagger_dt > Real(0);
    if (staggered) {  // pass 2 then divides by the new densities
      const bool plastic = on_.plasticity;
      be_.for_each("staggered stress update", n, [=] RUBBLE_LAMBDA(std::uint32_t i) {
        staggered_update_particle<D>(c, i, plastic);
        inv[i] = solid_inverses(s.h[i], s.rho[i]);
      });
    }
    if (!be_.solid_forces_pair_once(c))
      be_.for_each_neighbours("solid rates", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
        solid_rates_particle<D>(c, i, each);
      });
    if (staggered)
      be_.for_each("staggered energy rate", n,
                   [=] RUBBLE_LAMBDA(std::uint32_t i) { staggered_energy_particle<D>(c, i); });
  }

  // Self-gravity (3-D only): a_grav and phi from direct summation or the
  // octree, softened with h (or a fixed length); a_grav is added to dv/dt.
  void self_gravity() {
    const StoreView<D> s = view();
    be_.self_gravity(s);
    be_.for_each("gravity into dv/dt", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) { s.dvdt[i] += s.a_grav[i]; });
  }

  // simulation.gravity
  void body_force() {
    const RhsContext<D> c = context();
    be_.for_each("body force", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) { body_force_particle<D>(c, i); });
  }

  // Held particles: their rates zeroed, the power they put into the rest
  // first (wall_power_particle), for the books.
  void hold_boundaries() {
    const RhsContext<D> c = context();
    books_.wall_power = be_.reduce(
        size(), [=] RUBBLE_LAMBDA(std::uint32_t i) { return wall_power_particle<D>(c, i); }, 0.0, DoubleSum{});
    powers_.push_back(books_.wall_power);
    be_.for_each("hold boundaries", size(), [=] RUBBLE_LAMBDA(std::uint32_t i) { hold_boundary_particle<D>(c, i); });
    if (on_.rigid_tools) tool_rates();
  }

  // XSPH: the smoothed-velocity correction to dx/dt (physics/xsph.hpp).
  void xsph_velocity() {
    const RhsContext<D> c = context();
    be_.for_each_neighbours("xsph", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
      xsph_particle<D>(c, i, each);
    });
  }

  // Particle shifting (physics/particle_shifting.hpp) with the neighbours
  // of the last evaluation: exact for leapfrog, whose last evaluation is at
  // the final positions; for rk2_adaptive the final positions differ by the
  // step's last correction, and a pair that has just entered the support is
  // missed (its kernel terms vanish at the support's edge).
  void shift_particles(Real dt) {
    const std::size_t n = size();
    const RhsContext<D> c = context();
    shift_.resize(n);
    Vec<D>* out = shift_.data();
    const Real A = ph_.shifting;
    be_.for_each_neighbours("particle shifting", [=] RUBBLE_LAMBDA(std::uint32_t i, const Neighbours& each) {
      shifting_particle<D>(c, i, A, dt, out, each);
    });
    const Box<D> dom = domain_;
    const StoreView<D> s = c.s;
    be_.for_each("apply shifts", n, [=] RUBBLE_LAMBDA(std::uint32_t i) { s.x[i] = dom.wrap(s.x[i] + out[i]); });
  }

 private:
  const RunPhysics& ph_;
  Features on_;
  Backend& be_;
  Box<D> domain_;
  Vec<D> g_ = Vec<D>::zero();  // simulation.gravity
  Array<Real> search_radius_;
  Array<int> flags_;                   // summation density: whose h outgrew its radius
  Array<Mat<D>> art_R_;                // solids with artificial stress: R_a
  Array<SolidInverses> solid_inv_;     // solids: 1/H, 1/rho^2 per particle
  Array<Mat<D>> stagger_Lm_;           // staggered: pass 1's mass-weighted gradient
  Array<Real> stagger_du_, as_chi_;    // ... the energy rate's correction, chi_a
  Array<Vec<D>> shift_;                // particle shifting: this step's shifts
  Array<unsigned long long> fallbacks_;  // kernel-gradient correction fallbacks (1 entry)
  Real stagger_dt_ = 0;                // inside evaluate_staggered: its dt (0 otherwise)
  std::int64_t evaluations_ = 0;
  RhsPhaseSeconds phases_;
  bool dt_known_ = false;  // dt_cached_ is the limit of the current state
  Real dt_cached_ = 0;
  // energy bookkeeping and the watchdog
  EnergyBooks books_;
  std::vector<double> powers_;       // the held particles' power at each evaluation of this step
  FloorSums step_floor_{0, 0};       // this step's internal-energy floor (booked when accepted)
  double energy_tolerance_ = 0;      // the watchdog's bound per step (0: off)
  bool energy_known_ = false;        // energy_start_ and e_start() are those of the current state
  EnergySums energy_start_;
  Array<double> e_[2];               // each particle's energy at the step's start (e_[e_first_]) and end
  int e_first_ = 0;
  double last_change_ = 0, last_bound_ = 0;
  std::int64_t energy_retries_ = 0;
  std::vector<Tool> tools_;          // rigid tools (none: empty)
};

}  // namespace rubble
