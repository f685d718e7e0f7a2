// Restarts (issue #13): a run resumed from any snapshot it wrote, or from a
// checkpoint written when it was stopped, ends in exactly the state of the
// uninterrupted run: every field of the final snapshot bit for bit, on the
// CPU backend, for both integrators, for hydrodynamics, a solid with
// artificial stress, plasticity with walls and shifting, damage, the
// viscosity switch, and a self-gravitating body. conserved.csv of the resumed run is the
// uninterrupted run's, line for line. Changed files on disk cannot change a
// resumed run: the scene, its overrides and the library values travel in
// the snapshot.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>
#include <unistd.h>

#include "rubble/core/error.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"

using namespace rubble;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) {
  const auto p = fs::temp_directory_path() / ("rubble_test_restart_" + std::to_string(getpid()) + "_" + name);
  fs::remove_all(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

RunOptions into(const fs::path& dir) {
  RunOptions o;
  o.out_dir = dir.string();
  o.quiet = true;
  o.backend = Backend::Cpu;
  return o;
}

// Every field both stores hold, compared as bytes; the two must hold the
// same fields.
template <int D>
void expect_same_bits(const ParticleStore<D>& a, const ParticleStore<D>& b) {
  ASSERT_EQ(a.n, b.n);
  ASSERT_EQ(a.allocated_fields(), b.allocated_fields());
  for (const auto& f : field_table<D>())
    std::visit(
        [&](auto member) {
          const auto& x = a.*member;
          const auto& y = b.*member;
          ASSERT_EQ(x.size(), y.size()) << f.name;
          if (x.empty()) return;
          EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])), 0)
              << "field '" << f.name << "' differs after the restart";
        },
        f.member);
}

// Snapshot `file` of the runs in directories a and b, every field read
// back with its restart group: bit for bit the same. Returns their metadata.
template <int D>
std::pair<SnapshotMeta, SnapshotMeta> expect_same_snapshot(const fs::path& a, const fs::path& b,
                                                           const std::string& file) {
  ParticleStore<D> pa, pb;
  SnapshotMeta ma, mb;
  read_restart<D>((a / file).string(), pa, ma);
  read_restart<D>((b / file).string(), pb, mb);
  expect_same_bits<D>(pa, pb);
  return {ma, mb};
}

// Run `text` (output every end_time/4) to its end; resume from snapshot
// `from` (or from the checkpoint a wall-time stop wrote) in a new
// directory; the final snapshots must agree bit for bit.
template <int D>
void expect_restart_identical(const std::string& text, const std::string& name, int from) {
  const fs::path a = temp_dir(name + "_a"), b = temp_dir(name + "_b");
  const Scene scene = parse_scene(text, name + ".toml");
  const FinalState whole = run_scene(scene, into(a));
  ASSERT_TRUE(whole.stopped.empty());
  const std::string last = snapshot_filename(scene.output.name, 4);
  ASSERT_TRUE(fs::exists(a / last)) << "the scene should write 5 snapshots";

  const std::string start = (a / snapshot_filename(scene.output.name, from)).string();
  const Scene again = load_restart_scene(start);
  RunOptions opt = into(b);
  opt.restart_from = start;
  const FinalState resumed = run_scene(again, opt);
  EXPECT_EQ(resumed.steps, whole.steps);
  EXPECT_EQ(resumed.time, whole.time);

  const auto [ma, mb] = expect_same_snapshot<D>(a, b, last);
  EXPECT_EQ(ma.time, mb.time);
  EXPECT_EQ(ma.step, mb.step);
  EXPECT_EQ(ma.restart.dt_proposal, mb.restart.dt_proposal);
  // conserved.csv: the old rows up to the restart step, then the same rows
  EXPECT_EQ(slurp(a / "conserved.csv"), slurp(b / "conserved.csv"));
  // boundary_forces.csv likewise (runs with boundary bodies)
  EXPECT_EQ(fs::exists(a / "boundary_forces.csv"), fs::exists(b / "boundary_forces.csv"));
  if (fs::exists(a / "boundary_forces.csv")) {
    EXPECT_EQ(slurp(a / "boundary_forces.csv"), slurp(b / "boundary_forces.csv"));
  }
  // no snapshot before the restart point is rewritten into the new directory
  EXPECT_FALSE(fs::exists(b / snapshot_filename(scene.output.name, from)));
  EXPECT_TRUE(fs::exists(b / snapshot_filename(scene.output.name, from + 1)));
  if (!::testing::Test::HasFailure()) {
    fs::remove_all(a);
    fs::remove_all(b);
  }
}

// Stop the run by the wall-time limit right after its first steps, resume
// from the checkpoint, compare with the uninterrupted run.
template <int D>
void expect_checkpoint_identical(const std::string& text, const std::string& name) {
  const fs::path a = temp_dir(name + "_whole"), b = temp_dir(name + "_stopped");
  const Scene scene = parse_scene(text, name + ".toml");
  run_scene(scene, into(a));
  RunOptions opt = into(b);
  opt.max_wall_seconds = 1e-9;  // already past: stop after the first step
  const FinalState stopped = run_scene(scene, opt);
  EXPECT_EQ(stopped.stopped, "the wall-time limit");
  EXPECT_EQ(stopped.steps, 1);
  ASSERT_EQ(stopped.checkpoint, (b / (scene.output.name + ".checkpoint.h5")).string());
  SnapshotMeta meta = read_snapshot_meta(stopped.checkpoint);
  EXPECT_TRUE(meta.restart.checkpoint);
  EXPECT_EQ(meta.restart.next_snapshot, 1);  // only the initial snapshot was written
  for (const auto& e : fs::directory_iterator(b))
    EXPECT_EQ(e.path().extension() == ".tmp", false) << e.path() << " left behind";

  RunOptions resume = into(b);
  resume.restart_from = stopped.checkpoint;
  run_scene(load_restart_scene(stopped.checkpoint), resume);
  const std::string last = snapshot_filename(scene.output.name, 4);
  const auto [ma, mb] = expect_same_snapshot<D>(a, b, last);
  EXPECT_EQ(ma.step, mb.step);
  EXPECT_EQ(slurp(a / "conserved.csv"), slurp(b / "conserved.csv"));
  // resumed into its own directory: the index lists every snapshot once
  const std::string xdmf = slurp(b / (scene.output.name + ".xdmf"));
  for (int k = 0; k <= 4; ++k) {
    const std::string grid = "<Grid Name=\"" + snapshot_filename(scene.output.name, k) + "\"";
    const auto at = xdmf.find(grid);
    EXPECT_NE(at, std::string::npos) << grid;
    if (at != std::string::npos) {
      EXPECT_EQ(xdmf.find(grid, at + 1), std::string::npos) << grid;
    }
  }
  if (!::testing::Test::HasFailure()) {
    fs::remove_all(a);
    fs::remove_all(b);
  }
}

// 2-D gas: a high-pressure box beside a low-pressure one, periodic in y
// (summation density, viscosity, conductivity).
std::string hydro_scene(const std::string& integrator) {
  return "[simulation]\ndimension = 2\nend_time = 0.08\nintegrator = \"" + integrator +
         "\"\n[materials.gas]\neos = \"ideal_gas\"\ngamma = 1.4\nconductivity = { enabled = true, alpha_u = 1.0 }\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"gas\"\nmin = [0.0, 0.0]\nmax = [0.5, 0.4]\nspacing = 0.025\n"
         "density = 1.0\npressure = 1.0\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"gas\"\nmin = [0.5, 0.0]\nmax = [1.0, 0.4]\nspacing = 0.025\n"
         "density = 1.0\npressure = 0.1\n"
         "[domain]\nperiodic = [false, true]\nmin = [0.0, 0.0]\nmax = [1.0, 0.4]\n"
         "[output]\ninterval = 0.02\n";
}

// Two 2-D rubber blocks colliding (artificial stress, XSPH).
std::string solid_scene(const std::string& integrator) {
  return "[simulation]\ndimension = 2\nend_time = 0.4\nintegrator = \"" + integrator +
         "\"\nxsph = 0.5\n[materials.rubber]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n"
         "shear_modulus = 0.22\nartificial_stress = { epsilon = 0.3, n = 4 }\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.0, 0.0]\nmax = [0.5, 0.5]\nspacing = 0.05\n"
         "density = 1.0\ninternal_energy = 0.0\nvelocity = [0.1, 0.0]\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.55, 0.1]\nmax = [1.05, 0.6]\nspacing = 0.05\n"
         "density = 1.0\ninternal_energy = 0.0\nvelocity = [-0.1, 0.0]\n"
         "[output]\ninterval = 0.1\n";
}

// A granular column under gravity on an extrapolated floor between walls
// (Drucker-Prager, tension cracking memory, particle shifting).
std::string granular_scene() {
  return "[simulation]\ndimension = 2\nend_time = 0.02\nintegrator = \"leapfrog\"\nkernel = \"wendland_c2\"\n"
         "shifting = 0.05\ngravity = [0.0, -9.81]\n"
         "[materials.sand]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 2600.0, K0 = 7e5, n = 7.0 }\n"
         "shear_modulus = 3e5\nplasticity = { model = \"drucker_prager\", friction_angle = 20.0, cohesion = 0.0 }\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"sand\"\nmin = [0.0, 0.0]\nmax = [0.1, 0.05]\nspacing = 0.005\n"
         "density = 2600.0\ninternal_energy = 0.0\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"sand\"\nmin = [-0.015, -0.015]\nmax = [0.2, 0.0]\nspacing = 0.005\n"
         "density = 2600.0\ninternal_energy = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n"
         "[output]\ninterval = 0.005\n";
}

// A brittle block pulled apart (tensile damage with Weibull flaws): the
// resumed run must continue with the same flaws and damage.
std::string damage_scene(const std::string& integrator) {
  std::string s = "[simulation]\ndimension = 2\nend_time = 0.8\nintegrator = \"" + integrator +
                  "\"\n[materials.rock]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n"
                  "shear_modulus = 0.5\ndamage = { model = \"grady_kipp\", weibull_k = 1e20, weibull_m = 6.0, seed = 5 }\n";
  for (int half = 0; half < 2; ++half)
    s += "[[bodies]]\nshape = \"box\"\nmaterial = \"rock\"\nmin = [" + std::string(half ? "0.5" : "0.0") +
         ", 0.0]\nmax = [" + std::string(half ? "1.0" : "0.5") +
         ", 0.4]\nspacing = 0.05\ndensity = 1.0\ninternal_energy = 0.0\nvelocity = [" + std::string(half ? "0.1" : "-0.1") +
         ", 0.0]\n";
  return s + "[output]\ninterval = 0.2\n";
}

// Water stirred by a turning paddle lowered into it while a driven block (free to move and
// turn) falls into it: the tools' states must travel in the snapshot.
std::string tool_scene(const std::string& integrator) {
  return "[simulation]\ndimension = 2\nend_time = 0.08\nintegrator = \"" + integrator +
         "\"\ngravity = [0.0, -9.81]\n"
         "[materials.water]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1000.0, K0 = 2.0e5, n = 7.0 }\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [0.6, 0.3]\nspacing = 0.03\n"
         "density = 1000.0\npressure = 0.0\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [-0.09, -0.09]\nmax = [0.69, 0.0]\nspacing = 0.03\n"
         "density = 1000.0\npressure = 0.0\nboundary = \"fixed\"\nboundary_state = \"extrapolated\"\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.1, 0.33]\nmax = [0.25, 0.39]\nspacing = 0.03\n"
         "density = 1000.0\npressure = 0.0\nboundary = \"moving\"\nvelocity = [0.0, -1.0]\nangular_velocity = 6.0\n"
         "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.4, 0.3]\nmax = [0.55, 0.39]\nspacing = 0.03\n"
         "density = 1000.0\npressure = 0.0\nboundary = \"driven\"\nvelocity = [0.0, -1.0]\nangular_velocity = 1.0\n"
         "[output]\ninterval = 0.02\n";
}

// A self-gravitating polytrope (Barnes-Hut).
std::string gravity_scene(const std::string& integrator) {
  return "[simulation]\ndimension = 3\nend_time = 0.2\nintegrator = \"" + integrator +
         "\"\n[gravity]\nmode = \"barnes_hut\"\nG = 1.0\n"
         "[materials.gas]\neos = \"ideal_gas\"\ngamma = 2.0\n"
         "[[bodies]]\nshape = \"polytrope\"\nmaterial = \"gas\"\nradius = 1.0\nmass = 1.0\npolytropic_index = 1\n"
         "particles = 400\n[output]\ninterval = 0.05\n";
}

}  // namespace

TEST(Restart, HydroLeapfrogIsBitIdentical) { expect_restart_identical<2>(hydro_scene("leapfrog"), "hydro_lf", 2); }
TEST(Restart, HydroRk2IsBitIdentical) { expect_restart_identical<2>(hydro_scene("rk2_adaptive"), "hydro_rk2", 1); }
TEST(Restart, SolidLeapfrogIsBitIdentical) { expect_restart_identical<2>(solid_scene("leapfrog"), "solid_lf", 2); }
TEST(Restart, SolidRk2IsBitIdentical) { expect_restart_identical<2>(solid_scene("rk2_adaptive"), "solid_rk2", 3); }
// The kernel-gradient correction's per-particle K (a derived field, not in
// snapshots) is rebuilt by the restart's first evaluation before the first
// time-step limit reads it, so a corrected run resumes bit for bit too.
TEST(Restart, KernelCorrectionIsBitIdentical) {
  std::string text = solid_scene("leapfrog");
  text.insert(text.find("xsph = 0.5\n"), "kernel_correction = true\n");
  expect_restart_identical<2>(text, "solid_corr", 2);
}
TEST(Restart, GranularWallsAndShiftingAreBitIdentical) { expect_restart_identical<2>(granular_scene(), "granular", 2); }
// A Coulomb floor: the resumed run continues with the friction anchors
TEST(Restart, CoulombWallIsBitIdentical) {
  std::string text = granular_scene();
  const std::string wall = "boundary_state = \"extrapolated\"\n";
  text.replace(text.find(wall), wall.size(),
               wall + "wall_slip = \"coulomb\"\nwall_normal = [0.0, 1.0]\nwall_friction = 0.36\n");
  expect_restart_identical<2>(text, "coulomb", 2);
}
TEST(Restart, DamageLeapfrogIsBitIdentical) { expect_restart_identical<2>(damage_scene("leapfrog"), "damage_lf", 2); }
TEST(Restart, DamageRk2IsBitIdentical) { expect_restart_identical<2>(damage_scene("rk2_adaptive"), "damage_rk2", 2); }
// The viscosity switch: each particle's alpha travels in the snapshots.
TEST(Restart, ViscositySwitchIsBitIdentical) {
  for (const char* integrator : {"leapfrog", "rk2_adaptive"}) {
    std::string text = hydro_scene(integrator);
    text.insert(text.find("conductivity ="), "viscosity = { switch = \"morris_monaghan\" }\n");
    expect_restart_identical<2>(text, std::string("avsw_") + integrator, 2);
  }
}
TEST(Restart, RigidToolsLeapfrogAreBitIdentical) { expect_restart_identical<2>(tool_scene("leapfrog"), "tools_lf", 2); }
TEST(Restart, RigidToolsRk2AreBitIdentical) { expect_restart_identical<2>(tool_scene("rk2_adaptive"), "tools_rk2", 1); }
TEST(Restart, SelfGravityLeapfrogIsBitIdentical) { expect_restart_identical<3>(gravity_scene("leapfrog"), "grav_lf", 2); }
TEST(Restart, SelfGravityRk2IsBitIdentical) { expect_restart_identical<3>(gravity_scene("rk2_adaptive"), "grav_rk2", 1); }

TEST(Restart, FromACheckpointLeapfrog) { expect_checkpoint_identical<2>(solid_scene("leapfrog"), "ckpt_lf"); }
TEST(Restart, FromACheckpointRk2) { expect_checkpoint_identical<2>(hydro_scene("rk2_adaptive"), "ckpt_rk2"); }

// --checkpoint-every: the checkpoint is rewritten as the run goes (here
// after every step), and a run resumed from it ends where the whole run did.
TEST(Restart, PeriodicCheckpointsResumeIdentically) {
  const fs::path a = temp_dir("periodic"), b = temp_dir("periodic_resumed");
  const Scene scene = parse_scene(solid_scene("leapfrog"), "solid.toml");
  RunOptions opt = into(a);
  opt.checkpoint_every_seconds = 1e-9;
  const FinalState whole = run_scene(scene, opt);
  EXPECT_TRUE(whole.stopped.empty());
  const std::string checkpoint = (a / (scene.output.name + ".checkpoint.h5")).string();
  const SnapshotMeta meta = read_snapshot_meta(checkpoint);
  EXPECT_TRUE(meta.restartable);
  EXPECT_TRUE(meta.restart.checkpoint);
  EXPECT_EQ(meta.step, whole.steps - 1) << "the last checkpoint is the step before the end";
  RunOptions resume = into(b);
  resume.restart_from = checkpoint;
  run_scene(load_restart_scene(checkpoint), resume);
  expect_same_snapshot<2>(a, b, snapshot_filename(scene.output.name, 4));
  if (!::testing::Test::HasFailure()) {
    fs::remove_all(a);
    fs::remove_all(b);
  }
}

// The library file as the run read it travels in the snapshot: editing it
// afterwards changes nothing of the resumed run.
TEST(Restart, LibraryValuesTravelInTheSnapshot) {
  const fs::path dir = temp_dir("library"), lib = temp_dir("library_files");
  fs::create_directories(lib);
  std::ofstream(lib / "rubber.toml") << "source = \"test\"\nunits = \"dimensionless\"\neos = \"murnaghan\"\n"
                                        "murnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\nshear_modulus = 0.22\n";
  std::string text = solid_scene("leapfrog");
  const auto at = text.find("eos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\nshear_modulus = 0.22\n");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("eos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\nshear_modulus = 0.22\n").size(),
               "library = \"" + (lib / "rubber.toml").string() + "\"\n");
  const Scene scene = parse_scene(text, (lib / "scene.toml").string(), {"simulation.xsph=0.25"});
  ASSERT_EQ(scene.libraries.size(), 1u);
  run_scene(scene, into(dir));
  std::ofstream(lib / "rubber.toml") << "this is no longer TOML [";
  const Scene again = load_restart_scene((dir / snapshot_filename(scene.output.name, 1)).string());
  EXPECT_EQ(again.materials[0].shear_modulus, 0.22);
  EXPECT_EQ(again.materials[0].murnaghan.K0, 1.0);
  EXPECT_EQ(again.simulation.xsph, 0.25);  // the override travels too
  EXPECT_EQ(again.libraries.size(), 1u);
  fs::remove_all(dir);
  fs::remove_all(lib);
}

// Resuming may extend the run and change its output, not its physics.
TEST(Restart, OnlyTheExtentAndOutputMayChange) {
  const fs::path dir = temp_dir("extend"), more = temp_dir("extend_more");
  const Scene scene = parse_scene(hydro_scene("leapfrog"), "hydro.toml");
  run_scene(scene, into(dir));
  const std::string last = (dir / snapshot_filename(scene.output.name, 4)).string();
  EXPECT_THROW(load_restart_scene(last, {"materials.gas.gamma=1.6"}), InputError);
  // at its end time there is nothing to integrate
  RunOptions same = into(more);
  same.restart_from = last;
  EXPECT_THROW(run_scene(load_restart_scene(last), same), InputError);
  const Scene longer = load_restart_scene(last, {"simulation.end_time=0.1"});
  EXPECT_EQ(longer.simulation.end_time, 0.1);
  const FinalState fs = run_scene(longer, same);
  EXPECT_NEAR(fs.time, 0.1, 1e-12);
  EXPECT_TRUE(fs::exists(more / snapshot_filename(scene.output.name, 5)));
  fs::remove_all(dir);
  fs::remove_all(more);
}

// A diagnostic snapshot (or any file without the restart group) is refused
// with a message naming it.
TEST(Restart, RefusesASnapshotWithoutRestartData) {
  const fs::path dir = temp_dir("bare");
  fs::create_directories(dir);
  ParticleStore<1> ps;
  Features needs;
  ps.allocate(3, needs);
  const std::string path = (dir / "bare.h5").string();
  write_snapshot<1>(path, ps, SnapshotMeta{});
  try {
    load_restart_scene(path);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no restart data"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), path);
  }
  EXPECT_THROW(load_restart_scene((dir / "missing.h5").string()), InputError);
  fs::remove_all(dir);
}
