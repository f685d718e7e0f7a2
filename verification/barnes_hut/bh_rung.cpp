// Verification rung: Barnes-Hut self-gravity against direct summation
// (issue #5; PHYSICS.md §6).
//
//   bh_rung accuracy --case plummer|uniform --n 20000 --thetas 0,0.3,0.5,0.7
//           [--orders monopole,quadrupole] --records DIR [--checks] [--report-only]
//   bh_rung timing --case plummer|uniform --sizes 10000,30000,100000
//           [--direct-max 100000] --records DIR [--checks]
//   bh_rung scatter --case plummer|uniform --n 20000 --thetas 0.3 [--orders monopole]
//           [--seeds 12] [--roots 1.25,1.5] --records DIR [--checks]
//
// accuracy: one particle distribution (fixed seed), accelerations by direct
// summation (the reference) and by the tree at every theta, monopole and
// quadrupole, one particle per leaf and no softening (the conditions the
// PHYSICS.md §6 table was measured under). Per run: relative acceleration
// error |a_tree - a_direct| / |a_direct| over all particles (median, 99th
// percentile, maximum), the same for the potential, and the momentum
// imbalance |Σ m a| / Σ m |a|. Checks: median and p99 at or below the
// PHYSICS.md §6 table for the same case; theta = 0 reproduces direct
// summation to 1e-10 relative (issue #5). One JSON record per (order, theta).
//
// timing: wall time of tree build + walk (default leaf size, theta = 0.5,
// quadrupole) and of direct summation at each N, the best of a few
// repetitions, and the exponents of least-squares power laws t ∝ N^p.
// Check: the tree's p <= 1.3 (issue #5). One JSON record per N.
//
// scatter: the accuracy measurement (table conditions) repeated over --seeds
// particle sets (the first is accuracy's), to show how much the median and
// 99th percentile move between realisations, and, for the monopole, the
// same particles through an independent textbook tree (TextbookTree below:
// insertion, one particle per leaf, recursive walk) with (a) the solver's
// criterion on the same root cube, which must agree with rubble::Octree to
// round-off, (b) the earlier d > s/theta + delta (Barnes 1994) and (c) the
// plain s/d < theta (Barnes & Hut 1986) on the same root cube, and (d) the
// solver's criterion on root cubes --roots times larger (same centre): the
// octree's cell sizes relative to the particle set are a free choice of any
// implementation. Each variant's interactions per particle give its cost.
// Checks: the textbook agreement (1e-10), and rubble::Octree meeting the
// PHYSICS.md §6 table (median and p99) on more than half of the sets: a
// criterion that meets it on one fixed set only could be luck.
// One JSON record per (order, theta).
//
// Exit status 1 if a check fails (0 with --report-only), 2 on bad usage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../common/rung.hpp"
#include "rubble/gravity/direct.hpp"
#include "rubble/gravity/octree.hpp"

using rubble::MultipoleOrder;
using rubble::Real;
using rubble::Vec;
using rubble::verification::Check;
using rubble::verification::Json;

namespace {

struct Args : rubble::verification::RungArgs {
  std::string mode, dist = "plummer";
  std::size_t n = 20000;
  std::vector<double> thetas{0.3, 0.5, 0.7};
  std::vector<double> sizes{10000, 30000, 100000};
  std::vector<MultipoleOrder> orders{MultipoleOrder::Monopole, MultipoleOrder::Quadrupole};
  double direct_max = 1e5;
  int seeds = 12;
  std::vector<double> roots{1.25, 1.5};

  Args() : RungArgs({.taken = "--records --label --checks --report-only"}) {}
  bool own_option(rubble::verification::ArgReader& r) override {
    return r.value("--case", dist) || r.value("--n", n_read) || r.list("--thetas", thetas) ||
           r.list("--sizes", sizes) || r.words("--orders", order_names) || r.value("--direct-max", direct_max) ||
           r.value("--seeds", seeds) || r.list("--roots", roots);
  }
  void validate() override {
    n = std::size_t(n_read);
    if (!order_names.empty()) {
      orders.clear();
      for (const std::string& item : order_names) {
        if (item == "monopole") orders.push_back(MultipoleOrder::Monopole);
        else if (item == "quadrupole") orders.push_back(MultipoleOrder::Quadrupole);
        else throw std::runtime_error("--orders: unknown order " + item);
      }
    }
    if (dist != "plummer" && dist != "uniform") throw std::runtime_error("--case must be plummer or uniform");
  }

 private:
  double n_read = 20000;
  std::vector<std::string> order_names;
};

// The mode word first (accuracy, timing, scatter), then the options.
Args parse_args(int argc, char** argv) {
  if (argc < 2) throw std::runtime_error("usage: bh_rung accuracy|timing|scatter [options]");
  Args a;
  a.mode = argv[1];
  if (a.mode != "accuracy" && a.mode != "timing" && a.mode != "scatter")
    throw std::runtime_error("first argument must be accuracy, timing or scatter");
  a.parse(argc, argv, 2);
  return a;
}

// ---- particle sets (fixed seeds, total mass 1, G = 1) -----------------------

// Uniform double in [0, 1) from 53 random bits: the same on every platform.
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

Vec<3> random_direction(std::mt19937_64& rng) {
  const double z = 2 * uniform01(rng) - 1, phi = 2 * std::numbers::pi * uniform01(rng);
  const double s = std::sqrt(std::max(0.0, 1 - z * z));
  Vec<3> d;
  d[0] = Real(s * std::cos(phi));
  d[1] = Real(s * std::sin(phi));
  d[2] = Real(z);
  return d;
}

// Plummer sphere, scale radius a = 1, by inverting its cumulative mass
// M(<r)/M = r^3 / (r^2 + 1)^(3/2) (Aarseth, Hénon & Wielen 1974), truncated
// at r = 10 a (radii beyond are redrawn; 1.5 % of the mass).
// Uniform sphere: radius 1, by rejection from the cube.
std::vector<Vec<3>> make_sphere(const std::string& dist, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Vec<3>> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (dist == "plummer") {
      double r;
      do {
        const double X = uniform01(rng);
        r = X > 0 ? 1.0 / std::sqrt(std::pow(X, -2.0 / 3.0) - 1.0) : 0.0;
      } while (!(r <= 10.0));
      x[i] = random_direction(rng) * Real(r);
    } else {
      Vec<3> p;
      do {
        for (int k = 0; k < 3; ++k) p[k] = Real(2 * uniform01(rng) - 1);
      } while (rubble::norm2(p) > 1);
      x[i] = p;
    }
  }
  return x;
}

std::uint64_t seed_for(const std::string& dist, std::size_t n) {
  return (dist == "plummer" ? 0x5EEDULL : 0xBA11ULL) * 1000003ULL + n;
}

// ---- statistics --------------------------------------------------------------

struct Stats {
  double median = 0, p99 = 0, max = 0;
};

// Nearest-rank percentiles of a sample.
Stats stats_of(std::vector<double> e) {
  Stats s;
  if (e.empty()) return s;
  std::sort(e.begin(), e.end());
  auto rank = [&](double p) { return e[std::size_t(std::max(0.0, std::ceil(p * double(e.size())) - 1))]; };
  s.median = rank(0.5);
  s.p99 = rank(0.99);
  s.max = e.back();
  return s;
}

Json stats_json(const Stats& s) { return Json::object({{"median", s.median}, {"p99", s.p99}, {"max", s.max}}); }

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// |Σ m a| / Σ m |a|
double momentum_imbalance(const std::vector<Real>& m, const std::vector<Vec<3>>& a) {
  double s[3] = {0, 0, 0}, total = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (int k = 0; k < 3; ++k) s[k] += double(m[i]) * double(a[i][k]);
    total += double(m[i]) * double(rubble::norm(a[i]));
  }
  return std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) / total;
}

const char* order_name(MultipoleOrder o) { return o == MultipoleOrder::Monopole ? "monopole" : "quadrupole"; }

// PHYSICS.md §6 table: median / 99th percentile of the relative acceleration
// error at N = 2e4, double precision, one particle per leaf, no softening,
// measured by an independent implementation with the plain s/d < theta
// criterion. Returns false where the table has no entry.
bool table_value(const std::string& dist, MultipoleOrder order, double theta, double& median, double& p99) {
  struct Row {
    double theta, pm_med, pm_p99, pq_med, pq_p99, um_med, um_p99, uq_med, uq_p99;
  };
  static const Row table[] = {
      {0.3, 3.6e-4, 2.3e-3, 6.4e-5, 3.0e-4, 1.0e-3, 4.2e-3, 7.9e-5, 5.7e-4},
      {0.5, 1.4e-3, 9.6e-3, 4.3e-4, 2.3e-3, 5.3e-3, 1.5e-2, 5.8e-4, 3.0e-3},
      {0.7, 3.7e-3, 2.3e-2, 1.6e-3, 8.6e-3, 1.1e-2, 4.6e-2, 2.2e-3, 1.3e-2},
  };
  for (const Row& r : table) {
    if (std::fabs(r.theta - theta) > 1e-9) continue;
    const bool mono = order == MultipoleOrder::Monopole;
    if (dist == "plummer") {
      median = mono ? r.pm_med : r.pq_med;
      p99 = mono ? r.pm_p99 : r.pq_p99;
    } else {
      median = mono ? r.um_med : r.uq_med;
      p99 = mono ? r.um_p99 : r.uq_p99;
    }
    return true;
  }
  return false;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

void print_checks(const std::vector<Check>& checks) {
  for (const auto& c : checks)
    std::printf("  [%s] %s = %.4g (%s %.4g; %s)\n", c.passed() ? "PASS" : "FAIL", c.name.c_str(), c.value, c.op.c_str(),
                c.threshold, c.source.c_str());
}

// ---- accuracy ------------------------------------------------------------------

int run_accuracy(const Args& args) {
  const std::size_t n = args.n;
  const std::vector<Vec<3>> x = make_sphere(args.dist, n, seed_for(args.dist, n));
  const std::vector<Real> m(n, Real(1.0 / double(n)));
  const std::string label = args.label.empty() ? args.dist + "_n" + std::to_string(n) : args.label;
  const rubble::KernelType kernel = rubble::KernelType::CubicSpline;  // unused without softening

  // The reference.
  std::vector<Vec<3>> a_dir(n);
  std::vector<Real> phi_dir(n);
  auto t0 = std::chrono::steady_clock::now();
  rubble::direct_gravity(x.data(), m.data(), nullptr, n, kernel, Real(1), a_dir.data(), phi_dir.data());
  const double t_direct = seconds_since(t0);
  const double imb_direct = momentum_imbalance(m, a_dir);
  std::printf("%s: N = %zu, direct summation %.2f s, momentum imbalance %.2e\n", label.c_str(), n, t_direct, imb_direct);

  bool all_passed = true;
  // theta = 0 opens every node: the walk is direct summation in another
  // order of summation (issue #5: to 1e-10 relative).
  std::vector<double> theta_list = args.thetas;
  // Two tree settings per (order, theta): the table's conditions (one
  // particle per leaf, every particle walks alone) and the solver's defaults
  // (leaves of up to 8 particles, groups of up to 32 sharing one walk).
  struct Setting {
    const char* name;
    std::uint32_t leaf_size, group_size;
  };
  const Setting settings[] = {{"table conditions", 1, 1}, {"solver defaults", 8, 32}};
  for (MultipoleOrder order : args.orders) {
    for (double theta : theta_list) {
     for (const Setting& setting : settings) {
      rubble::OctreeOptions opt;
      opt.theta = Real(theta);
      opt.order = order;
      opt.leaf_size = setting.leaf_size;
      opt.group_size = setting.group_size;
      rubble::Octree tree(opt);
      std::vector<Vec<3>> a(n);
      std::vector<Real> phi(n);
      t0 = std::chrono::steady_clock::now();
      tree.build(x.data(), m.data(), nullptr, n);
      const double t_build = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      tree.field(Real(1), a.data(), phi.data());
      const double t_walk = seconds_since(t0);

      std::vector<double> ea(n), ep(n);
      for (std::size_t i = 0; i < n; ++i) {
        ea[i] = double(rubble::norm(a[i] - a_dir[i])) / double(rubble::norm(a_dir[i]));
        ep[i] = std::fabs(double(phi[i] - phi_dir[i])) / std::fabs(double(phi_dir[i]));
      }
      const Stats sa = stats_of(ea), sp = stats_of(ep);
      const double imb = momentum_imbalance(m, a);
      const double per_particle_multipoles = double(tree.last_counts().multipoles) / double(n);
      const double per_particle_pairs = double(tree.last_counts().pairs) / double(n);

      std::vector<Check> checks;
      if (args.checks) {
        double tmed = 0, tp99 = 0;
        if (theta == 0) {
          checks.push_back({std::string("theta=0: max relative acceleration error vs direct (") + setting.name + ")",
                            sa.max, 1e-10, "<=",
                            "issue #5: theta -> 0 reproduces direct summation to 1e-10 relative"});
        } else if (n == 20000 && table_value(args.dist, order, theta, tmed, tp99)) {
          // The table was measured at N = 2e4 only: other N are recorded, not judged.
          const std::string src = "PHYSICS.md §6 table (" + args.dist + " " + order_name(order) + ", theta " +
                                  num(theta) + ", N = 2e4)";
          checks.push_back({std::string("median relative acceleration error (") + setting.name + ")", sa.median, tmed,
                            "<=", src});
          checks.push_back({std::string("99th percentile relative acceleration error (") + setting.name + ")", sa.p99,
                            tp99, "<=", src});
        }
      }
      std::vector<Json> cj;
      for (const auto& c : checks) {
        cj.push_back(c.json());
        all_passed = all_passed && c.passed();
      }
      // theta = 0 is a case of its own (its 1/theta would be infinite).
      const Json record = rubble::verification::record_head("barnes_hut", theta > 0 ? label : label + "_theta0",
                                                            theta > 0 ? 1.0 / theta : double(n),
                                                            theta > 0 ? "1/theta" : "N", n, 3).with({
          {"parameters", Json::object({{"distribution", args.dist},
                                       {"order", order_name(order)},
                                       {"leaf_size", int(setting.leaf_size)},
                                       {"group_size", int(setting.group_size)},
                                       {"softening", 0.0},
                                       {"criterion", "2 B / (sqrt(3) theta), B = |com - farthest cell corner|"}})},
          {"theta", theta},
          {"errors", Json::object({{"acc", stats_json(sa)}, {"phi", stats_json(sp)}})},
          {"momentum_imbalance", imb},
          {"momentum_imbalance_direct", imb_direct},
          {"interactions_per_particle", Json::object({{"multipole", per_particle_multipoles},
                                                      {"pair", per_particle_pairs}})},
          {"timing", Json::object({{"tree_build", t_build}, {"tree_walk", t_walk}, {"direct", t_direct}})},
          {"wall_seconds", t_build + t_walk},
          {"checks", Json::array(cj)},
      });
      char stem[160];
      std::snprintf(stem, sizeof stem, "barnes_hut-%s-%s-theta%.3f-leaf%u-group%u", label.c_str(), order_name(order),
                    theta, setting.leaf_size, setting.group_size);
      rubble::verification::write_record(args.records, stem, record, "cpu");
      std::printf("  %-10s theta %.2f leaf %u group %2u: acc rel err median %.3e  p99 %.3e  max %.3e | phi median "
                  "%.3e p99 %.3e | imbalance %.2e | %.0f multipoles + %.0f pairs per particle | build %.3f s walk "
                  "%.3f s\n",
                  order_name(order), theta, setting.leaf_size, setting.group_size, sa.median, sa.p99, sa.max,
                  sp.median, sp.p99, imb, per_particle_multipoles, per_particle_pairs, t_build, t_walk);
      print_checks(checks);
      std::fflush(stdout);
     }
    }
  }
  return (all_passed || args.report_only) ? 0 : 1;
}

// ---- timing ----------------------------------------------------------------------

// Least-squares slope of log t against log N.
double fitted_exponent(const std::vector<double>& n, const std::vector<double>& t) {
  return -rubble::verification::observed_order(n, t);
}

int run_timing(const Args& args) {
  const rubble::OctreeOptions opt;  // production defaults: theta 0.5, quadrupole, leaf size 8
  std::vector<double> ns, t_tree, t_build, t_walk, nd, t_dir;
  struct Row {
    std::size_t n;
    double build, walk, direct;
    Stats err;
  };
  std::vector<Row> rows;
  for (double nn : args.sizes) {
    const std::size_t n = std::size_t(nn);
    const std::vector<Vec<3>> x = make_sphere(args.dist, n, seed_for(args.dist, n));
    const std::vector<Real> m(n, Real(1.0 / double(n)));
    rubble::Octree tree(opt);
    std::vector<Vec<3>> a(n);
    double best_build = 1e30, best_walk = 1e30;
    const int tree_reps = 5;  // best of five: robust to a busy machine (3 at 1e5 once gave 1.37 for 1.24)
    for (int rep = 0; rep < tree_reps; ++rep) {
      auto t0 = std::chrono::steady_clock::now();
      tree.build(x.data(), m.data(), nullptr, n);
      best_build = std::min(best_build, seconds_since(t0));
      t0 = std::chrono::steady_clock::now();
      tree.field(Real(1), a.data(), nullptr);
      best_walk = std::min(best_walk, seconds_since(t0));
    }
    Row row{n, best_build, best_walk, -1, {}};
    if (nn <= args.direct_max) {
      std::vector<Vec<3>> ad(n);
      double best = 1e30;
      const int reps = n <= 30000 ? 2 : 1;
      for (int rep = 0; rep < reps; ++rep) {
        const auto t0 = std::chrono::steady_clock::now();
        rubble::direct_gravity(x.data(), m.data(), nullptr, n, opt.kernel, Real(1), ad.data(), nullptr);
        best = std::min(best, seconds_since(t0));
      }
      row.direct = best;
      std::vector<double> e(n);
      for (std::size_t i = 0; i < n; ++i) e[i] = double(rubble::norm(a[i] - ad[i]) / rubble::norm(ad[i]));
      row.err = stats_of(e);
      nd.push_back(nn);
      t_dir.push_back(best);
    }
    ns.push_back(nn);
    t_build.push_back(best_build);
    t_walk.push_back(best_walk);
    t_tree.push_back(best_build + best_walk);
    rows.push_back(row);
    std::printf("N %8zu  tree build %.4f s  walk %.4f s  total %.4f s  direct %s s  (acc err median %.2e p99 %.2e)\n",
                n, best_build, best_walk, best_build + best_walk, row.direct >= 0 ? num(row.direct).c_str() : "-",
                row.err.median, row.err.p99);
    std::fflush(stdout);
  }
  const double p_tree = ns.size() >= 2 ? fitted_exponent(ns, t_tree) : NAN;
  const double p_build = ns.size() >= 2 ? fitted_exponent(ns, t_build) : NAN;
  const double p_walk = ns.size() >= 2 ? fitted_exponent(ns, t_walk) : NAN;
  const double p_dir = nd.size() >= 2 ? fitted_exponent(nd, t_dir) : NAN;
  std::printf("fitted exponents t ∝ N^p: tree (build + walk) %.3f (build %.3f, walk %.3f), direct %.3f\n", p_tree,
              p_build, p_walk, p_dir);

  std::vector<Check> checks;
  if (args.checks)
    checks.push_back({"fitted exponent of tree build + walk time vs N", p_tree, 1.3, "<=",
                      "issue #5: the tree's exponent must be <= 1.3"});
  print_checks(checks);
  bool all_passed = true;
  std::vector<Json> cj;
  for (const auto& c : checks) {
    cj.push_back(c.json());
    all_passed = all_passed && c.passed();
  }
  const std::string label = args.label.empty() ? "timing_" + args.dist : args.label;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    const bool last = k + 1 == rows.size();
    const Json errs = r.direct >= 0 ? Json::object({{"acc", stats_json(r.err)}})
                                    : Json::object({{"acc", Json::object({{"median", Json()}})}});
    const Json record = rubble::verification::record_head("barnes_hut", label, double(r.n), "N", r.n, 3).with({
        {"parameters", Json::object({{"distribution", args.dist},
                                     {"order", order_name(opt.order)},
                                     {"theta", double(opt.theta)},
                                     {"leaf_size", int(opt.leaf_size)}})},
        {"errors", errs},
        {"timing", Json::object({{"tree_build", r.build},
                                 {"tree_walk", r.walk},
                                 {"tree_total", r.build + r.walk},
                                 {"direct", r.direct >= 0 ? Json(r.direct) : Json()}})},
        {"observed_order", last ? Json::object({{"tree_time_exponent", p_tree},
                                                {"tree_build_exponent", p_build},
                                                {"tree_walk_exponent", p_walk},
                                                {"direct_time_exponent", p_dir}})
                                : Json::object({})},
        {"wall_seconds", r.build + r.walk},
        {"checks", last ? Json::array(cj) : Json::array({})},
    });
    char stem[160];
    std::snprintf(stem, sizeof stem, "barnes_hut-%s-n%zu", label.c_str(), r.n);
    rubble::verification::write_record(args.records, stem, record, "cpu");
  }
  return (all_passed || args.report_only) ? 0 : 1;
}

// ---- scatter: realisations, a textbook tree, the root cube -------------------------

// Barnes & Hut (1986) as it is usually written, independently of
// rubble::Octree (no Morton keys, no skipped levels, no stackless walk):
// particles are inserted one at a time into a cube that splits every cell
// holding two of them (one particle per leaf); cells carry their geometric
// centre and side, mass and centre of mass; the walk recurses from the root
// and uses a cell's monopole when
//     d > 2 B / (sqrt(3) theta)     (the solver's criterion, B = |com - farthest cell corner|),
//     d > s/theta + delta           (Barnes 1994, delta = |com - cell centre|), or
//     s/d < theta                   (plain Barnes & Hut 1986)
// with d the distance to the centre of mass. A leaf (one particle) is exact.
// No softening; monopole only; double precision whatever Real is.
class TextbookTree {
 public:
  enum class Criterion { Solver, Offset, Plain };

  TextbookTree(const std::vector<Vec<3>>& x, double particle_mass, const double centre[3], double side)
      : x_(x), m_(particle_mass) {
    cells_.reserve(2 * x.size() + 1);
    Cell root;
    for (int k = 0; k < 3; ++k) root.c[k] = centre[k];
    root.half = 0.5 * side;
    cells_.push_back(root);
    for (std::size_t i = 0; i < x.size(); ++i) insert(0, int(i), 0);
    finish(0);
  }

  // Acceleration (G = 1) of particle i due to all others; adds the cells and
  // particles it used to *interactions.
  Vec<3> accel(std::size_t i, double theta, Criterion crit, std::uint64_t* interactions) const {
    double a[3] = {0, 0, 0};
    walk(0, int(i), theta, crit, a, interactions);
    Vec<3> out;
    for (int k = 0; k < 3; ++k) out[k] = Real(a[k]);
    return out;
  }

 private:
  struct Cell {
    double c[3] = {0, 0, 0}, half = 0, m = 0, com[3] = {0, 0, 0};
    int particle = -1, count = 0;
    int child[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  };

  int octant_of(const Cell& cell, int i) const {
    int o = 0;
    for (int k = 0; k < 3; ++k)
      if (double(x_[i][k]) >= cell.c[k]) o |= 1 << k;
    return o;
  }
  int child_of(int cell, int o) {
    if (cells_[cell].child[o] < 0) {
      Cell ch;
      ch.half = 0.5 * cells_[cell].half;
      for (int k = 0; k < 3; ++k) ch.c[k] = cells_[cell].c[k] + (((o >> k) & 1) ? ch.half : -ch.half);
      cells_[cell].child[o] = int(cells_.size());
      cells_.push_back(ch);
    }
    return cells_[cell].child[o];
  }
  void insert(int cell, int i, int depth) {
    if (depth > 60) throw std::runtime_error("TextbookTree: coincident particles");
    if (cells_[cell].count == 0) {
      cells_[cell].particle = i;
      cells_[cell].count = 1;
      return;
    }
    if (cells_[cell].count == 1) {  // split: push the resident particle down
      const int j = cells_[cell].particle;
      cells_[cell].particle = -1;
      insert(child_of(cell, octant_of(cells_[cell], j)), j, depth + 1);
    }
    ++cells_[cell].count;
    insert(child_of(cell, octant_of(cells_[cell], i)), i, depth + 1);
  }
  void finish(int cell) {
    Cell& c = cells_[cell];
    if (c.count == 1) {
      c.m = m_;
      for (int k = 0; k < 3; ++k) c.com[k] = double(x_[c.particle][k]);
      return;
    }
    double m = 0, mx[3] = {0, 0, 0};
    for (int o = 0; o < 8; ++o) {
      const int ch = cells_[cell].child[o];
      if (ch < 0) continue;
      finish(ch);
      m += cells_[ch].m;
      for (int k = 0; k < 3; ++k) mx[k] += cells_[ch].m * cells_[ch].com[k];
    }
    Cell& cc = cells_[cell];
    cc.m = m;
    for (int k = 0; k < 3; ++k) cc.com[k] = mx[k] / m;
  }
  void walk(int cell, int i, double theta, Criterion crit, double a[3], std::uint64_t* interactions) const {
    const Cell& c = cells_[cell];
    if (c.count == 1 && c.particle == i) return;
    double r[3], d2 = 0, off2 = 0, b2 = 0;
    for (int k = 0; k < 3; ++k) {
      r[k] = double(x_[i][k]) - c.com[k];
      d2 += r[k] * r[k];
      const double off = c.com[k] - c.c[k];
      off2 += off * off;
      b2 += (c.half + std::fabs(off)) * (c.half + std::fabs(off));  // to the farthest corner
    }
    const double d = std::sqrt(d2), s = 2 * c.half;
    bool accept = c.count == 1;
    if (!accept) {
      if (crit == Criterion::Solver) accept = d > 2 / std::sqrt(3.0) * std::sqrt(b2) / theta;
      else if (crit == Criterion::Offset) accept = d > s / theta + std::sqrt(off2);
      else accept = s < theta * d;
    }
    if (accept) {
      ++*interactions;
      const double f = c.m / (d2 * d);
      for (int k = 0; k < 3; ++k) a[k] -= f * r[k];
      return;
    }
    for (int o = 0; o < 8; ++o)
      if (c.child[o] >= 0) walk(c.child[o], i, theta, crit, a, interactions);
  }

  const std::vector<Vec<3>>& x_;
  double m_;
  std::vector<Cell> cells_;
};

// p99 by linear interpolation between order statistics (numpy's default),
// to compare with the nearest rank used everywhere else.
double p99_interpolated(std::vector<double> e) {
  std::sort(e.begin(), e.end());
  const double pos = 0.99 * double(e.size() - 1);
  const std::size_t k = std::size_t(pos);
  const double f = pos - double(k);
  return k + 1 < e.size() ? e[k] * (1 - f) + e[k + 1] * f : e[k];
}

int run_scatter(const Args& args) {
  const std::size_t n = args.n;
  const std::string label = (args.label.empty() ? args.dist + "_n" + std::to_string(n) : args.label) + "_scatter";
  const int seeds = std::max(1, args.seeds);
  const rubble::KernelType kernel = rubble::KernelType::CubicSpline;  // unused without softening
  const std::vector<Real> m(n, Real(1.0 / double(n)));
  // Uniform sphere (radius 1): 6.4 % of the particles lie within 0.4 of the
  // centre, where |a| ∝ r is small. Plummer (a = 1): within the scale radius.
  const double r_inner = args.dist == "uniform" ? 0.4 : 1.0;

  // Per (order, theta) and variant: the median and p99 of every seed.
  struct Series {
    std::string name;
    std::vector<double> median, p99, interactions;  // interactions per particle
  };
  struct Case {
    MultipoleOrder order;
    double theta;
    std::vector<Series> series;  // [0] rubble::Octree, then (monopole) the textbook variants
    double textbook_max_diff = 0;
    double p99_interp_max_rel = 0;  // |p99 interpolated - nearest rank| / nearest rank, largest
    double tail_inner_min = 1;      // smallest fraction (over sets) of the worst 1 % within r_inner of the centre
  };
  std::vector<Case> cases;
  for (MultipoleOrder order : args.orders)
    for (double theta : args.thetas) {
      if (!(theta > 0)) continue;
      Case c{order, theta, {{"rubble::Octree", {}, {}, {}}}, 0, 0};
      if (order == MultipoleOrder::Monopole) {
        c.series.push_back({"textbook, 2B/(sqrt3 theta) (solver)", {}, {}, {}});
        c.series.push_back({"textbook, s/theta + delta (Barnes 94)", {}, {}, {}});
        c.series.push_back({"textbook, plain s/d < theta", {}, {}, {}});
        for (double f : args.roots) c.series.push_back({"textbook, solver's, root x" + num(f), {}, {}, {}});
      }
      cases.push_back(c);
    }

  const auto t_start = std::chrono::steady_clock::now();
  for (int sd = 0; sd < seeds; ++sd) {
    const std::uint64_t seed = seed_for(args.dist, n) + std::uint64_t(sd) * 0x9E3779B97F4A7C15ULL;
    const std::vector<Vec<3>> x = make_sphere(args.dist, n, seed);
    std::vector<Vec<3>> a_dir(n);
    rubble::direct_gravity(x.data(), m.data(), nullptr, n, kernel, Real(1), a_dir.data(), nullptr);
    auto errors_of = [&](const std::vector<Vec<3>>& a) {
      std::vector<double> e(n);
      for (std::size_t i = 0; i < n; ++i) e[i] = double(rubble::norm(a[i] - a_dir[i])) / double(rubble::norm(a_dir[i]));
      return e;
    };
    std::printf("set %2d:", sd);
    for (Case& c : cases) {
      rubble::OctreeOptions opt;
      opt.theta = Real(c.theta);
      opt.order = c.order;
      opt.leaf_size = 1;
      opt.group_size = 1;
      rubble::Octree tree(opt);
      tree.build(x.data(), m.data(), nullptr, n);
      std::vector<Vec<3>> a(n);
      tree.field(Real(1), a.data(), nullptr);
      const std::vector<double> e = errors_of(a);
      const Stats s = stats_of(e);
      c.series[0].median.push_back(s.median);
      c.series[0].p99.push_back(s.p99);
      c.series[0].interactions.push_back(double(tree.last_counts().multipoles + tree.last_counts().pairs) /
                                         double(n));
      c.p99_interp_max_rel = std::max(c.p99_interp_max_rel, std::fabs(p99_interpolated(e) - s.p99) / s.p99);
      {  // where the worst 1 % lie: distance from the set's centre of mass
        Vec<3> com = Vec<3>::zero();
        for (const Vec<3>& p : x) com += p * Real(1.0 / double(n));
        std::size_t tail = 0, inner = 0;
        for (std::size_t i = 0; i < n; ++i)
          if (e[i] > s.p99) {
            ++tail;
            inner += double(rubble::norm(x[i] - com)) < r_inner;
          }
        if (tail > 0) c.tail_inner_min = std::min(c.tail_inner_min, double(inner) / double(tail));
      }
      std::printf("  %s theta %.2f: %.3e / %.3e", order_name(c.order), c.theta, s.median, s.p99);
      if (c.order != MultipoleOrder::Monopole) continue;
      // The textbook tree on the same root cube (the key box), then on larger ones.
      const rubble::Box<3>& kb = tree.key_box();
      double centre[3], side = 0;
      for (int k = 0; k < 3; ++k) {
        centre[k] = 0.5 * (double(kb.lo[k]) + double(kb.hi[k]));
        side = std::max(side, double(kb.hi[k]) - double(kb.lo[k]));
      }
      std::size_t si = 1;
      using Crit = TextbookTree::Criterion;
      auto textbook = [&](double root_factor, Crit crit, bool compare) {
        const TextbookTree tb(x, 1.0 / double(n), centre, side * root_factor);
        std::vector<Vec<3>> at(n);
        double diff = 0;
        std::uint64_t inter = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(max : diff) reduction(+ : inter)
        for (std::size_t i = 0; i < n; ++i) {
          at[i] = tb.accel(i, c.theta, crit, &inter);
          if (compare) diff = std::max(diff, double(rubble::norm(at[i] - a[i])) / double(rubble::norm(a_dir[i])));
        }
        const Stats st = stats_of(errors_of(at));
        c.series[si].median.push_back(st.median);
        c.series[si].p99.push_back(st.p99);
        c.series[si].interactions.push_back(double(inter) / double(n));
        ++si;
        return diff;
      };
      c.textbook_max_diff = std::max(c.textbook_max_diff, textbook(1.0, Crit::Solver, true));
      textbook(1.0, Crit::Offset, false);
      textbook(1.0, Crit::Plain, false);
      for (double f : args.roots) textbook(f, Crit::Solver, false);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  const double wall = seconds_since(t_start);

  bool all_passed = true;
  for (const Case& c : cases) {
    double tmed = NAN, tp99 = NAN;
    const bool has_table = n == 20000 && table_value(args.dist, c.order, c.theta, tmed, tp99);
    std::printf("%s %s theta %.2f over %d particle sets (one particle per leaf, no softening); median | p99: "
                "mean [min, max]%s\n",
                label.c_str(), order_name(c.order), c.theta, seeds,
                has_table ? (", sets meeting PHYSICS.md §6 (" + num(tmed) + " / " + num(tp99) + ")").c_str() : "");
    std::vector<std::pair<std::string, Json>> series_json;
    int ours_meet_both = 0;
    for (const Series& se : c.series) {
      auto mean = [](const std::vector<double>& v) {
        double t = 0;
        for (double e : v) t += e;
        return t / double(v.size());
      };
      const auto [mn_med, mx_med] = std::minmax_element(se.median.begin(), se.median.end());
      const auto [mn_p99, mx_p99] = std::minmax_element(se.p99.begin(), se.p99.end());
      int meet_med = 0, meet_p99 = 0, meet_both = 0;
      for (std::size_t k = 0; k < se.median.size(); ++k) {
        meet_med += se.median[k] <= tmed;
        meet_p99 += se.p99[k] <= tp99;
        meet_both += se.median[k] <= tmed && se.p99[k] <= tp99;
      }
      if (&se == &c.series[0]) ours_meet_both = meet_both;
      std::printf("  %-38s %.3e [%.3e, %.3e] | %.3e [%.3e, %.3e] | %6.0f interactions", se.name.c_str(),
                  mean(se.median), *mn_med, *mx_med, mean(se.p99), *mn_p99, *mx_p99, mean(se.interactions));
      if (has_table) std::printf("  median %d, p99 %d, both %d of %d", meet_med, meet_p99, meet_both, seeds);
      std::printf("\n");
      series_json.push_back({se.name, Json::object({{"median", se.median},
                                                    {"p99", se.p99},
                                                    {"interactions_per_particle", se.interactions}})});
    }
    std::printf("  rubble::Octree: at least %.0f %% of the errors above the p99 lie within r < %g of the centre of mass; "
                "p99 by linear interpolation differs from the nearest rank by at most %.1e relative\n",
                100 * c.tail_inner_min, r_inner, c.p99_interp_max_rel);
    std::vector<Check> checks;
    if (args.checks && c.order == MultipoleOrder::Monopole)
      checks.push_back({"max |a_octree - a_textbook| / |a_direct| over all particle sets (same criterion, same root)",
                        c.textbook_max_diff, 1e-10, "<=",
                        "an independent textbook tree with the solver's criterion must give the same forces"});
    if (args.checks && has_table)
      checks.push_back({"particle sets on which rubble::Octree meets the table's median and p99", double(ours_meet_both),
                        double(seeds / 2 + 1), ">=",
                        "PHYSICS.md §6 table (" + args.dist + " " + order_name(c.order) + ", theta " + num(c.theta) +
                            ", N = 2e4), on more than half of " + std::to_string(seeds) + " sets"});
    print_checks(checks);
    std::vector<Json> cj;
    for (const auto& ch : checks) {
      cj.push_back(ch.json());
      all_passed = all_passed && ch.passed();
    }
    const Series& ours = c.series[0];
    double mean_med = 0, mean_p99 = 0;
    for (std::size_t k = 0; k < ours.median.size(); ++k) {
      mean_med += ours.median[k] / double(seeds);
      mean_p99 += ours.p99[k] / double(seeds);
    }
    const Json record = rubble::verification::record_head("barnes_hut", label, 1.0 / c.theta, "1/theta", n, 3).with({
        {"parameters", Json::object({{"distribution", args.dist},
                                     {"order", order_name(c.order)},
                                     {"leaf_size", 1},
                                     {"group_size", 1},
                                     {"softening", 0.0},
                                     {"particle_sets", seeds}})},
        {"theta", c.theta},
        {"errors", Json::object({{"acc", Json::object({{"median", mean_med}, {"p99", mean_p99}})}})},
        {"notes", "errors.acc: means over the particle sets of rubble::Octree's median and p99; per-set values of "
                  "every variant under scatter"},
        {"scatter", Json::object(series_json)},
        {"tail_fraction_inner", c.tail_inner_min},
        {"tail_inner_radius", r_inner},
        {"textbook_max_diff", c.order == MultipoleOrder::Monopole ? Json(c.textbook_max_diff) : Json()},
        {"wall_seconds", wall},
        {"checks", Json::array(cj)},
    });
    char stem[160];
    std::snprintf(stem, sizeof stem, "barnes_hut-%s-%s-theta%.3f", label.c_str(), order_name(c.order), c.theta);
    rubble::verification::write_record(args.records, stem, record, "cpu");
  }
  std::fflush(stdout);
  return (all_passed || args.report_only) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main("bh_rung: error: ", [&] {
    const Args args = parse_args(argc, argv);
    if (args.mode == "scatter") return run_scatter(args);
    return args.mode == "accuracy" ? run_accuracy(args) : run_timing(args);
  });
}
