// Verification rung: a self-gravitating n = 1 polytrope in hydrostatic
// equilibrium (issue #5 item 5; PHYSICS.md §7, "static self-gravitating
// polytrope"). Runs the scene through the same pipeline as `rubble run`
// (polytrope body generator, SPH + Barnes-Hut self-gravity, leapfrog, a
// damped relaxation for t < simulation.damping_end), then judges the free
// evolution that follows:
//   - the mass-weighted 90 % radius r90 (about the centre of mass) stays
//     within 2 % of its value at the end of the relaxation for 5 dynamical
//     times (issue #5);
//   - the total energy (kinetic + internal + gravitational, conserved.csv)
//     drifts by at most 1 % of |E| over the same time (issue #5).
// Also recorded (not judged): r90 and the density profile against the
// Lane-Emden solution, and the gravitational energy against -3/(5-n) GM^2/R.
//
//   polytrope_rung --scene FILE --records DIR --out DIR [--set key=value ...]
//                  [--dynamical-times 5] [--checks]
//
// The dynamical time is sqrt(R^3 / (G M)) of the polytrope body.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../common/conserved_csv.hpp"
#include "../common/rung.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/reference/lane_emden.hpp"
#include "rubble/run.hpp"

using rubble::verification::Check;
using rubble::verification::Json;

namespace {

struct Args : rubble::verification::RungArgs {
  double dynamical_times = 5;
  Args()
      : RungArgs({.taken = "--scene --records --out --set --checks", .out = "polytrope_out", .required = "--scene"}) {}
  bool own_option(rubble::verification::ArgReader& r) override {
    return r.value("--dynamical-times", dynamical_times);
  }
};

// One snapshot's radial structure about the centre of mass.
struct Shape {
  double t = 0, r90 = 0;
  std::vector<double> r, rho;  // per particle
};

Shape measure(const std::string& path) {
  rubble::ParticleStore<3> ps;
  rubble::SnapshotMeta meta;
  rubble::read_snapshot<3>(path, ps, meta);
  Shape s;
  s.t = meta.time;
  double M = 0, c[3] = {0, 0, 0};
  for (std::size_t i = 0; i < ps.n; ++i) {
    M += ps.m[i];
    for (int k = 0; k < 3; ++k) c[k] += double(ps.m[i]) * double(ps.x[i][k]);
  }
  for (double& ck : c) ck /= M;
  std::vector<std::pair<double, double>> rm(ps.n);
  s.r.resize(ps.n);
  s.rho.resize(ps.n);
  for (std::size_t i = 0; i < ps.n; ++i) {
    double r2 = 0;
    for (int k = 0; k < 3; ++k) r2 += (double(ps.x[i][k]) - c[k]) * (double(ps.x[i][k]) - c[k]);
    rm[i] = {std::sqrt(r2), double(ps.m[i])};
    s.r[i] = rm[i].first;
    s.rho[i] = ps.rho[i];
  }
  // mass-weighted 90 % radius: the radius enclosing 90 % of the mass
  std::sort(rm.begin(), rm.end());
  double acc = 0;
  for (const auto& [r, m] : rm) {
    acc += m;
    if (acc >= 0.9 * M) {
      s.r90 = r;
      break;
    }
  }
  return s;
}

using rubble::verification::ConservedRow;

int run(const Args& args) {
  const rubble::Scene scene = rubble::load_scene_file(args.scene, args.sets);
  if (scene.bodies.size() != 1 || scene.bodies[0].shape != rubble::BodyShape::Polytrope)
    throw std::runtime_error("the scene must hold exactly one polytrope body");
  const rubble::BodyConfig& body = scene.bodies[0];
  const double G = scene.gravity.G;
  const double t_dyn = std::sqrt(body.radius * body.radius * body.radius / (G * body.mass));
  const double t_relax = scene.simulation.damping_end;
  const double t_stop = t_relax + args.dynamical_times * t_dyn;
  if (scene.simulation.end_time < t_stop * (1 - 1e-9))
    throw std::runtime_error("simulation.end_time must reach damping_end + " + std::to_string(args.dynamical_times) +
                             " dynamical times = " + std::to_string(t_stop));
  const rubble::Polytrope model(body.polytropic_index, body.mass, body.radius, G);

  const rubble::FinalState fs = rubble::verification::run_into(scene, args.out);
  std::printf("polytrope: N = %zu, %lld steps, wall %.1f s\n", fs.m.size(), static_cast<long long>(fs.steps),
              fs.wall_seconds);

  // r90 at every snapshot.
  std::vector<Shape> shapes;
  for (const auto& p : rubble::verification::snapshot_files(args.out, scene.output.name))
    shapes.push_back(measure(p.string()));
  if (shapes.empty()) throw std::runtime_error("no snapshots written");
  const double r90_exact = model.radius_of_mass_fraction(0.9);
  const Shape* relaxed = nullptr;
  for (const Shape& s : shapes)
    if (!relaxed && s.t >= t_relax * (1 - 1e-9)) relaxed = &s;
  if (!relaxed) throw std::runtime_error("no snapshot at or after the end of the relaxation");
  double r90_change = 0;
  std::vector<double> ts, r90s;
  for (const Shape& s : shapes) {
    ts.push_back(s.t);
    r90s.push_back(s.r90);
    if (s.t >= relaxed->t && s.t <= t_stop * (1 + 1e-9))
      r90_change = std::max(r90_change, std::fabs(s.r90 - relaxed->r90) / relaxed->r90);
    std::printf("  t %6.3f  r90 %.5f\n", s.t, s.r90);
  }

  // Energy drift after the relaxation.
  const auto rows = rubble::verification::read_conserved_csv((std::filesystem::path(args.out) / "conserved.csv").string());
  const ConservedRow* e0 = nullptr;
  for (const auto& r : rows)
    if (!e0 && r.t >= t_relax * (1 - 1e-9)) e0 = &r;
  if (!e0) throw std::runtime_error("conserved.csv has no row after the relaxation");
  double drift = 0;
  std::vector<double> et, etot, ekin, eint, egrav;
  const std::size_t stride = std::max<std::size_t>(1, rows.size() / 400);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ConservedRow& r = rows[i];
    if (r.t >= e0->t && r.t <= t_stop * (1 + 1e-9)) drift = std::max(drift, std::fabs(r.total - e0->total) / std::fabs(e0->total));
    if (i % stride == 0 || i + 1 == rows.size()) {
      et.push_back(r.t);
      etot.push_back(r.total);
      ekin.push_back(r.kinetic);
      eint.push_back(r.internal);
      egrav.push_back(r.gravitational);
    }
  }

  // Density profile of the last snapshot against Lane-Emden (informative).
  const Shape& last = shapes.back();
  double l1 = 0;
  for (std::size_t i = 0; i < last.r.size(); ++i) l1 += std::fabs(last.rho[i] - model.density(last.r[i]));
  l1 /= double(last.r.size()) * model.rho_c;
  std::vector<double> pr, prho, er, erho;
  const std::size_t pstride = std::max<std::size_t>(1, last.r.size() / 3000);
  for (std::size_t i = 0; i < last.r.size(); i += pstride) {
    pr.push_back(last.r[i]);
    prho.push_back(last.rho[i]);
  }
  for (int k = 0; k <= 400; ++k) {
    const double r = body.radius * k / 400.0;
    er.push_back(r);
    erho.push_back(model.density(r));
  }

  std::printf("r90: relaxed %.5f (Lane-Emden %.5f), largest change over %.3g dynamical times %.3e\n", relaxed->r90,
              r90_exact, args.dynamical_times, r90_change);
  std::printf("energy: E(t_relax) = %.6f (W = %.6f, Lane-Emden W = %.6f), largest drift %.3e\n", e0->total,
              e0->gravitational, model.W, drift);
  std::printf("density profile at t = %.3f: mean |rho - rho_LE| / rho_c = %.3e\n", last.t, l1);

  std::vector<Check> checks;
  if (args.checks) {
    checks.push_back({"largest relative change of r90 over 5 dynamical times after relaxation", r90_change, 0.02, "<=",
                      "issue #5 item 5: radius kept within 2 % for 5 dynamical times"});
    checks.push_back({"largest relative total-energy drift over the same run", drift, 0.01, "<=",
                      "issue #5 item 5: total energy drifts <= 1 %"});
  }
  bool all_passed = true;
  std::vector<Json> cj;
  for (const auto& c : checks) {
    cj.push_back(c.json());
    all_passed = all_passed && c.passed();
    std::printf("  [%s] %s = %.4g (%s %.4g; %s)\n", c.passed() ? "PASS" : "FAIL", c.name.c_str(), c.value,
                c.op.c_str(), c.threshold, c.source.c_str());
  }

  const Json record = rubble::verification::record_head("polytrope",
                                                       "polytrope_n" + std::to_string(int(body.polytropic_index + 0.5)),
                                                       double(fs.m.size()), "N", fs.m.size(), 3).with({
      {"parameters", Json::object({{"polytropic_index", body.polytropic_index},
                                   {"gamma", scene.materials.at(0).gamma},
                                   {"G", G},
                                   {"theta", scene.gravity.theta},
                                   {"order", scene.gravity.order == rubble::MultipoleOrder::Quadrupole ? "quadrupole"
                                                                                                        : "monopole"},
                                   {"damping_time", scene.simulation.damping_time},
                                   {"damping_end", t_relax},
                                   {"t_end", scene.simulation.end_time}})},
      {"errors", Json::object({{"r90", Json::object({{"max_rel_change", r90_change},
                                                     {"rel_vs_lane_emden", std::fabs(relaxed->r90 - r90_exact) / r90_exact}})},
                               {"energy", Json::object({{"max_rel_drift", drift}})},
                               {"rho", Json::object({{"L1_over_rho_c", l1}})}})},
      {"r90_relaxed", relaxed->r90},
      {"r90_lane_emden", r90_exact},
      {"energy_after_relaxation", Json::object({{"total", e0->total},
                                                {"kinetic", e0->kinetic},
                                                {"internal", e0->internal},
                                                {"gravitational", e0->gravitational},
                                                {"gravitational_lane_emden", model.W}})},
      {"dynamical_time", t_dyn},
      {"series", Json::object({{"snapshot_t", ts},
                               {"r90", r90s},
                               {"t", et},
                               {"total", etot},
                               {"kinetic", ekin},
                               {"internal", eint},
                               {"gravitational", egrav}})},
      {"steps", static_cast<long long>(fs.steps)},
      {"wall_seconds", fs.wall_seconds},
      {"checks", Json::array(cj)},
      {"units", Json::object({{"x", "R"}, {"rho", "M/R^3"}})},
      {"profile", Json::object({{"x_label", "r"},
                                {"x", pr},
                                {"rho", prho},
                                {"exact", Json::object({{"x", er}, {"rho", erho}})}})},
  });
  rubble::verification::write_record(args.records, "polytrope-n1-" + std::to_string(fs.m.size()), record, rubble::backend_name(rubble::default_backend()));
  return all_passed ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main<Args>("polytrope_rung: error: ", argc, argv, run);
}
