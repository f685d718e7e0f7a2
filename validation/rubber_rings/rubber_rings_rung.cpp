// Validation rung: colliding rubber rings (issue #4 item 5; PHYSICS.md §7;
// Monaghan 2000; Gray, Monaghan & Swift 2001).
//
//   rubber_rings_rung --scene FILE --records DIR --out DIR --spacing DX
//                     [--label NAME] [--set key=value ...] [--report-only]
//
// Runs the scene through rubble::run_scene (snapshots every output interval,
// conserved.csv every step), then reads the output back and checks, with the
// thresholds of issue #4 item 5:
//   - linear momentum |sum m v| < 1e-10 sum m |v| at every output;
//   - total energy (kinetic + internal) drift <= 0.5 % of the initial kinetic energy;
//   - each ring's centre-of-mass x-velocity changes sign after contact;
//   - after separation (last output) exactly two connected bodies (link: pair closer than 1.5 dx);
//   - no pair closer than 0.5 dx at any output (clumping).
// Writes one JSON record. --report-only (the run without artificial stress,
// recorded to show the tensile instability) keeps the exit status 0.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../../verification/common/conserved_csv.hpp"
#include "../../verification/common/rung.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"

namespace {

using rubble::verification::Check;
using rubble::verification::Json;

struct Args : rubble::verification::RungArgs {
  double spacing = 0.15;
  Args() : RungArgs({.taken = "--scene --records --out --label --set --report-only",
                     .out = "rubber_rings_out",
                     .label = "rubber_rings"}) {}
  bool own_option(rubble::verification::ArgReader& r) override { return r.value("--spacing", spacing); }
  void validate() override {
    if (scene.empty()) throw std::runtime_error("--scene is required");
  }
};

struct Output {
  double t = 0;
  double momentum = 0, momentum_scale = 0;  // |sum m v|, sum m |v|
  double vcom_left = 0, vcom_right = 0;     // centre-of-mass x-velocities (material 0, 1)
  double min_pair = 0;                      // closest pair distance
  int bodies = 0;                           // connected bodies (link < 1.5 dx)
  std::vector<double> x, y, rho;
};

// Closest pair and connected components by a uniform grid of cell size `link`.
void pairs(const std::vector<double>& x, const std::vector<double>& y, double link, double& min_pair, int& bodies) {
  const std::size_t n = x.size();
  const double x0 = *std::min_element(x.begin(), x.end()), y0 = *std::min_element(y.begin(), y.end());
  const double x1 = *std::max_element(x.begin(), x.end()), y1 = *std::max_element(y.begin(), y.end());
  const long nx = long((x1 - x0) / link) + 1, ny = long((y1 - y0) / link) + 1;
  std::vector<std::vector<std::size_t>> cells(std::size_t(nx * ny));
  auto cx = [&](std::size_t i) { return long((x[i] - x0) / link); };
  auto cy = [&](std::size_t i) { return long((y[i] - y0) / link); };
  for (std::size_t i = 0; i < n; ++i) cells[std::size_t(cy(i) * nx + cx(i))].push_back(i);
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  double d2min = 1e300;
  for (std::size_t i = 0; i < n; ++i)
    for (long jy = std::max(0L, cy(i) - 1); jy <= std::min(ny - 1, cy(i) + 1); ++jy)
      for (long jx = std::max(0L, cx(i) - 1); jx <= std::min(nx - 1, cx(i) + 1); ++jx)
        for (std::size_t j : cells[std::size_t(jy * nx + jx)]) {
          if (j <= i) continue;
          const double d2 = (x[i] - x[j]) * (x[i] - x[j]) + (y[i] - y[j]) * (y[i] - y[j]);
          d2min = std::min(d2min, d2);
          if (d2 < link * link) parent[find(i)] = find(j);
        }
  min_pair = std::sqrt(d2min);
  bodies = 0;
  for (std::size_t i = 0; i < n; ++i) bodies += find(i) == i;
}

Output measure(const std::string& path, double dx) {
  rubble::ParticleStore<2> ps;
  rubble::SnapshotMeta meta;
  rubble::read_snapshot<2>(path, ps, meta);
  Output o;
  o.t = meta.time;
  double P[2] = {0, 0}, mv[2][2] = {{0, 0}, {0, 0}};
  double mass[2] = {0, 0};
  for (std::size_t i = 0; i < ps.n; ++i) {
    const double m = ps.m[i];
    for (int k = 0; k < 2; ++k) P[k] += m * ps.v[i][k];
    o.momentum_scale += m * std::hypot(double(ps.v[i][0]), double(ps.v[i][1]));
    const int ring = ps.material_id[i] == 0 ? 0 : 1;
    mass[ring] += m;
    mv[ring][0] += m * ps.v[i][0];
    o.x.push_back(ps.x[i][0]);
    o.y.push_back(ps.x[i][1]);
    o.rho.push_back(ps.rho[i]);
  }
  o.momentum = std::hypot(P[0], P[1]);
  o.vcom_left = mv[0][0] / mass[0];
  o.vcom_right = mv[1][0] / mass[1];
  pairs(o.x, o.y, 1.5 * dx, o.min_pair, o.bodies);
  return o;
}

using rubble::verification::ConservedRow;

int run(const Args& args) {
  std::vector<std::string> sets = args.sets;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", args.spacing);
  sets.push_back(std::string("bodies.0.spacing=") + buf);
  sets.push_back(std::string("bodies.1.spacing=") + buf);
  const rubble::Scene scene = rubble::load_scene_file(args.scene, sets);
  if (scene.simulation.dimension != 2 || scene.materials.size() != 2 || scene.bodies.size() != 2)
    throw std::runtime_error("the rubber-ring scene is 2-D with two materials (one per ring) and two bodies");
  const double dx = args.spacing;

  const rubble::FinalState fs = rubble::verification::run_into(scene, args.out);
  std::printf("%s dx=%g: N = %zu, %lld steps, wall %.1f s\n", args.label.c_str(), dx, fs.m.size(),
              static_cast<long long>(fs.steps), fs.wall_seconds);

  std::vector<Output> outs;
  for (const auto& p : rubble::verification::snapshot_files(args.out, scene.output.name))
    outs.push_back(measure(p.string(), dx));
  if (outs.size() < 2) throw std::runtime_error("fewer than two snapshots written");

  const auto rows = rubble::verification::read_conserved_csv((std::filesystem::path(args.out) / "conserved.csv").string());
  const double ke0 = rows.front().kinetic, e0 = rows.front().total;
  double drift = 0;
  std::vector<double> et, ekin, eint, etot;
  const std::size_t stride = std::max<std::size_t>(1, rows.size() / 400);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    drift = std::max(drift, std::fabs(rows[i].total - e0) / ke0);
    if (i % stride == 0 || i + 1 == rows.size()) {
      et.push_back(rows[i].t);
      ekin.push_back(rows[i].kinetic);
      eint.push_back(rows[i].internal);
      etot.push_back(rows[i].total);
    }
  }

  double momentum_ratio = 0, min_pair = 1e300;
  std::vector<double> ot, vl, vr, mp, nb, mom;
  for (const Output& o : outs) {
    momentum_ratio = std::max(momentum_ratio, o.momentum / o.momentum_scale);
    min_pair = std::min(min_pair, o.min_pair);
    ot.push_back(o.t);
    vl.push_back(o.vcom_left);
    vr.push_back(o.vcom_right);
    mp.push_back(o.min_pair / dx);
    nb.push_back(o.bodies);
    mom.push_back(o.momentum / o.momentum_scale);
    std::printf("  t %6.2f  vcom %+.5f %+.5f  min pair %.3f dx  bodies %d  |P|/sum m|v| %.2e\n", o.t, o.vcom_left,
                o.vcom_right, o.min_pair / dx, o.bodies, o.momentum / o.momentum_scale);
  }
  const Output& first = outs.front();
  const Output& last = outs.back();
  // sign change: the final COM velocity opposes the initial one (rebound);
  // the measure is the smaller of the two rings' reversed speeds (> 0 passes)
  const double rebound = std::min(-last.vcom_left * (first.vcom_left > 0 ? 1 : -1),
                                  -last.vcom_right * (first.vcom_right > 0 ? 1 : -1));
  std::printf("  energy drift %.3e of KE0, max |P|/sum m|v| %.2e, rebound speed %.4f, bodies at end %d, min pair %.3f dx\n",
              drift, momentum_ratio, rebound, last.bodies, min_pair / dx);

  const std::string src = "issue #4 item 5";
  std::vector<Check> checks = {
      {"max |sum m v| / sum m|v| over outputs", momentum_ratio, 1e-10, "<=", src},
      {"energy drift max|E(t) - E(0)| / KE(0)", drift, 5e-3, "<=", src},
      {"COM x-velocity reversed after contact (min over rings of -v_end sign(v_0))", rebound, 0.0, ">=", src},
      {"connected bodies at t_end (link 1.5 dx) = 2: |bodies - 2|", std::fabs(double(last.bodies) - 2), 0.0, "<=", src},
      {"min pair distance / dx over outputs", min_pair / dx, 0.5, ">=", src},
  };
  // the rebound check is strict: exactly zero does not count
  if (rebound <= 0) checks[2].value = std::min(rebound, -1e-300);
  bool ok = true;
  const Json checks_json = rubble::verification::judge_checks(checks, ok);

  // density strip: four outputs spread over the run
  std::vector<Json> strip;
  for (int q = 0; q < 4; ++q) {
    const Output& o = outs[std::size_t(std::lround(q * double(outs.size() - 1) / 3.0))];
    strip.push_back(Json::object({{"t", o.t}, {"x", o.x}, {"y", o.y}, {"rho", o.rho}}));
  }
  const rubble::MaterialConfig& mat = scene.materials[0];
  const Json record = rubble::verification::record_head("rubber_rings", args.label, 1.0 / dx, "1/dx", fs.m.size(),
                                                        2).with({
      {"parameters", Json::object({{"dx", dx},
                                   {"mu", mat.shear_modulus},
                                   {"artificial_stress", mat.artificial_stress.enabled},
                                   {"epsilon", mat.artificial_stress.epsilon},
                                   {"n", mat.artificial_stress.n},
                                   {"artificial_stress_form", rubble::artificial_stress_form_name(mat.artificial_stress.form)},
                                   {"end_time", scene.simulation.end_time},
                                   {"report_only", args.report_only}})},
      {"errors", Json::object({{"energy", Json::object({{"rel", drift}})},
                               {"momentum", Json::object({{"rel", momentum_ratio}})}})},
      {"wall_seconds", fs.wall_seconds},
      {"checks", checks_json},
      {"energy_history", Json::object({{"t", et}, {"kinetic", ekin}, {"internal", eint}, {"total", etot}})},
      {"outputs", Json::object({{"t", ot}, {"vcom_left", vl}, {"vcom_right", vr}, {"min_pair_over_dx", mp},
                                {"bodies", nb}, {"momentum_ratio", mom}})},
      {"density_strip", Json::array(strip)},
  });
  std::snprintf(buf, sizeof buf, "%g", 1.0 / dx);
  rubble::verification::write_record(args.records, "rubber_rings-" + args.label + "-" + buf + "-cpu", record, rubble::backend_name(rubble::default_backend()));
  std::filesystem::remove_all(args.out);
  return ok || args.report_only ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main<Args>("rubber_rings_rung: ", argc, argv, run);
}
