// Verification rung: the forces of soil on tools against geotechnical
// theory (issue #54 item 4), from the force each boundary body feels
// (boundary_forces.csv). Two cases, each a scene in this folder:
//
// --case passive (earth_pressure.toml): a smooth vertical wall pushed slowly
// into a layer of Drucker-Prager soil lying on a smooth floor against a
// smooth fixed wall. Once the whole layer yields it is in Rankine's passive
// state, and the force per metre of width on the pushed wall is
//
//   F_R = 1/2 gamma d^2 K_p + 2 c d sqrt(K_p),   K_p = tan^2(45 deg + phi/2)
//
// (Rankine 1857; e.g. UFC 3-220-20 (2025), Foundations and Earth
// Structures, eqs. 4-4 and 4-7). Resolution: particles per depth d / dx.
//
// --case bearing (bearing_capacity.toml): a rough rigid strip footing of
// width B pressed slowly into weightless soil. Its bearing pressure F/B
// reaches the limit of Prandtl (1920) and Reissner (1924),
//
//   q_u = c N_c,  N_c = pi + 2 (phi = 0),  N_c = (N_q - 1) cot(phi),
//   N_q = exp(pi tan phi) tan^2(45 deg + phi/2)
//
// (e.g. Terzaghi & Peck 1967, Soil Mechanics in Engineering Practice, as
// cited by Itasca's FLAC3D verification of the strip footing). Resolution:
// particles per footing width B / dx.
//
// The force (the wall's -force_x; the footing's force_y / B) is averaged
// over the plateau, t >= --plateau-from, and compared with the reference at
// each resolution:
//   - |F / F_ref - 1| <= 10 % at every resolution (issue #54 item 4);
//   - recorded: the plateau's scatter, the observed order of the change of
//     F between resolutions.
// With --quasi-static C each resolution runs again with
// simulation.quasi_static_sound_speed = C (issue #54 item 5): the softened
// run's force within 2 % of the run as given, in at least 5 times fewer
// steps.
//
//   soil_forces_rung --case passive|bearing --scene FILE --resolutions 8,12,16
//                    --records DIR --out DIR --label NAME [--set key=value ...]
//                    [--plateau-from 0.5] [--quasi-static C] [--checks]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "../common/conserved_csv.hpp"
#include "../common/rung.hpp"
#include "rubble/run.hpp"

using rubble::verification::Check;
using rubble::verification::Json;

namespace {

struct Args : rubble::verification::RungArgs {
  double plateau_from = 0.5;
  double quasi_static = 0;  // --quasi-static C: each resolution also run softened to C m/s
  std::string which = "passive";  // --case
  Args()
      : RungArgs({.taken = "--scene --resolutions --records --out --label --set --checks --known-failure --report-only",
                  .out = "earth_pressure_out",
                  .label = "c0",
                  .required = "--scene --resolutions"}) {}
  bool own_option(rubble::verification::ArgReader& r) override {
    return r.value("--plateau-from", plateau_from) || r.value("--quasi-static", quasi_static) ||
           r.value("--case", which);
  }
  void validate() override {
    for (double n : resolutions)
      if (!(n >= 4)) throw std::runtime_error("--resolutions are particles per depth or width, each >= 4");
    if (!(plateau_from > 0)) throw std::runtime_error("--plateau-from must be > 0");
    if (which != "passive" && which != "bearing") throw std::runtime_error("--case must be passive or bearing");
  }
};

struct Result {
  double n = 0, force = 0, scatter = 0, wall_seconds = 0;
  std::size_t particles = 0;
  long long steps = 0;
  std::vector<double> t, f;  // the force over time
};

// One run at n particles per depth (the scene with `sets`): the mean force
// on the pushed wall over the plateau.
// `length`: what the resolution counts particles over (the depth, the
// footing's width); `per_width`: the footing's width B (bearing), else 0.
Result run_one(const Args& args, const rubble::Scene& base, int pushed, double length, double per_width, double n,
               std::vector<std::string> sets, const std::string& tag) {
  for (std::size_t k = 0; k < base.bodies.size(); ++k)
    sets.push_back("bodies." + std::to_string(k) + ".spacing=" + rubble::verification::exact_number(length / n));
  const rubble::Scene scene = rubble::load_scene_file(args.scene, sets);
  const std::filesystem::path out = std::filesystem::path(args.out) / (tag + std::to_string(int(n)));
  const rubble::FinalState fs = rubble::verification::run_into(scene, out);
  const std::string csv = (out / "boundary_forces.csv").string();
  using rubble::verification::read_csv_column;
  const std::vector<double> body = read_csv_column(csv, "body"), t = read_csv_column(csv, "time"),
                            fc = read_csv_column(csv, per_width > 0 ? "force_y" : "force_x");
  Result r;
  r.n = n;
  r.particles = fs.m.size();
  r.wall_seconds = fs.wall_seconds;
  r.steps = static_cast<long long>(fs.steps);
  double sum = 0, sum2 = 0;
  int count = 0;
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (int(body[i]) != pushed) continue;
    // the soil pushes the wall back (-x); it carries the footing (+y), per width
    const double F = per_width > 0 ? fc[i] / per_width : -fc[i];
    if (r.t.empty() || t[i] >= r.t.back() + 0.002) {
      r.t.push_back(t[i]);
      r.f.push_back(F);
    }
    if (t[i] < args.plateau_from) continue;
    sum += F;
    sum2 += F * F;
    ++count;
  }
  if (count < 10) throw std::runtime_error("fewer than 10 rows of boundary_forces.csv in the plateau");
  r.force = sum / count;
  r.scatter = std::sqrt(std::max(0.0, sum2 / count - r.force * r.force));
  return r;
}

int run(const Args& args) {
  const rubble::Scene base = rubble::load_scene_file(args.scene, args.sets);
  const bool bearing = args.which == "bearing";
  const std::size_t expect = bearing ? 3 : 4;
  if (base.bodies.size() != expect)
    throw std::runtime_error(bearing ? "the bearing scene must hold the soil, its container and the footing"
                                     : "the passive scene must hold the soil, the floor and the two walls");
  const rubble::BodyConfig& soil = base.bodies[0];
  const rubble::MaterialConfig& mat = base.materials.at(std::size_t(soil.material_id));
  if (mat.plasticity.model != rubble::PlasticityModel::DruckerPrager)
    throw std::runtime_error("the soil must be a Drucker-Prager material");
  int pushed = -1;
  for (std::size_t k = 0; k < base.bodies.size(); ++k)
    if (base.bodies[k].boundary == rubble::BoundaryKind::Moving) pushed = int(k);
  if (pushed < 0) throw std::runtime_error("no moving wall or footing in the scene");
  const double phi = mat.plasticity.friction_angle * std::numbers::pi / 180, c = mat.plasticity.cohesion;
  const double Kp = std::pow(std::tan(std::numbers::pi / 4 + phi / 2), 2);
  double F_R = 0, length = 0, width = 0;
  const double d = soil.max[1] - soil.min[1], g = -base.simulation.gravity[1], gamma = soil.density * g;
  std::string reference;
  if (bearing) {
    const rubble::BodyConfig& footing = base.bodies[std::size_t(pushed)];
    width = footing.max[0] - footing.min[0];
    length = width;
    if (g != 0) throw std::runtime_error("the bearing case is Prandtl's weightless soil: no simulation.gravity");
    const double Nq = std::exp(std::numbers::pi * std::tan(phi)) * Kp;
    const double Nc = phi > 0 ? (Nq - 1) / std::tan(phi) : std::numbers::pi + 2;
    F_R = c * Nc;
    reference = "Prandtl-Reissner bearing capacity c N_c (Terzaghi & Peck 1967)";
    std::printf("bearing capacity (%s): phi = %.1f deg, c = %g Pa, psi = %.1f deg, B = %g m, N_c = %.4f, q_u = %.2f Pa\n",
                args.label.c_str(), mat.plasticity.friction_angle, c, mat.plasticity.dilatancy_angle, width, Nc, F_R);
  } else {
    length = d;
    F_R = 0.5 * gamma * d * d * Kp + 2 * c * d * std::sqrt(Kp);
    reference = "Rankine passive pressure, UFC 3-220-20 eqs. 4-4, 4-7";
    std::printf("earth pressure (%s): phi = %.1f deg, c = %g Pa, psi = %.1f deg, d = %g m, K_p = %.4f, F_R = %.2f N/m\n",
                args.label.c_str(), mat.plasticity.friction_angle, c, mat.plasticity.dilatancy_angle, d, Kp, F_R);
  }
  if (base.simulation.end_time < args.plateau_from * 1.2)
    throw std::runtime_error("simulation.end_time must reach past --plateau-from");
  const char* unit = bearing ? "Pa" : "N/m";
  const char* per = bearing ? "width" : "depth";

  std::vector<Result> results, softened;
  for (double n : args.resolutions) {
    const Result r = run_one(args, base, pushed, length, width, n, args.sets, "n");
    std::printf("  %3.0f per %s: N = %zu, F = %.2f %s (scatter %.2f), F/F_ref - 1 = %+.4f, %lld steps, wall %.1f s\n", n,
                per, r.particles, r.force, unit, r.scatter, r.force / F_R - 1, r.steps, r.wall_seconds);
    results.push_back(r);
    if (args.quasi_static > 0) {
      std::vector<std::string> sets = args.sets;
      sets.push_back("simulation.quasi_static_sound_speed=" + rubble::verification::exact_number(args.quasi_static));
      const Result q = run_one(args, base, pushed, length, width, n, sets, "q");
      std::printf("      softened to %g m/s: F = %.2f %s (scatter %.2f), F/F - 1 = %+.4f, %lld steps (%.1f x fewer), wall %.1f s\n",
                  args.quasi_static, q.force, unit, q.scatter, q.force / r.force - 1, q.steps, double(r.steps) / double(q.steps),
                  q.wall_seconds);
      softened.push_back(q);
    }
  }

  // the checks of each resolution (its record's), and all of them (the exit status)
  std::vector<std::vector<Check>> per_resolution(results.size());
  std::vector<double> ns, forces, changes;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const Result& r = results[k];
    ns.push_back(r.n);
    forces.push_back(r.force);
    const std::string at = " at " + std::to_string(int(r.n)) + " particles per " + per;
    per_resolution[k].push_back({"|F/F_ref - 1|" + at, std::fabs(r.force / F_R - 1), 0.10, "<=",
                                 bearing ? "issue #54 item 4b: within 10 % of the Prandtl-Reissner bearing capacity"
                                         : "issue #54 item 4a: within 10 % of Rankine's passive force"});
    if (k < softened.size()) {
      const Result& q = softened[k];
      per_resolution[k].push_back({"|F_softened/F - 1|" + at, std::fabs(q.force / r.force - 1), 0.02, "<=",
                                   "issue #54 item 5: the same answer within 2 %"});
      per_resolution[k].push_back({"steps / steps_softened" + at, double(r.steps) / double(q.steps), 5.0, ">=",
                                   "issue #54 item 5: at least 5 times fewer steps"});
    }
  }
  for (std::size_t k = 1; k < results.size(); ++k) changes.push_back(std::fabs(forces[k] - forces[k - 1]) / F_R);
  double order = NAN;
  if (changes.size() >= 2 && changes.front() > 0 && changes.back() > 0) {
    std::vector<double> mid(ns.begin() + 1, ns.end());
    order = rubble::verification::observed_order(mid, changes);
  }
  std::printf("  observed order of the change of F between resolutions: %.2f\n", order);

  // one record per resolution (docs/report-format.md)
  std::vector<Check> checks;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const Result& r = results[k];
    bool all_passed = true;
    const Json judged = rubble::verification::judge_checks(per_resolution[k], all_passed);
    checks.insert(checks.end(), per_resolution[k].begin(), per_resolution[k].end());
    Json soft = Json::object({});
    if (k < softened.size())
      soft = Json::object({{"sound_speed", args.quasi_static},
                           {"force", softened[k].force},
                           {"steps", softened[k].steps},
                           {"wall_seconds", softened[k].wall_seconds}});
    const Json record =
        rubble::verification::record_head("soil_forces", args.label, r.n, std::string("particles per ") + per,
                                          r.particles, 2)
            .with({
                {"setup", args.which},
                {"parameters", Json::object({{"friction_angle", mat.plasticity.friction_angle},
                                             {"cohesion", c},
                                             {"dilatancy_angle", mat.plasticity.dilatancy_angle},
                                             {"depth", d},
                                             {"footing_width", width},
                                             {"unit_weight", gamma},
                                             {"K_p", Kp},
                                             {"plateau_from", args.plateau_from},
                                             {"wall_speed",
                                              std::fabs(base.bodies[std::size_t(pushed)].velocity[bearing ? 1 : 0])}})},
                {"reference", Json::object({{"F_R", F_R}, {"unit", unit}, {"source", reference}})},
                {"force", r.force},
                {"force_scatter", r.scatter},
                {"F_over_ref_minus_1", r.force / F_R - 1},
                {"errors", Json::object({{"F", Json::object({{"rel", std::fabs(r.force / F_R - 1)}})}})},
                {"observed_order_of_change", std::isfinite(order) ? Json(order) : Json()},
                {"softened", soft},
                {"series", Json::object({{"per_depth", r.n}, {"t", r.t}, {"force", r.f}})},
                {"steps", r.steps},
                {"wall_seconds", r.wall_seconds},
                {"checks", judged},
            });
    rubble::verification::write_record(
        args.records,
        "soil-forces-" + args.label + "-" + std::to_string(int(r.n)),
        record, rubble::backend_name(rubble::default_backend()));
  }
  if (!args.keep) std::filesystem::remove_all(args.out);
  return args.exit_status(checks);
}

}  // namespace

int main(int argc, char** argv) {
  return rubble::verification::rung_main<Args>("soil_forces_rung: error: ", argc, argv, run);
}
