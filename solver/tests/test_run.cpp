// End-to-end runs through run_scene (the pipeline `rubble run` uses):
// equilibrium is kept, and the discrete conservation laws hold.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "rubble/core/error.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/run.hpp"

using namespace rubble;

namespace {

std::string uniform_gas_scene(int dim, const std::string& integrator, const std::string& density,
                              const std::string& lattice) {
  auto vec = [&](double v) {
    std::string s = "[";
    for (int k = 0; k < dim; ++k) s += (k ? ", " : "") + std::to_string(v);
    return s + "]";
  };
  std::string periodic = "[";
  for (int k = 0; k < dim; ++k) periodic += k ? ", true" : "true";
  periodic += "]";
  return "[simulation]\ndimension = " + std::to_string(dim) + "\nend_time = 0.05\nintegrator = \"" + integrator +
         "\"\ndensity = \"" + density +
         "\"\n[materials.gas]\neos = \"ideal_gas\"\ngamma = 1.4\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"gas\"\nlattice = \"" + lattice + "\"\nmin = " + vec(0) +
         "\nmax = " + vec(1) + "\nspacing = " + std::to_string(dim == 1 ? 0.02 : dim == 2 ? 0.05 : 0.125) +
         "\ndensity = 1.0\npressure = 1.0\n[domain]\nperiodic = " + periodic + "\nmin = " + vec(0) +
         "\nmax = " + vec(1) + "\n";
}

RunOptions in_memory() {
  RunOptions o;
  o.write_output = false;
  o.quiet = true;
  return o;
}

double max_speed(const FinalState& fs) {
  double vmax = 0;
  for (double v : fs.v) vmax = std::max(vmax, std::fabs(v));
  return vmax;
}

}  // namespace

// A uniform periodic gas on a lattice is an exact equilibrium of the
// discrete equations (every particle sees the same neighbourhood), so the
// particles must stay at rest to round-off.
TEST(Run, UniformGasStaysAtRest) {
  for (int dim : {1, 2, 3})
    for (const char* integrator : {"leapfrog", "rk2_adaptive"})
      for (const char* density : {"summation", "continuity"}) {
        const Scene s = parse_scene(uniform_gas_scene(dim, integrator, density, "cubic"), "uniform.toml");
        const FinalState fs = run_scene(s, in_memory());
        EXPECT_LT(max_speed(fs), 1e-12) << dim << "-D " << integrator << " " << density;
        for (double p : fs.p) ASSERT_NEAR(p, fs.p[0], 1e-10 * fs.p[0]);
      }
}

// Sod tube, coarse: momentum is conserved to round-off (the pair force is
// antisymmetric); the total energy changes only through time-integration
// error, measured ~2e-6 relative for the default scene at Courant 0.3; the
// bound 1e-4 leaves a wide margin and still catches a missing work term,
// which would change it by O(1e-2).
TEST(Run, SodConservesMomentumAndEnergy) {
  for (const char* density : {"summation", "continuity"})
    for (const char* integrator : {"leapfrog", "rk2_adaptive"}) {
      const std::string path = std::string(RUBBLE_SOURCE_DIR) + "/verification/sod_shock_tube/sod_1d.toml";
      const Scene s = load_scene_file(path, {"bodies.0.spacing=0.0125", "bodies.1.spacing=0.1",
                                             std::string("simulation.density=\"") + density + "\"",
                                             std::string("simulation.integrator=\"") + integrator + "\"",
                                             "simulation.end_time=0.1"});
      const FinalState fs = run_scene(s, in_memory());
      double p = 0, pabs = 0, e = 0;
      for (std::size_t i = 0; i < fs.m.size(); ++i) {
        p += fs.m[i] * fs.v[i];
        pabs += fs.m[i] * std::fabs(fs.v[i]);
        e += fs.m[i] * (0.5 * fs.v[i] * fs.v[i] + fs.u[i]);
      }
      // Initial energy is all internal, mass x u = M p/((gamma-1) rho) for
      // each half of length 1: 1 x 2.5 + 0.125 x 2 = 2.75.
      const double e0 = 1.0 * (1.0 / (0.4 * 1.0)) + 0.125 * (0.1 / (0.4 * 0.125));
      EXPECT_GT(pabs, 0.01) << "the gas must move";
      EXPECT_LT(std::fabs(p), 1e-12 * pabs) << density << " " << integrator;
      EXPECT_LT(std::fabs(e - e0) / e0, 1e-4) << density << " " << integrator;
    }
}

// Periodic in x, open in y: a slab of gas expands into vacuum along y.
// Momentum stays zero to round-off and the free surfaces move outwards
// symmetrically (the setup is mirror-symmetric about y = 0.25).
TEST(Run, SlabExpandsIntoVacuumThroughOpenBoundaries) {
  const std::string text = R"(
[simulation]
dimension = 2
end_time = 0.05
integrator = "leapfrog"
[materials.gas]
eos = "ideal_gas"
gamma = 1.4
[[bodies]]
shape = "box"
material = "gas"
min = [0.0, 0.0]
max = [0.5, 0.5]
spacing = 0.025
density = 1.0
pressure = 1.0
[domain]
periodic = [true, false]
min = [0.0, 0.0]
max = [0.5, 1.0]  # the open y bounds are not used
)";
  const FinalState fs = run_scene(parse_scene(text, "slab.toml"), in_memory());
  double py = 0, pabs = 0, ymin = 1e9, ymax = -1e9, vx = 0;
  for (std::size_t i = 0; i < fs.m.size(); ++i) {
    py += fs.m[i] * fs.v[2 * i + 1];
    pabs += fs.m[i] * std::fabs(fs.v[2 * i + 1]);
    vx = std::max(vx, std::fabs(fs.v[2 * i]));
    ymin = std::min(ymin, fs.x[2 * i + 1]);
    ymax = std::max(ymax, fs.x[2 * i + 1]);
  }
  EXPECT_GT(pabs, 1e-3);                   // it expands
  EXPECT_LT(std::fabs(py), 1e-12 * pabs);  // momentum conserved
  EXPECT_LT(vx, 1e-10);                    // nothing drives motion along the periodic axis
  EXPECT_LT(ymin, 0.0125);                 // both surfaces moved out of the initial lattice
  EXPECT_GT(ymax, 0.4875);
  EXPECT_NEAR(ymin + ymax, 0.5, 1e-10);    // and symmetrically
}

// simulation.dt_min bounds the step the physics allows, whatever the output
// interval (issue #13 item 4): with outputs closer together than dt_min the
// steps are cut to land on them, which is not a collapse, but a stable step
// below dt_min is, and the run stops naming it.
TEST(Run, DtMinIsEnforcedWhateverTheOutputInterval) {
  const std::string base = uniform_gas_scene(1, "leapfrog", "summation", "cubic");
  // the stable step here is ~0.3 * 0.024 / 1.18 ~ 6e-3
  const std::string fine_output = base + "[output]\ninterval = 0.001\n";
  EXPECT_NO_THROW(run_scene(parse_scene(fine_output, "t.toml", {"simulation.dt_min=1e-4"}), in_memory()));
  try {
    run_scene(parse_scene(fine_output, "t.toml", {"simulation.dt_min=0.01"}), in_memory());
    ADD_FAILURE() << "a stable step below dt_min must stop the run";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("dt_min = 0.01"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at t = "), std::string::npos) << e.what();
  }
  for (const char* integrator : {"leapfrog", "rk2_adaptive"}) {
    const std::string coarse = uniform_gas_scene(1, integrator, "summation", "cubic");
    EXPECT_THROW(run_scene(parse_scene(coarse, "t.toml", {"simulation.dt_min=0.02"}), in_memory()), RunError)
        << integrator;
  }
}

// simulation.h_tolerance: the smoothing-length iteration stops when a
// Newton step moves h by at most that fraction of h, so every particle's
// final (h, rho) pair satisfies h = hfact (m/rho)^(1/D) to about the
// tolerance (the next step is the remaining error, Newton's convergence
// being quadratic): checked at Phantom's 1e-4 and at the default 1e-10 on
// the Sod tube, whose shock and rarefaction move h every step.
TEST(Run, SmoothingLengthIterationStopsAtItsTolerance) {
  const std::string path = std::string(RUBBLE_SOURCE_DIR) + "/verification/sod_shock_tube/sod_1d.toml";
  for (const double tol : {1e-4, 0.0}) {
    const Scene s = load_scene_file(path, {"bodies.0.spacing=0.0125", "bodies.1.spacing=0.1",
                                           "simulation.integrator=\"leapfrog\"", "simulation.end_time=0.05",
                                           "simulation.h_tolerance=" + std::to_string(tol)});
    const FinalState fs = run_scene(s, in_memory());
    const double hfact = s.simulation.hfact > 0 ? s.simulation.hfact : kernel_default_hfact(s.simulation.kernel);
    const double bound = 2 * (tol > 0 ? tol : double(h_iteration_tolerance(0)));
    double worst = 0;
    for (std::size_t i = 0; i < fs.h.size(); ++i)
      worst = std::max(worst, std::fabs(fs.h[i] / (hfact * fs.m[i] / fs.rho[i]) - 1));
    EXPECT_LE(worst, bound) << "h_tolerance " << tol;
    EXPECT_GT(fs.steps, 10);
  }
}

// The CPU force loops compute each pair once within a thread's range of
// particles and from each side across ranges (CpuBackend::hydro_pair_once, both
// solid passes), so the thread count changes only the order of
// the sums: a run on 1 and on 3 threads (uneven ranges) agrees to rounding
// in every field (relative to the field's scale); a pair counted twice or
// missed changes the fields at the 1e-3 level or more.
#if defined(_OPENMP)
FinalState run_on_threads(const std::string& scene, const std::vector<std::string>& sets, int threads) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  const FinalState fs = run_scene(load_scene_file(std::string(RUBBLE_SOURCE_DIR) + scene, sets), in_memory());
  omp_set_num_threads(saved);
  return fs;
}

double worst_relative_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double scale = 0, diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    scale = std::max(scale, std::fabs(a[i]));
    diff = std::max(diff, std::fabs(a[i] - b[i]));
  }
  return diff / scale;
}

// A 3-D Sedov blast, 0.01 time units: ~1e-15 of each field's scale (the
// bound 1e-12 leaves room for its growth).
TEST(Run, ThreadCountChangesOnlyTheRounding) {
  const std::vector<std::string> sets = {"bodies.0.spacing=0.0625", "energy_deposits.0.radius=0.3",
                                         "simulation.end_time=0.01"};
  const FinalState one = run_on_threads("/verification/sedov_taylor/sedov_3d.toml", sets, 1);
  const FinalState three = run_on_threads("/verification/sedov_taylor/sedov_3d.toml", sets, 3);
  ASSERT_EQ(one.u.size(), three.u.size());
  ASSERT_EQ(one.steps, three.steps);
  EXPECT_LE(worst_relative_difference(one.x, three.x), 1e-12);
  EXPECT_LE(worst_relative_difference(one.v, three.v), 1e-12);
  EXPECT_LE(worst_relative_difference(one.u, three.u), 1e-12);
  EXPECT_LE(worst_relative_difference(one.rho, three.rho), 1e-12);
  EXPECT_GT(*std::max_element(one.v.begin(), one.v.end()), 0.1);  // the blast moves the gas
}

// The oscillating plate (kernel-gradient correction, clumping artificial
// stress, an evolving clamp) started with v_y = 0.5 m/s against its clamp,
// ~1000 steps: rounding grows to ~1e-13 of each field's scale (measured
// 2e-13 for p between the gather and the pair-once loop over 1581 steps).
// Both stress updates (leapfrog.hpp): the staggered one sums pass 1's
// mass-weighted gradient across the threads' ranges too.
TEST(Run, ThreadCountChangesOnlyTheRoundingOfASolid) {
  for (const char* update : {"predicted", "staggered"}) {
  SCOPED_TRACE(update);
  const std::vector<std::string> sets = {"simulation.end_time=0.004", "bodies.0.velocity=[0.0, 0.5]",
                                         "output.interval=0.004",
                                         std::string("simulation.stress_update=\"") + update + "\""};
  const FinalState one = run_on_threads("/validation/oscillating_plate/oscillating_plate.toml", sets, 1);
  const FinalState three = run_on_threads("/validation/oscillating_plate/oscillating_plate.toml", sets, 3);
  ASSERT_EQ(one.p.size(), three.p.size());
  ASSERT_EQ(one.steps, three.steps);
  EXPECT_GT(one.steps, 500);
  EXPECT_LE(worst_relative_difference(one.x, three.x), 1e-11);
  EXPECT_LE(worst_relative_difference(one.v, three.v), 1e-11);
  EXPECT_LE(worst_relative_difference(one.p, three.p), 1e-11);
  EXPECT_LE(worst_relative_difference(one.rho, three.rho), 1e-11);
  EXPECT_GT(*std::max_element(one.p.begin(), one.p.end()), 1e3);  // the clamp loads the plate
  }
}
#endif

// Continuity density keeps the neighbour lists across evaluations while
// every interacting pair is still listed (CpuBackend::search_still_holds).
// Entries beyond the supports add nothing and the lists keep their order,
// so the run must be the same bit for bit as one that searches at every
// evaluation: a solid (the plate, leapfrog and rk2_adaptive) that keeps
// its lists from one sort to the next, and a periodic 3-D blast in the
// continuity form whose fast particles break them sooner.
void expect_same_run_with_and_without_kept_lists(const std::string& scene, const std::vector<std::string>& sets,
                                                 double most_searches_per_evaluation) {
  const std::string path = std::string(RUBBLE_SOURCE_DIR) + scene;
  RunOptions keep = in_memory(), search = in_memory();
  // kept lists and the search counter are the CPU backend's, whatever
  // RUBBLE_BACKEND says (ci/gpu/check runs the unit tests with cuda there)
  keep.backend = search.backend = Backend::Cpu;
  search.keep_neighbour_lists = false;
  const FinalState kept = run_scene(load_scene_file(path, sets), keep);
  const FinalState fresh = run_scene(load_scene_file(path, sets), search);
  ASSERT_EQ(kept.steps, fresh.steps);
  EXPECT_EQ(kept.x, fresh.x);
  EXPECT_EQ(kept.v, fresh.v);
  EXPECT_EQ(kept.rho, fresh.rho);
  EXPECT_EQ(kept.p, fresh.p);
  EXPECT_EQ(kept.u, fresh.u);
  EXPECT_EQ(kept.h, fresh.h);
  const double evaluations = double(fresh.particle_evaluations) / double(fresh.m.size());
  EXPECT_EQ(double(fresh.neighbour_searches), evaluations);
  EXPECT_LE(double(kept.neighbour_searches), most_searches_per_evaluation * evaluations);
  EXPECT_GT(kept.neighbour_searches, 0);
}

TEST(Run, KeptNeighbourListsGiveTheSameRun) {
  const std::string plate = "/validation/oscillating_plate/oscillating_plate.toml";
  // sorted every 16 steps: at most one search in 16 plus the first
  expect_same_run_with_and_without_kept_lists(
      plate, {"simulation.end_time=0.002", "bodies.0.velocity=[0.0, 0.5]", "output.interval=0.002"}, 0.07);
  expect_same_run_with_and_without_kept_lists(plate,
                                              {"simulation.end_time=0.002", "bodies.0.velocity=[0.0, 0.5]",
                                               "output.interval=0.002", "simulation.integrator=\"rk2_adaptive\""},
                                              0.07);
  expect_same_run_with_and_without_kept_lists(
      "/verification/sedov_taylor/sedov_3d.toml",
      {"bodies.0.spacing=0.0625", "energy_deposits.0.radius=0.3", "simulation.end_time=0.01",
       "simulation.density=\"continuity\""},
      1.0);
}
