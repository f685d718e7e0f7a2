// `rubble eos MATERIAL --rho A:B:N --u C:D:M [--format csv]` end to end
// (issue #3 item 6), and Tillotson / Murnaghan scenes through `rubble run`.
// Suite eos_cli, so that `ctest -R eos` selects it.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene_parser.hpp"

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string item; std::getline(in, item, sep);) out.push_back(item);
  return out;
}

struct Result {
  int code = -1;
  std::string out, err;
};

class eos_cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("rubble_test_eos_cli_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    unsetenv("RUBBLE_MATERIALS");  // the build's library
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }

  Result rubble(const std::string& args) {
    const std::string cmd = "cd '" + dir_.string() + "' && '" + std::string(RUBBLE_BINARY) + "' " + args + " >'" +
                            (dir_ / "stdout.txt").string() + "' 2>'" + (dir_ / "stderr.txt").string() + "'";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / "stdout.txt");
    r.err = slurp(dir_ / "stderr.txt");
    fs::remove(dir_ / "stdout.txt");
    fs::remove(dir_ / "stderr.txt");
    return r;
  }

  void expect_usage_error(const std::string& args, const std::string& fragment) {
    const Result r = rubble(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << args << ": stderr lacks '" << fragment << "': " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }

  fs::path dir_;
};

TEST_F(eos_cli, HelpListsTheSubcommand) {
  Result r = rubble("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("eos"), std::string::npos) << r.out;
  r = rubble("eos --help");
  EXPECT_EQ(r.code, 0);
  for (const char* opt : {"--rho", "--u", "--format", "--set", "MATERIAL"})
    EXPECT_NE(r.out.find(opt), std::string::npos) << opt << " not in: " << r.out;
}

TEST_F(eos_cli, CsvGridMatchesTheEquationOfState) {
  const Result r = rubble("eos basalt --rho 1000:5000:5 --u 0:3e7:4 --format csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 1u + 5 * 4) << r.out;
  EXPECT_EQ(lines[0], "rho,u,p,c_s,regime");
  const rubble::EosParams e = rubble::eos_params_from_material(rubble::load_material("basalt"));
  std::vector<std::string> regimes;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = split(lines[i], ',');
    ASSERT_EQ(f.size(), 5u) << lines[i];
    const double rho = std::stod(f[0]), u = std::stod(f[1]);
    EXPECT_EQ(rho, 1000.0 + 1000.0 * ((i - 1) / 4));  // rho outer, u inner
    EXPECT_EQ(u, 1e7 * ((i - 1) % 4));
    const rubble::EosState s = rubble::eos_evaluate(e, rho, u);
    EXPECT_EQ(std::stod(f[2]), s.p);  // %.17g round-trips
    EXPECT_EQ(std::stod(f[3]), std::sqrt(s.c2));
    regimes.push_back(f[4]);
  }
  for (const char* name : {"compressed", "expanded_cold+c2_floor", "partial_vaporisation", "expanded_hot"})
    EXPECT_NE(std::find(regimes.begin(), regimes.end(), name), regimes.end()) << name;
}

TEST_F(eos_cli, TableIsAlignedAndStatesSourceAndUnits) {
  const Result r = rubble("eos iron --rho 7000:8000:2 --u 0:1e6:3");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 4u + 6) << r.out;
  EXPECT_NE(lines[0].find("iron: tillotson EOS"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("source: Melosh"), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find("p [Pa]"), std::string::npos) << lines[2];
  const std::size_t width = lines[4].find("  ", 60);
  for (std::size_t i = 4; i < lines.size(); ++i) {
    EXPECT_EQ(split(lines[i], ' ').size() >= 5, true) << lines[i];
    EXPECT_EQ(lines[i].find("  ", 60), width) << "columns not aligned: " << lines[i];
  }
}

TEST_F(eos_cli, LogSpacingOverridesAndMaterialFiles) {
  Result r = rubble("eos rubber --rho 0.5:1.5:3 --u 1:100:3:log --format csv --set rho_limit=0.9");
  ASSERT_EQ(r.code, 0) << r.err;
  auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 10u);
  EXPECT_EQ(lines[1], "0.5,1,0,1,murnaghan+cutoff");
  EXPECT_EQ(split(lines[2], ',')[1], "10");
  EXPECT_EQ(split(lines[3], ',')[1], "100");
  EXPECT_EQ(lines[7], "1.5,1,0.5,1,murnaghan");
  // a material file of one's own, by path
  const fs::path src = fs::path(RUBBLE_SOURCE_DIR) / "reference_data" / "materials" / "granite.toml";
  write("mygranite.toml", slurp(src));
  r = rubble("eos mygranite.toml --rho 2680:2680:1 --u 0:0:1 --format csv --set cs_min=5000");
  ASSERT_EQ(r.code, 0) << r.err;
  lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1], "2680,0,0,5000,compressed+cs_min");
}

TEST_F(eos_cli, UnknownMaterialIsAClearError) {
  expect_usage_error("eos basalts --rho 1:2:2 --u 0:1:2", "unknown material");
  expect_usage_error("eos basalts --rho 1:2:2 --u 0:1:2", "did you mean 'basalt'");
  expect_usage_error("eos basalts --rho 1:2:2 --u 0:1:2", "aluminium, aluminium_bars, basalt, basalt_brittle, basalt_collins, granite, granite_collins, ice, ice_brittle, iron, nylon, phobos_regolith, porous_aluminium, porous_basalt, pumice, rubber, water");
  expect_usage_error("eos nothere.toml --rho 1:2:2 --u 0:1:2", "no such material file");
  expect_usage_error("eos basalt --rho 1:2:2 --u 0:1:2 --set tillotson.E_cv=1", "tillotson.E_cv");
}

TEST_F(eos_cli, MalformedRangesAreClearErrors) {
  expect_usage_error("eos basalt --rho 1:2 --u 0:1:2", "--rho: expected A:B:N");
  expect_usage_error("eos basalt --rho 1:2:3:4:5 --u 0:1:2", "--rho: expected A:B:N");
  expect_usage_error("eos basalt --rho a:2:3 --u 0:1:2", "--rho: A 'a' is not a finite number");
  expect_usage_error("eos basalt --rho 1:2:2.5 --u 0:1:2", "--rho: N = '2.5' must be a whole number");
  expect_usage_error("eos basalt --rho 1:2:0 --u 0:1:2", "--rho: N = '0'");
  expect_usage_error("eos basalt --rho 0:2:3 --u 0:1:2", "--rho: A must be > 0");
  expect_usage_error("eos basalt --rho 2:1:3 --u 0:1:2", "--rho: B must be > A");
  expect_usage_error("eos basalt --rho 1:2:1 --u 0:1:2", "--rho: N = 1 needs A = B");
  expect_usage_error("eos basalt --rho 1:2:3 --u=-1:1:2", "--u: A must be >= 0");
  expect_usage_error("eos basalt --rho 1:2:3 --u 0:1:2:log", "--u: log spacing needs A > 0");
  expect_usage_error("eos basalt --rho 1:2:3 --u 0:1:2:lin", "the 4th part may only be 'log'");
  expect_usage_error("eos basalt --rho 1:inf:3 --u 0:1:2", "not a finite number");
  expect_usage_error("eos basalt --rho 1:2:3", "--u");
  expect_usage_error("eos basalt --rho 1:2:3 --u 0:1:2 --format xml", "--format");
}

// SPH sanity through the program: Tillotson and Murnaghan scenes run.
TEST_F(eos_cli, TillotsonAndMurnaghanScenesRunThroughRubbleRun) {
  write("basalt.toml", R"([simulation]
dimension = 1
end_time = 2e-5
density = "continuity"

[materials.rock]
library = "basalt"
tillotson.A = 2.0e10     # a single-parameter override

[[bodies]]
shape = "box"
material = "rock"
min = [0.0]
max = [1.0]
spacing = 0.05
density = 2700.0
pressure = 1.0e8

[domain]
periodic = [true]
min = [0.0]
max = [1.0]
)");
  Result r = rubble("run basalt.toml --quiet --out basalt_out");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "basalt_out" / "conserved.csv"));

  write("rings.toml", R"([simulation]
dimension = 2
end_time = 0.5
density = "continuity"
integrator = "leapfrog"

[materials.rubber]
library = "rubber"

[[bodies]]
shape = "box"
material = "rubber"
min = [0.0, 0.0]
max = [1.0, 1.0]
spacing = 0.1
density = 1.0
internal_energy = 0.0
velocity = [0.01, 0.0]
)");
  r = rubble("run rings.toml --quiet --out rings_out");
  EXPECT_EQ(r.code, 0) << r.err;

  // an unphysical override stops the run before any output, naming the key
  write("bad.toml", slurp(dir_ / "basalt.toml") + "\n");
  r = rubble("run bad.toml --set materials.rock.tillotson.E_iv=3e7 --out bad_out");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("materials.rock.tillotson.E_iv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("must be < E_cv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad_out"));
}

}  // namespace

// A state outside the range of numbers is flagged on its row and counted on
// stderr, never printed as nan/inf silently; a grid too large to be a
// table is refused (issue #13 items 5 and 7).
TEST_F(eos_cli, NonFiniteStatesAreFlaggedAndHugeTablesRefused) {
  const Result r = rubble("eos basalt --rho 1000:1e300:2 --u 1:1e300:2 --format csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 5u);
  int flagged = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const bool nonfinite = lines[i].find("nan") != std::string::npos || lines[i].find("inf") != std::string::npos;
    const bool marked = lines[i].find("+NONFINITE") != std::string::npos;
    EXPECT_EQ(nonfinite, marked) << lines[i];
    flagged += marked;
  }
  EXPECT_GT(flagged, 0) << "rho = u = 1e300 overflows the Tillotson pressure";
  EXPECT_NE(r.err.find(std::to_string(flagged) + " of 4 states give a non-finite"), std::string::npos) << r.err;
  expect_usage_error("eos basalt --rho 1:2:10000 --u 0:1:10000", "more than the 1e7 rows");
}

// `rubble strength MATERIAL --p A:B:N [--damage A:B:N] [--u C:D:M]`: the
// yield surface the return enforces (plasticity.hpp: yield_limit_sqrt_j2),
// here basalt_collins' Collins curves: Y_0 and Y_d0 at p = 0, Y_M far out,
// zero beyond the intact curve's tensile zero, and the von Mises limit
// Y/sqrt(3) of basalt_brittle. Bad input names the option.
TEST_F(eos_cli, StrengthTabulatesTheYieldSurface) {
  const Result r = rubble("strength basalt_collins --p -2e7:1e12:3 --damage 0:1:2 --format csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> rows = lines_of(r.out);
  ASSERT_EQ(rows.size(), 7u) << r.out;
  EXPECT_EQ(rows[0], "p,damage,u,sqrt_J2_max");
  const rubble::PlasticityParams pp =
      rubble::plasticity_params_from_config(rubble::load_material("basalt_collins").plasticity);
  int checked = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const std::vector<std::string> c = split(rows[i], ',');
    ASSERT_EQ(c.size(), 4u) << rows[i];
    const double p = std::stod(c[0]), d = std::stod(c[1]), y = std::stod(c[3]);
    EXPECT_DOUBLE_EQ(y, rubble::collins_yield_strength(pp, p, d, 0)) << rows[i];
    if (p == -2e7) {
      EXPECT_EQ(y, 0.0) << "beyond the tensile zero -Y0 (Y_M - Y0)/(mu_i Y_M) = -1.42e7 Pa";
    }
    if (p == 1e12 && d == 0) {
      EXPECT_NEAR(y, 3.5e9, 0.01 * 3.5e9) << "towards Y_M";
    }
    ++checked;
  }
  EXPECT_EQ(checked, 6);
  const Result zero = rubble("strength basalt_collins --p 0:0:1 --damage 0:1:2 --format csv");
  ASSERT_EQ(zero.code, 0) << zero.err;
  EXPECT_NE(zero.out.find("0,0,0,20000000\n"), std::string::npos) << zero.out;  // Y_0
  EXPECT_NE(zero.out.find("0,1,0,10000\n"), std::string::npos) << zero.out;     // Y_d0
  const Result vm = rubble("strength basalt_brittle --p 0:1e9:2 --damage 0:0:1 --format csv");
  ASSERT_EQ(vm.code, 0) << vm.err;
  const std::vector<std::string> v = split(lines_of(vm.out)[1], ',');
  EXPECT_NEAR(std::stod(v[3]), 3.5e9 / std::sqrt(3.0), 1.0);  // von Mises: sqrt(3 J2) <= Y
  const Result table = rubble("strength granite_collins --p 0:1e9:3");
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("# source:"), std::string::npos) << table.out;
  expect_usage_error("strength basalt --p 0:1e9:3", "no yield surface");
  expect_usage_error("strength basalt_collins --p 0:1e9:3 --damage 0:2:3", "--damage");
  expect_usage_error("strength basalt_collins --p 1e9:0:3", "--p");
}
