// Scene parser: TOML text (+ --set overrides) -> a validated Scene with every
// default filled in. This is the only file that knows TOML. Every key is
// documented in docs/scene.md.
//
// Principle 8 ("fail loudly, lose nothing"): anything we do not understand is
// an InputError naming the file, the full key (simulation.end_time,
// materials.gas.gamma, bodies[0].density) and the problem. Nothing is silently
// ignored or silently defaulted to zero.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "rubble/core/error.hpp"
#include "rubble/run.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/layered_body.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "rubble/physics/rigid_body.hpp"

namespace rubble {
namespace {

// ---- small string helpers --------------------------------------------------

std::string join(const std::vector<std::string>& words, const char* sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) out += (i ? sep : "") + words[i];
  return out;
}

std::string fmt(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

std::string trim(std::string_view s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string_view::npos) return {};
  const auto b = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(a, b - a + 1));
}

// Levenshtein distance, for "did you mean ...?" suggestions.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// The candidate closest to `word`, or "" if none is plausibly a typo of it.
std::string closest(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a floating-point number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "nothing";
  }
}

std::string sub(const std::string& path, std::string_view name) {
  return path.empty() ? std::string(name) : path + "." + std::string(name);
}

// [A-Za-z0-9_-]+ : material names and snapshot file stems.
bool is_identifier(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

// ---- --set overrides ----------------------------------------------------------

// A key as --set takes it: bodies[0].spacing -> bodies.0.spacing.
std::string set_form(std::string key) {
  std::string out;
  for (char c : key) {
    if (c == '[') out += '.';
    else if (c != ']') out += c;
  }
  return out;
}

// Apply one "dotted.key=value" override to the TOML tree. Returns the key in
// message form (bodies[0].spacing) so errors about it can say where it came from.
std::string apply_override(toml::table& root, const std::string& text, const std::string& file) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw InputError(file, "", "--set '" + text + "': expected dotted.key=value");
  const std::string key = trim(std::string_view(text).substr(0, eq));
  const std::string value = trim(std::string_view(text).substr(eq + 1));

  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const auto dot = key.find('.', start);
    parts.push_back(trim(std::string_view(key).substr(start, dot - start)));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  for (const auto& p : parts)
    if (p.empty()) throw InputError(file, key, "--set '" + text + "': empty component in the key");
  // Messages write array entries as bodies[0]; --set takes them dotted.
  if (key.find_first_of("[]") != std::string::npos)
    throw InputError(file, key,
                     "--set '" + text + "': keys are dotted, array entries by number: write --set " +
                         set_form(key) + "=" + value);

  // The value is TOML if it parses as TOML (0.5, true, "text", [1, 2],
  // {alpha = 1}); otherwise it is taken as a plain string (hcp, leapfrog).
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    parsed.clear();
  }
  if (parsed.size() != 1 || !parsed.contains("v")) {
    parsed.clear();
    parsed.insert("v", value);
  }

  // Walk (and create) tables; a numeric component indexes an array of tables.
  toml::table* cur = &root;
  std::string shown;  // the path so far, in message form
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const std::string& part = parts[i];
    toml::node* child = cur->get(part);
    if (!child) child = cur->insert(part, toml::table{}).first->second.as_table();
    shown = sub(shown, part);
    if (auto* t = child->as_table()) {
      cur = t;
    } else if (auto* arr = child->as_array()) {
      const bool numeric = i + 2 < parts.size() &&
                           parts[i + 1].find_first_not_of("0123456789") == std::string::npos;
      if (!numeric)
        throw InputError(file, shown,
                         "--set '" + text + "': '" + shown + "' is an array; index an array of tables " +
                             "as in bodies.0.spacing=..., or set the whole array as in " + shown + "=[...]");
      // (more than 9 digits is out of range anyway, and would overflow stoul)
      const std::size_t idx = parts[i + 1].size() > 9 ? arr->size() : std::stoul(parts[i + 1]);
      if (idx >= arr->size())
        throw InputError(file, shown,
                         "--set '" + text + "': index " + parts[i + 1] + " is out of range ('" + shown +
                             "' has " + std::to_string(arr->size()) + " entries)");
      auto* t = (*arr)[idx].as_table();
      if (!t)
        throw InputError(file, shown, "--set '" + text + "': entry " + parts[i + 1] + " is not a table");
      shown += "[" + parts[i + 1] + "]";
      cur = t;
      ++i;
    } else {
      throw InputError(file, shown,
                       "--set '" + text + "': '" + shown + "' is " + type_name(*child) +
                           ", not a table, so it has no key '" + parts[i + 1] + "'");
    }
  }
  cur->insert_or_assign(parts.back(), std::move(*parsed.get("v")));
  return sub(shown, parts.back());
}

// ---- the validating reader --------------------------------------------------------

class SceneReader {
 public:
  SceneReader(std::string file, std::map<std::string, std::string> set_by,
              const std::vector<LibraryText>* embedded = nullptr)
      : file_(std::move(file)), set_by_(std::move(set_by)), embedded_(embedded) {}

  Scene read(const toml::table& root);
  // The library files read() used (Scene::libraries).
  const std::vector<LibraryText>& libraries_read() const { return libraries_read_; }
  // A material file read on its own (`rubble eos`, load_material): the keys
  // of a library file, messages with keys relative to the file.
  MaterialConfig read_library_material(const std::string& name, const toml::table& t);

 private:
  std::string file_;
  std::map<std::string, std::string> set_by_;  // message key -> the --set text that wrote it
  const std::vector<LibraryText>* embedded_;   // library texts to use instead of the disk (restart)
  std::vector<LibraryText> libraries_read_;    // every library file read, as read
  int dim_ = 0;
  // Materials merged from a library file and the scene are copies, which
  // toml++ gives no source position: where each key came from, as text for
  // messages (" (in library file F, line N)" or " (line N)").
  std::map<std::string, std::string> origin_;
  std::set<std::string> from_library_;  // message keys whose value came from a library file
  std::map<std::string, std::string> library_of_;  // "materials.NAME" -> its library file

  // Throw an InputError; where known, say the line or the --set that set the value.
  [[noreturn]] void fail(const std::string& key, std::string problem, const toml::node* where = nullptr) const {
    for (const auto& [k, text] : set_by_)
      if (key == k || key.rfind(k + ".", 0) == 0 || key.rfind(k + "[", 0) == 0) {
        // a suggested key, in the form --set takes
        if (const auto at = problem.find("did you mean '"); at != std::string::npos) {
          const auto from = at + 14, to = problem.find('\'', from);
          if (to != std::string::npos)
            problem.replace(from, to - from, "--set " + set_form(problem.substr(from, to - from)) + "=...");
        }
        problem += " (set by --set " + text + ")";
        throw InputError(file_, key, problem);
      }
    if (const auto o = origin_.find(key); o != origin_.end()) {
      problem += o->second;
      throw InputError(file_, key, problem);
    }
    for (const auto& [material, library_file] : library_of_)
      if (key.rfind(material + ".", 0) == 0) {
        problem += " (" + material + " is library file " + library_file + " plus the scene's overrides)";
        throw InputError(file_, key, problem);
      }
    if (where && where->source().begin.line > 0)
      problem += " (line " + std::to_string(where->source().begin.line) + ")";
    throw InputError(file_, key, problem);
  }

  // Every key of `t` must be in `known`; otherwise name it and suggest the closest.
  void check_keys(const toml::table& t, const std::string& path, const std::vector<std::string>& known) const {
    for (const auto& [k, node] : t) {
      const std::string name(k.str());
      if (std::find(known.begin(), known.end(), name) != known.end()) continue;
      const std::string guess = closest(name, known);
      fail(sub(path, name),
           "unknown key" + (guess.empty() ? "; known keys here: " + join(known)
                                          : " (did you mean '" + sub(path, guess) + "'?)"),
           &node);
    }
  }

  const toml::table* table(const toml::table& t, std::string_view name, const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return nullptr;
    if (!n->is_table()) fail(sub(path, name), "expected a table, got " + type_name(*n), n);
    return n->as_table();
  }

  // A finite number (integers accepted), or nullopt when absent.
  std::optional<double> number(const toml::table& t, std::string_view name, const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return std::nullopt;
    return as_number(*n, sub(path, name), "");
  }

  double as_number(const toml::node& n, const std::string& key, const std::string& entry) const {
    double x = 0;
    if (auto* i = n.as_integer()) x = static_cast<double>(i->get());
    else if (auto* f = n.as_floating_point()) x = f->get();
    else fail(key, entry + "expected a number, got " + type_name(n), &n);
    if (std::isnan(x)) fail(key, entry + "is NaN; every number must be finite (NaN in input data)", &n);
    if (!std::isfinite(x)) fail(key, entry + "is infinite; every number must be finite", &n);
    return x;
  }

  double required_number(const toml::table& t, std::string_view name, const std::string& path,
                         const std::string& what) const {
    const auto x = number(t, name, path);
    if (!x) fail(sub(path, name), "missing required key (" + what + ")");
    return *x;
  }

  // Check a condition on a number already read; `rule` is the condition in words.
  void require(bool ok, const toml::table& t, std::string_view name, const std::string& path, double x,
               const std::string& rule) const {
    if (!ok) fail(sub(path, name), "is " + fmt(x) + ", must be " + rule, t.get(name));
  }

  std::optional<std::int64_t> integer(const toml::table& t, std::string_view name, const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return std::nullopt;
    if (auto* i = n->as_integer()) return i->get();
    // 1e7 is a fine way to write an integer; 2.5 is not.
    if (auto* f = n->as_floating_point()) {
      const double x = f->get();
      if (std::isfinite(x) && x == std::floor(x) && std::fabs(x) < 9.0e18) return static_cast<std::int64_t>(x);
    }
    fail(sub(path, name), "expected an integer, got " + type_name(*n), n);
  }

  std::optional<bool> boolean(const toml::table& t, std::string_view name, const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return std::nullopt;
    if (auto* b = n->as_boolean()) return b->get();
    fail(sub(path, name), "expected true or false, got " + type_name(*n), n);
  }

  std::optional<std::string> string(const toml::table& t, std::string_view name, const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return std::nullopt;
    if (auto* s = n->as_string()) return s->get();
    fail(sub(path, name), "expected a string, got " + type_name(*n), n);
  }

  // A string from a fixed list of choices, mapped to an enum.
  template <class E>
  E choice(const toml::table& t, std::string_view name, const std::string& path, E fallback,
           const std::vector<std::pair<std::string, E>>& options) const {
    std::vector<std::string> names;
    for (const auto& o : options) names.push_back(o.first);
    const toml::node* n = t.get(name);
    if (!n) return fallback;
    if (!n->is_string()) fail(sub(path, name), "expected a string, one of: " + join(names) + "; got " + type_name(*n), n);
    const std::string v = n->as_string()->get();
    for (const auto& o : options)
      if (o.first == v) return o.second;
    const std::string guess = closest(v, names);
    fail(sub(path, name),
         "unknown value '" + v + "'; expected one of: " + join(names) +
             (guess.empty() ? "" : " (did you mean '" + guess + "'?)"),
         n);
  }

  // Exactly D finite numbers (one per axis), or nullopt when absent.
  std::optional<std::array<double, 3>> vector(const toml::table& t, std::string_view name,
                                              const std::string& path) const {
    const toml::node* n = t.get(name);
    if (!n) return std::nullopt;
    const std::string key = sub(path, name);
    const toml::array* arr = n->as_array();
    if (!arr) fail(key, "expected an array of " + std::to_string(dim_) + " numbers, got " + type_name(*n), n);
    check_length(*arr, key, n);
    std::array<double, 3> out{};
    for (int a = 0; a < dim_; ++a) out[a] = as_number((*arr)[a], key, "entry " + std::to_string(a) + " ");
    return out;
  }

  void check_length(const toml::array& arr, const std::string& key, const toml::node* n) const {
    if (arr.size() != static_cast<std::size_t>(dim_))
      fail(key,
           "expected " + std::to_string(dim_) + " entries (one per axis, simulation.dimension = " +
               std::to_string(dim_) + "), got " + std::to_string(arr.size()),
           n);
  }

  void read_simulation(const toml::table& root, SimulationConfig& s);
  MaterialConfig read_material(const std::string& name, const toml::table& t);
  MaterialConfig read_material_table(const std::string& p, const toml::table& t, bool library);
  void read_murnaghan(const toml::table& mt, const std::string& p, MurnaghanParams& c);
  void read_tillotson(const toml::table& mt, const std::string& p, TillotsonParams& c);
  void read_eos_options(const toml::table& t, const std::string& p, EosKind eos, EosLimits& o);
  void read_porosity(const toml::table& q, const std::string& qp, MaterialConfig& m);
  void read_plasticity(const toml::table& q, const std::string& qp, MaterialConfig& m);
  void read_damage(const toml::table& q, const std::string& qp, MaterialConfig& m);
  std::string resolve_library(const std::string& spec, const std::string& key, const toml::node* where) const;
  void record_origins(const toml::table& t, const std::string& prefix, const std::string& library_file);
  BodyConfig read_body(const std::string& path, const toml::table& t, const std::vector<MaterialConfig>& mats);
  void read_rigid_tool(const std::string& p, const toml::table& t, BodyConfig& b) const;
  Region read_region_shape(const std::string& p, const toml::table& t, const std::string& shape) const;
  Region read_region_table(const std::string& p, const toml::table& t, std::vector<std::string> extra = {}) const;
  MeasureRegionConfig read_measure_region(const std::string& p, const toml::table& t, const Scene& scene) const;
  void check_pressure_reachable(const std::string& p, const toml::table& t, const MaterialConfig& m, double rho,
                                double pressure) const;
  void read_domain(const toml::table& t, DomainConfig& d);
  EnergyDepositConfig read_energy_deposit(const std::string& p, const toml::table& t);
  void read_output(const toml::table& t, OutputConfig& o);
  // self-gravity (issue #5)
  void read_gravity(const toml::table& t, GravityConfig& g);
  void read_collision(const toml::table& t, Scene& scene);
  BodyConfig read_polytrope_body(const std::string& p, const toml::table& t, const std::vector<MaterialConfig>& mats);
  BodyConfig read_layered_body(const std::string& p, const toml::table& t, const std::vector<MaterialConfig>& mats);
  // t.material: the index of a [materials] entry (required)
  int material_index(const toml::table& t, const std::string& p, const std::vector<MaterialConfig>& mats) const;
  double G_ = kGravitationalConstantSI;  // [gravity].G, read before the bodies
  bool gravity_on_ = false;
};

int SceneReader::material_index(const toml::table& t, const std::string& p,
                                const std::vector<MaterialConfig>& mats) const {
  const auto material = string(t, "material", p);
  if (!material) fail(p + ".material", "missing required key (the name of a [materials] entry)");
  std::vector<std::string> names;
  for (const auto& m : mats) names.push_back(m.name);
  const auto it = std::find(names.begin(), names.end(), *material);
  if (it == names.end()) {
    const std::string guess = closest(*material, names);
    fail(p + ".material",
         "unknown material '" + *material + "'; defined materials: " + join(names) +
             (guess.empty() ? "" : " (did you mean '" + guess + "'?)"),
         t.get("material"));
  }
  return static_cast<int>(it - names.begin());
}

void SceneReader::read_simulation(const toml::table& root, SimulationConfig& s) {
  const std::string p = "simulation";
  const toml::table* t = table(root, "simulation", "");
  if (!t) fail(p, "missing required table [simulation] (it needs at least dimension and end_time)");
  check_keys(*t, p,
             {"dimension", "end_time", "integrator", "kernel", "density", "hfact", "courant", "force_factor",
              "h_tolerance", "rk2_tolerance", "energy_step_tolerance", "density_step_fraction", "quasi_static_sound_speed", "dt_initial", "dt_min", "max_steps", "damping_time", "damping_end", "damping_frame", "pressure_force",
              "kernel_correction", "stress_update", "xsph", "shifting", "gravity", "allow_overlap"});

  const auto dim = integer(*t, "dimension", p);
  if (!dim) fail(p + ".dimension", "missing required key (1, 2 or 3)");
  if (*dim < 1 || *dim > 3) fail(p + ".dimension", "is " + std::to_string(*dim) + ", must be 1, 2 or 3", t->get("dimension"));
  s.dimension = dim_ = static_cast<int>(*dim);

  s.end_time = required_number(*t, "end_time", p, "the simulated time to run to [s], > 0");
  require(s.end_time > 0, *t, "end_time", p, s.end_time, "> 0");

  s.integrator = choice(*t, "integrator", p, Integrator::RK2Adaptive,
                        {{"rk2_adaptive", Integrator::RK2Adaptive}, {"leapfrog", Integrator::Leapfrog}});
  s.kernel = choice(*t, "kernel", p, KernelType::CubicSpline,
                    {{"cubic_spline", KernelType::CubicSpline},
                     {"wendland_c2", KernelType::WendlandC2},
                     {"wendland_c4", KernelType::WendlandC4},
                     {"wendland_c6", KernelType::WendlandC6}});
  s.density = choice(*t, "density", p, DensityForm::Summation,
                     {{"summation", DensityForm::Summation}, {"continuity", DensityForm::Continuity}});

  if (auto x = number(*t, "hfact", p)) {
    require(*x >= 0, *t, "hfact", p, *x, "> 0 (or 0 for the kernel's default)");
    s.hfact = *x;
  }
  if (auto x = number(*t, "courant", p)) {
    require(*x > 0 && *x <= 1, *t, "courant", p, *x, "in (0, 1]");
    s.courant = *x;
  }
  if (auto x = number(*t, "force_factor", p)) {
    require(*x > 0 && *x <= 1, *t, "force_factor", p, *x, "in (0, 1]");
    s.force_factor = *x;
  }
  if (auto x = number(*t, "h_tolerance", p)) {
    require(*x >= 0 && *x <= 0.01, *t, "h_tolerance", p, *x, "in [0, 0.01] (0 = the default)");
    s.h_tolerance = *x;
  }
  if (auto x = number(*t, "rk2_tolerance", p)) {
    require(*x > 0, *t, "rk2_tolerance", p, *x, "> 0");
    s.rk2_tolerance = *x;
  }
  if (auto x = number(*t, "energy_step_tolerance", p)) {
    require(*x >= 0 && *x <= 1, *t, "energy_step_tolerance", p, *x, "in [0, 1] (0 = off; default courant^2)");
    s.energy_step_tolerance = *x;
  }
  if (auto x = number(*t, "quasi_static_sound_speed", p)) {
    require(*x > 0, *t, "quasi_static_sound_speed", p, *x, "> 0 [m/s] (leave it out for the materials as given)");
    s.quasi_static_sound_speed = *x;
  }
  if (auto x = number(*t, "density_step_fraction", p)) {
    require(*x >= 0 && *x <= 1, *t, "density_step_fraction", p, *x, "in [0, 1] (0 = no limit; default 0.1)");
    s.density_step_fraction = *x;
  }
  if (auto x = number(*t, "dt_initial", p)) {
    require(*x >= 0 && *x <= s.end_time, *t, "dt_initial", p, *x, ">= 0 and <= end_time (0 = automatic)");
    s.dt_initial = *x;
  }
  if (auto x = number(*t, "dt_min", p)) {
    require(*x >= 0 && *x < s.end_time, *t, "dt_min", p, *x, ">= 0 and < end_time (0 = 1e-12 * end_time)");
    s.dt_min = *x;
  }
  if (s.dt_min == 0) s.dt_min = 1e-12 * s.end_time;
  if (auto n = integer(*t, "max_steps", p)) {
    if (*n <= 0) fail(p + ".max_steps", "is " + std::to_string(*n) + ", must be > 0", t->get("max_steps"));
    s.max_steps = *n;
  }
  // Velocity damping (relaxation of initial conditions): both keys or neither.
  const auto damping_time = number(*t, "damping_time", p);
  const auto damping_end = number(*t, "damping_end", p);
  if (damping_time.has_value() != damping_end.has_value())
    fail(damping_time ? p + ".damping_end" : p + ".damping_time",
         "missing; simulation.damping_time and simulation.damping_end go together");
  if (damping_time) {
    require(*damping_time > 0, *t, "damping_time", p, *damping_time, "> 0 (leave both damping keys out for none)");
    require(*damping_end > 0 && *damping_end <= s.end_time, *t, "damping_end", p, *damping_end, "in (0, end_time]");
    s.damping_time = *damping_time;
    s.damping_end = *damping_end;
  }
  s.damping_frame = choice(*t, "damping_frame", p, DampingFrame::Global,
                           {{"global", DampingFrame::Global}, {"body", DampingFrame::Body}});
  s.pressure_force = choice(*t, "pressure_force", p, PressureForce::Standard,
                            {{"standard", PressureForce::Standard}, {"geometric", PressureForce::Geometric}});
  if (auto b = boolean(*t, "kernel_correction", p)) s.kernel_correction = *b;
  s.stress_update = choice(*t, "stress_update", p, StressUpdate::Predicted,
                           {{"predicted", StressUpdate::Predicted}, {"staggered", StressUpdate::Staggered}});
  if (auto x = number(*t, "xsph", p)) {
    require(*x >= 0 && *x <= 1, *t, "xsph", p, *x, "in [0, 1] (0 = off; Monaghan 1989 uses 0.5)");
    s.xsph = *x;
  }
  if (auto x = number(*t, "shifting", p)) {
    require(*x >= 0 && *x <= 10, *t, "shifting", p, *x,
            "in [0, 10] (0 = off; Skillen et al. 2013 use 1-6 for the coefficient A of A h |v| dt)");
    s.shifting = *x;
  }
  // A uniform external acceleration (issue #12): D numbers, m/s^2.
  if (auto g = vector(*t, "gravity", p)) s.gravity = *g;
  if (auto b = boolean(*t, "allow_overlap", p)) s.allow_overlap = *b;
}

// ---- materials (docs/scene.md "Materials"; issue #3) -------------------------

bool ends_with(const std::string& s, std::string_view tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// A file's whole content; an unreadable file is an InputError naming it.
std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file for reading");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "error while reading the file");
  return buf.str();
}

// TOML text as a table; malformed text is an InputError naming `path`.
toml::table parse_toml_text(const std::string& text, const std::string& path) {
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    throw InputError(path, "",
                     "malformed TOML at line " + std::to_string(at.line) + ", column " + std::to_string(at.column) +
                         ": " + std::string(e.description()));
  }
}

// A TOML file as a table; a malformed file is an InputError naming it.
toml::table parse_toml_file(const std::string& path) { return parse_toml_text(read_text_file(path), path); }

// Copy `src` into `dst`, key by key; tables present in both are merged, so
// a scene may override a single parameter (tillotson.A) of a library table.
void merge_tables(toml::table& dst, const toml::table& src) {
  for (const auto& [k, n] : src) {
    toml::node* d = dst.get(k.str());
    if (d && d->is_table() && n.is_table()) merge_tables(*d->as_table(), *n.as_table());
    else dst.insert_or_assign(k.str(), n);
  }
}

// Where each key of `t` (under `prefix`) came from, for messages about the
// merged copy: the library file and line, or the scene line.
void SceneReader::record_origins(const toml::table& t, const std::string& prefix, const std::string& library_file) {
  for (const auto& [k, n] : t) {
    const std::string key = sub(prefix, k.str());
    const auto line = n.source().begin.line;
    const std::string at = line > 0 ? "line " + std::to_string(line) : "";
    if (!library_file.empty()) {
      origin_[key] = " (in library file " + library_file + (at.empty() ? "" : ", " + at) + ")";
      from_library_.insert(key);
    } else {
      origin_[key] = at.empty() ? "" : " (" + at + ")";
      from_library_.erase(key);
    }
    if (const toml::table* inner = n.as_table()) record_origins(*inner, key, library_file);
  }
}

// `library = SPEC`: a name from the library directory, or a file ending in
// .toml (relative to the scene file's folder).
std::string SceneReader::resolve_library(const std::string& spec, const std::string& key,
                                         const toml::node* where) const {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (ends_with(spec, ".toml")) {
    fs::path path(spec);
    if (path.is_relative()) path = fs::path(file_).parent_path() / path;
    if (!fs::is_regular_file(path, ec)) fail(key, "no such material file '" + path.string() + "'", where);
    return path.string();
  }
  if (!is_identifier(spec))
    fail(key, "is '" + spec + "'; expected a library material name (letters, digits, '_', '-') or a file ending in .toml",
         where);
  const std::string dir = materials_directory();
  if (dir.empty())
    fail(key, "no material library directory is known; set the environment variable RUBBLE_MATERIALS", where);
  const fs::path path = fs::path(dir) / (spec + ".toml");
  if (!fs::is_regular_file(path, ec)) {
    const std::vector<std::string> names = library_material_names();
    const std::string guess = closest(spec, names);
    fail(key,
         "unknown library material '" + spec + "'; the library (" + dir + ") has: " +
             (names.empty() ? std::string("nothing") : join(names)) +
             (guess.empty() ? "" : " (did you mean '" + guess + "'?)"),
         where);
  }
  return path.string();
}

void SceneReader::read_murnaghan(const toml::table& mt, const std::string& p, MurnaghanParams& c) {
  const std::string tp = sub(p, "murnaghan");
  const toml::table* t = table(mt, "murnaghan", p);
  if (!t) fail(tp, "missing required table (the Murnaghan parameters: rho0 [kg/m^3], K0 [Pa], n)");
  check_keys(*t, tp, {"rho0", "K0", "n"});
  c.rho0 = required_number(*t, "rho0", tp, "reference density [kg/m^3], > 0");
  c.K0 = required_number(*t, "K0", tp, "zero-pressure bulk modulus [Pa], > 0");
  c.n = required_number(*t, "n", tp, "dimensionless exponent, > 0; n = 1 is the linear law");
  require(c.rho0 > 0, *t, "rho0", tp, c.rho0, "> 0");
  require(c.K0 > 0, *t, "K0", tp, c.K0, "> 0 (a bulk modulus)");
  require(c.n > 0, *t, "n", tp, c.n, "> 0");
}

void SceneReader::read_tillotson(const toml::table& mt, const std::string& p, TillotsonParams& c) {
  const std::string tp = sub(p, "tillotson");
  const toml::table* t = table(mt, "tillotson", p);
  if (!t) fail(tp, "missing required table (the Tillotson parameters: rho0, A, B, E0, E_iv, E_cv, a, b, alpha, beta)");
  check_keys(*t, tp, {"rho0", "A", "B", "E0", "E_iv", "E_cv", "a", "b", "alpha", "beta"});
  c.rho0 = required_number(*t, "rho0", tp, "reference density [kg/m^3], > 0");
  c.A = required_number(*t, "A", tp, "bulk modulus [Pa], > 0");
  c.B = required_number(*t, "B", tp, "nonlinear compression coefficient [Pa], >= 0");
  c.E0 = required_number(*t, "E0", tp, "energy scale E0 [J/kg], > 0");
  c.E_iv = required_number(*t, "E_iv", tp, "specific energy of incipient vaporisation [J/kg], > 0");
  c.E_cv = required_number(*t, "E_cv", tp, "specific energy of complete vaporisation [J/kg], > E_iv");
  c.a = required_number(*t, "a", tp, "dimensionless, >= 0");
  c.b = required_number(*t, "b", tp, "dimensionless, >= 0");
  c.alpha = required_number(*t, "alpha", tp, "dimensionless decay exponent, >= 0");
  c.beta = required_number(*t, "beta", tp, "dimensionless decay exponent, >= 0");
  require(c.rho0 > 0, *t, "rho0", tp, c.rho0, "> 0");
  require(c.A > 0, *t, "A", tp, c.A, "> 0 (the bulk modulus)");
  require(c.B >= 0, *t, "B", tp, c.B, ">= 0 (a modulus)");
  require(c.E0 > 0, *t, "E0", tp, c.E0, "> 0");
  require(c.E_iv > 0, *t, "E_iv", tp, c.E_iv, "> 0");
  if (!(c.E_cv > c.E_iv)) {
    // blame the one the scene changed, if only one came from a library file
    const bool iv_here = !from_library_.count(tp + ".E_iv"), cv_here = !from_library_.count(tp + ".E_cv");
    if (iv_here && !cv_here)
      require(false, *t, "E_iv", tp, c.E_iv,
              "< E_cv (" + fmt(c.E_cv) + "): complete vaporisation takes more energy than incipient vaporisation");
    require(false, *t, "E_cv", tp, c.E_cv,
            "> E_iv (" + fmt(c.E_iv) + "): complete vaporisation takes more energy than incipient vaporisation");
  }
  require(c.a >= 0, *t, "a", tp, c.a, ">= 0");
  require(c.b >= 0, *t, "b", tp, c.b, ">= 0");
  require(c.alpha >= 0, *t, "alpha", tp, c.alpha, ">= 0");
  require(c.beta >= 0, *t, "beta", tp, c.beta, ">= 0");
}

// The add-on options: rho_limit, p_min, cs_min (each off unless given) and
// the Tillotson cs_floor (on unless set to false).
void SceneReader::read_eos_options(const toml::table& t, const std::string& p, EosKind eos, EosLimits& o) {
  if (eos == EosKind::IdealGas && t.contains("rho_limit"))
    fail(sub(p, "rho_limit"), "the ideal gas has no tension cut-off (it needs a reference density: murnaghan or tillotson)",
         t.get("rho_limit"));
  if (auto x = number(t, "rho_limit", p)) {
    require(*x >= 0 && *x <= 1, t, "rho_limit", p, *x,
            "in [0, 1]: the tension cut-off acts below rho/rho0 = rho_limit (0 = off)");
    o.rho_limit = *x;
  }
  if (const toml::node* n = t.get("p_min")) {
    if (const auto* s = n->as_string()) {
      if (s->get() != "none") fail(sub(p, "p_min"), "is '" + s->get() + "'; expected a pressure [Pa] or \"none\"", n);
      o.p_min_enabled = false;
    } else {
      o.p_min = as_number(*n, sub(p, "p_min"), "");
      o.p_min_enabled = true;
    }
  }
  if (auto x = number(t, "cs_min", p)) {
    require(*x >= 0, t, "cs_min", p, *x, ">= 0 (0 = off)");
    o.cs_min = *x;
  }
  if (t.contains("cs_floor") && eos != EosKind::Tillotson)
    fail(sub(p, "cs_floor"), "only the Tillotson EOS has a sound-speed floor (c^2 >= A/rho0); use cs_min for a minimum",
         t.get("cs_floor"));
  if (auto b = boolean(t, "cs_floor", p)) o.cs_floor = *b;
}

// One material table, complete: the EOS and its parameters, the add-ons,
// viscosity and conductivity; `library`: also source and units.
MaterialConfig SceneReader::read_material_table(const std::string& p, const toml::table& t, bool library) {
  MaterialConfig m;
  // The EOS decides which further keys belong here.
  const auto eos = string(t, "eos", p);
  if (!eos) fail(sub(p, "eos"), "missing required key (the equation of state; one of: ideal_gas, murnaghan, tillotson)");
  m.eos = choice(t, "eos", p, EosKind::IdealGas,
                 {{"ideal_gas", EosKind::IdealGas}, {"murnaghan", EosKind::Murnaghan}, {"tillotson", EosKind::Tillotson}});
  // (rho_limit is known to every EOS so that the ideal gas can say why it
  // has no tension cut-off)
  std::vector<std::string> known = {"eos",    "viscosity",     "conductivity",     "rho_limit",
                                    "p_min",  "cs_min",        "cs_floor",         "shear_modulus",
                                    "artificial_stress",             "stress_diffusion",
                                    "porosity", "plasticity", "damage"};
  if (m.eos == EosKind::IdealGas) known.push_back("gamma");
  if (m.eos == EosKind::Murnaghan) known.push_back("murnaghan");
  if (m.eos == EosKind::Tillotson) known.push_back("tillotson");
  if (library) known.insert(known.end(), {"source", "units", "description"});
  check_keys(t, p, known);

  if (library) {
    const auto source = string(t, "source", p);
    if (!source || trim(*source).empty())
      fail(sub(p, "source"), "missing: every library material names the source of its parameters (source = \"...\")",
           t.get("source"));
    m.source = *source;
    m.units = choice(t, "units", p, std::string(), {{"SI", std::string("SI")}, {"dimensionless", std::string("dimensionless")}});
    if (m.units.empty()) fail(sub(p, "units"), "missing: every library material states its units (\"SI\" or \"dimensionless\")");
    string(t, "description", p);  // optional free text; must be a string
  }

  switch (m.eos) {
    case EosKind::IdealGas:
      m.gamma = required_number(t, "gamma", p, "the ideal_gas EOS needs gamma, the adiabatic index, > 1");
      require(m.gamma > 1, t, "gamma", p, m.gamma, "> 1");
      break;
    case EosKind::Murnaghan: read_murnaghan(t, p, m.murnaghan); break;
    case EosKind::Tillotson: read_tillotson(t, p, m.tillotson); break;
  }
  read_eos_options(t, p, m.eos, m.eos_options);

  if (const toml::table* v = table(t, "viscosity", p)) {
    const std::string vp = sub(p, "viscosity");
    check_keys(*v, vp, {"alpha", "beta", "switch", "alpha_min", "decay"});
    if (auto x = number(*v, "alpha", vp)) {
      require(*x >= 0, *v, "alpha", vp, *x, ">= 0");
      m.viscosity.alpha = *x;
    }
    if (auto x = number(*v, "beta", vp)) {
      require(*x >= 0, *v, "beta", vp, *x, ">= 0");
      m.viscosity.beta = *x;
    }
    m.viscosity.switch_on = choice(*v, "switch", vp, false, {{"none", false}, {"morris_monaghan", true}});
    if (auto x = number(*v, "alpha_min", vp)) {
      if (!m.viscosity.switch_on)
        fail(sub(vp, "alpha_min"), "applies only with switch = \"morris_monaghan\"", v->get("alpha_min"));
      require(*x >= 0, *v, "alpha_min", vp, *x, ">= 0");
      m.viscosity.alpha_min = *x;
    }
    if (auto x = number(*v, "decay", vp)) {
      if (!m.viscosity.switch_on)
        fail(sub(vp, "decay"), "applies only with switch = \"morris_monaghan\"", v->get("decay"));
      require(*x > 0 && *x <= 1, *v, "decay", vp, *x, "in (0, 1] (tau = h/(decay c); 0.1 in Price's codes)");
      m.viscosity.decay = *x;
    }
    if (m.viscosity.switch_on && !(m.viscosity.alpha > m.viscosity.alpha_min))
      fail(sub(vp, "alpha"),
           "is " + std::to_string(m.viscosity.alpha) + " with the switch; it is alpha_max and must exceed alpha_min (" +
               std::to_string(m.viscosity.alpha_min) + ")",
           v->get("alpha"));
  }
  if (const toml::table* c = table(t, "conductivity", p)) {
    const std::string cp = sub(p, "conductivity");
    check_keys(*c, cp, {"enabled", "alpha_u"});
    if (auto b = boolean(*c, "enabled", cp)) m.conductivity.enabled = *b;
    if (auto x = number(*c, "alpha_u", cp)) {
      require(*x >= 0, *c, "alpha_u", cp, *x, ">= 0");
      m.conductivity.alpha_u = *x;
    }
  }
  // Strength (issue #4): a shear modulus makes the material an elastic solid.
  if (auto x = number(t, "shear_modulus", p)) {
    require(*x >= 0, t, "shear_modulus", p, *x, ">= 0 (0 = no strength)");
    m.shear_modulus = *x;
  }
  if (const toml::table* a = table(t, "artificial_stress", p)) {
    const std::string ap = sub(p, "artificial_stress");
    check_keys(*a, ap, {"enabled", "epsilon", "n", "form", "clump_onset", "clump_full"});
    m.artificial_stress.enabled = true;  // a table turns it on unless enabled = false
    if (auto b = boolean(*a, "enabled", ap)) m.artificial_stress.enabled = *b;
    if (auto x = number(*a, "epsilon", ap)) {
      require(*x >= 0 && *x <= 1, *a, "epsilon", ap, *x, "in [0, 1] (typically 0.2-0.3)");
      m.artificial_stress.epsilon = *x;
    }
    if (auto x = number(*a, "n", ap)) {
      require(*x > 0 && *x <= 16, *a, "n", ap, *x, "in (0, 16] (typically 4)");
      m.artificial_stress.n = *x;
    }
    // the form (issue #17 item 3): "clumping" (default) acts only where a
    // neighbour has come closer than the local spacing; "monaghan" everywhere
    ArtificialStressConfig& as = m.artificial_stress;
    as.form = choice(*a, "form", ap, ArtificialStressForm::Clumping,
                     {{"clumping", ArtificialStressForm::Clumping}, {"monaghan", ArtificialStressForm::Monaghan}});
    if (as.form == ArtificialStressForm::Monaghan)
      for (const char* k : {"clump_onset", "clump_full"})
        if (a->contains(k)) fail(sub(ap, k), "only the \"clumping\" form has this key (form = \"monaghan\" here)");
    if (auto x = number(*a, "clump_onset", ap)) {
      require(*x > 0 && *x <= 2, *a, "clump_onset", ap, *x, "in (0, 2] (nearest neighbour / local spacing; default 1)");
      as.clump_onset = *x;
    }
    if (auto x = number(*a, "clump_full", ap)) {
      require(*x > 0, *a, "clump_full", ap, *x, "> 0");
      as.clump_full = *x;
    }
    if (!(as.clump_full < as.clump_onset))  // blame the key the scene gave (the other may be the default)
      fail(sub(ap, a->contains("clump_full") ? "clump_full" : "clump_onset"),
           "clump_full = " + fmt(as.clump_full) + " must be below clump_onset = " + fmt(as.clump_onset) +
               " (the weight ramps from 0 at onset to 1 at full; defaults 1.0 and 0.95)");
    if (m.artificial_stress.enabled && !(m.shear_modulus > 0))
      fail(ap, "artificial stress acts on solids only; give the material a shear_modulus > 0 or remove it");
  }
  // deviatoric stress diffusion (physics/stress_diffusion.hpp)
  if (auto x = number(t, "stress_diffusion", p)) {
    require(*x >= 0 && *x <= 1, t, "stress_diffusion", p, *x, "in [0, 1] (Feng et al. 2021 use 0.1; 0 = off)");
    if (*x > 0 && !(m.shear_modulus > 0))
      fail(sub(p, "stress_diffusion"),
           "stress diffusion acts on the deviatoric stress of solids only; give the material a shear_modulus > 0 or "
           "remove it",
           t.get("stress_diffusion"));
    m.stress_diffusion = *x;
  }
  if (const toml::table* q = table(t, "porosity", p)) read_porosity(*q, sub(p, "porosity"), m);
  if (const toml::table* q = table(t, "plasticity", p)) read_plasticity(*q, sub(p, "plasticity"), m);
  if (const toml::table* q = table(t, "damage", p)) read_damage(*q, sub(p, "damage"), m);
  return m;
}

// porosity = { model = "p_alpha", alpha0, p_e, p_s, crush_curve, [p_t, alpha_t, n1, n2], [c_e, c_s0] }
// (issue #11; Jutzi, Benz & Michel 2008; Jutzi et al. 2009; docs/scene.md).
void SceneReader::read_porosity(const toml::table& q, const std::string& qp, MaterialConfig& m) {
  PorosityParams& c = m.porosity;
  const auto model = string(q, "model", qp);
  if (!model) fail(sub(qp, "model"), "missing required key (the porosity model; \"p_alpha\")");
  choice(q, "model", qp, 0, {{"p_alpha", 0}});
  c.curve = choice(q, "crush_curve", qp, CrushCurve::Quadratic,
                         {{"quadratic", CrushCurve::Quadratic}, {"steep", CrushCurve::Steep}});
  std::vector<std::string> known = {"model", "crush_curve", "alpha0", "p_e", "p_s", "c_e", "c_s0",
                                    "deviatoric_rate_factor"};
  if (c.curve == CrushCurve::Steep) known.insert(known.end(), {"p_t", "alpha_t", "n1", "n2"});
  check_keys(q, qp, known);
  if (m.eos == EosKind::IdealGas)
    fail(qp, "a porous material needs a Murnaghan or Tillotson matrix; an ideal gas has no solid matrix to compact",
         q.get("model"));
  c.enabled = true;
  c.alpha_e = required_number(q, "alpha0", qp, "the initial distention alpha0 = rho_s/rho > 1");
  require(c.alpha_e > 1, q, "alpha0", qp, c.alpha_e, "> 1 (alpha = rho_matrix/rho_bulk; 1 is no porosity)");
  c.p_e = required_number(q, "p_e", qp, "the elastic limit [Pa]");
  require(c.p_e >= 0, q, "p_e", qp, c.p_e, ">= 0");
  c.p_s = required_number(q, "p_s", qp, "the full-compaction pressure [Pa]");
  require(c.p_s > c.p_e, q, "p_s", qp, c.p_s, "> p_e = " + fmt(c.p_e) + " (the crush curve runs from p_e to p_s)");
  // J08's factor on a porous solid's deviatoric stress rate (physics/porosity.hpp)
  if (auto b = boolean(q, "deviatoric_rate_factor", qp)) c.deviatoric_rate_factor = *b;
  // The elastic branch (J08 §3.2) needs both sound speeds; a material that
  // gives neither has none: alpha stays alpha0 until p exceeds p_e.
  if (q.contains("c_e") || q.contains("c_s0")) {
    c.c_s0 = required_number(q, "c_s0", qp, "the matrix sound speed [m/s] (c_e is given: the elastic branch needs both)");
    require(c.c_s0 > 0, q, "c_s0", qp, c.c_s0, "> 0");
    c.c_e = required_number(q, "c_e", qp,
                            "the porous elastic sound speed [m/s] (c_s0 is given: the elastic branch needs both)");
    require(c.c_e > 0 && c.c_e < c.c_s0, q, "c_e", qp, c.c_e,
            "> 0 and < c_s0 = " + fmt(c.c_s0) + " (porous material is elastically softer than its matrix)");
  }
  if (c.curve == CrushCurve::Steep) {
    c.p_t = required_number(q, "p_t", qp, "the steep curve's transition pressure [Pa]");
    require(c.p_t > c.p_e && c.p_t < c.p_s, q, "p_t", qp, c.p_t, "between p_e and p_s");
    c.alpha_t = required_number(q, "alpha_t", qp, "the steep curve's distention at p_t");
    require(c.alpha_t > 1 && c.alpha_t < c.alpha_e, q, "alpha_t", qp, c.alpha_t, "> 1 and < alpha0");
    c.n1 = required_number(q, "n1", qp, "the steep curve's first exponent");
    require(c.n1 > 0, q, "n1", qp, c.n1, "> 0");
    c.n2 = required_number(q, "n2", qp, "the steep curve's second exponent");
    require(c.n2 > 0, q, "n2", qp, c.n2, "> 0");
  }  // the quadratic curve (Jutzi 2008 eq. 8) has no exponents to set
}

// plasticity = { model = "von_mises", yield_stress } or
// { model = "drucker_prager", friction_angle, cohesion, dilatancy_angle, cone } (issue #12; docs/scene.md).
void SceneReader::read_plasticity(const toml::table& q, const std::string& qp, MaterialConfig& m) {
  PlasticityConfig& c = m.plasticity;
  const auto model = string(q, "model", qp);
  if (!model) fail(sub(qp, "model"), "missing required key (\"von_mises\", \"drucker_prager\" or \"collins\")");
  c.model = choice(q, "model", qp, PlasticityModel::None,
                   {{"von_mises", PlasticityModel::VonMises},
                    {"drucker_prager", PlasticityModel::DruckerPrager},
                    {"collins", PlasticityModel::Collins}});
  if (c.model == PlasticityModel::VonMises) {
    check_keys(q, qp, {"model", "yield_stress"});
    c.yield_stress = required_number(q, "yield_stress", qp, "the von Mises yield stress Y [Pa]");
    require(c.yield_stress > 0, q, "yield_stress", qp, c.yield_stress, "> 0");
  } else if (c.model == PlasticityModel::Collins) {
    // Collins, Melosh & Ivanov 2004 (physics/plasticity.hpp: collins_yield_strength)
    check_keys(q, qp,
               {"model", "cohesion", "friction_intact", "strength_limit", "cohesion_damaged", "friction_damaged",
                "melt_energy"});
    c.cohesion = required_number(q, "cohesion", qp, "the intact strength Y_0 at zero pressure [Pa]");
    require(c.cohesion >= 0, q, "cohesion", qp, c.cohesion, ">= 0");
    c.friction_intact = required_number(q, "friction_intact", qp, "the intact friction coefficient mu_i");
    require(c.friction_intact >= 0, q, "friction_intact", qp, c.friction_intact, ">= 0");
    c.strength_limit =
        required_number(q, "strength_limit", qp, "the limiting strength Y_M of intact rock at high pressure [Pa]");
    require(c.strength_limit > c.cohesion, q, "strength_limit", qp, c.strength_limit,
            "> cohesion = " + fmt(c.cohesion) + " (the Lundborg curve rises from Y_0 to Y_M)");
    c.friction_damaged = required_number(q, "friction_damaged", qp, "the damaged friction coefficient mu_d");
    require(c.friction_damaged >= 0, q, "friction_damaged", qp, c.friction_damaged, ">= 0");
    if (auto x = number(q, "cohesion_damaged", qp)) {
      require(*x >= 0 && *x <= c.cohesion, q, "cohesion_damaged", qp, *x,
              "in [0, cohesion = " + fmt(c.cohesion) + "] (damaged rock is no stronger than intact rock)");
      c.cohesion_damaged = *x;
    }
    if (auto x = number(q, "melt_energy", qp)) {
      require(*x > 0, q, "melt_energy", qp, *x, "> 0 [J/kg] (leave it out for no thermal softening)");
      c.melt_energy = *x;
    }
    if (c.cohesion == 0 && c.friction_intact == 0)
      fail(sub(qp, "cohesion"), "is 0 with friction_intact = 0: the material would have no strength at all");
  } else {
    check_keys(q, qp, {"model", "friction_angle", "cohesion", "dilatancy_angle", "cone"});
    c.friction_angle = required_number(q, "friction_angle", qp, "the friction angle phi [degrees]");
    require(c.friction_angle >= 0 && c.friction_angle < 90, q, "friction_angle", qp, c.friction_angle,
            "in [0, 90) degrees");
    c.cohesion = required_number(q, "cohesion", qp, "the cohesion c [Pa] (0 for dry sand)");
    require(c.cohesion >= 0, q, "cohesion", qp, c.cohesion, ">= 0");
    if (c.friction_angle == 0 && c.cohesion == 0)
      fail(sub(qp, "cohesion"), "is 0 with friction_angle = 0: the material would have no strength at all");
    if (auto x = number(q, "dilatancy_angle", qp)) {
      require(*x >= 0 && *x <= c.friction_angle, q, "dilatancy_angle", qp, *x,
              "in [0, friction_angle = " + fmt(c.friction_angle) + "] degrees (psi > phi is unphysical)");
      c.dilatancy_angle = *x;
    }
    c.cone = choice(q, "cone", qp, DpConeFit::PlaneStrain,
                    {{"plane_strain", DpConeFit::PlaneStrain},
                     {"compression", DpConeFit::Compression},
                     {"extension", DpConeFit::Extension}});
  }
  if (!(m.shear_modulus > 0))
    fail(qp, "plasticity acts on solids only; give the material a shear_modulus > 0 (a fluid has no deviatoric stress)");
}

// damage = { model = "grady_kipp", weibull_k, weibull_m, crack_speed, deviatoric, seed,
//            min_flaws_per_particle, cap, crack_length }
// (issue #18; Benz & Asphaug 1994, 1995; docs/scene.md).
void SceneReader::read_damage(const toml::table& q, const std::string& qp, MaterialConfig& m) {
  DamageConfig& c = m.damage;
  const auto model = string(q, "model", qp);
  if (!model) fail(sub(qp, "model"), "missing required key (the damage model; \"grady_kipp\")");
  choice(q, "model", qp, 0, {{"grady_kipp", 0}});
  check_keys(q, qp,
             {"model", "weibull_k", "weibull_m", "crack_speed", "deviatoric", "seed", "min_flaws_per_particle", "cap",
              "crack_length"});
  c.enabled = true;
  c.weibull_k = required_number(q, "weibull_k", qp, "the Weibull coefficient k [m^-3] of n(eps) = k eps^m");
  require(c.weibull_k > 0, q, "weibull_k", qp, c.weibull_k, "> 0 [m^-3]");
  c.weibull_m = required_number(q, "weibull_m", qp, "the Weibull exponent m of n(eps) = k eps^m");
  require(c.weibull_m > 0, q, "weibull_m", qp, c.weibull_m, "> 0 (rocks: 6-12)");
  if (auto x = number(q, "crack_speed", qp)) {
    require(*x > 0 && *x <= 1, q, "crack_speed", qp, *x,
            "in (0, 1] (the crack speed as a fraction of the longitudinal sound speed; 0.4 in Benz & Asphaug 1994)");
    c.crack_speed = *x;
  }
  // Collins strength weakens damaged rock through its yield surface (Y falls
  // from Y_i to Y_d as D grows); scaling the deviator by 1 - D as well would
  // count the damage twice (miluphcuda refuses DAMAGE_ACTS_ON_S with it).
  const bool collins = m.plasticity.model == PlasticityModel::Collins;
  c.deviatoric = !collins;
  if (auto b = boolean(q, "deviatoric", qp)) {
    if (*b && collins)
      fail(sub(qp, "deviatoric"),
           "is true, but the material's plasticity is \"collins\", whose yield surface already weakens damaged "
           "rock (Collins et al. 2004); leave deviatoric out (it defaults to false there)",
           q.get("deviatoric"));
    c.deviatoric = *b;
  }
  if (auto n = integer(q, "seed", qp)) {
    if (*n < 0) fail(sub(qp, "seed"), "is " + std::to_string(*n) + ", must be >= 0", q.get("seed"));
    c.seed = *n;
  }
  if (auto n = integer(q, "min_flaws_per_particle", qp)) {
    // The draw costs about N (M + ln N) random numbers for N particles.
    constexpr std::int64_t kMaxFlawsPerParticle = 1000000;
    if (*n < 1 || *n > kMaxFlawsPerParticle)
      fail(sub(qp, "min_flaws_per_particle"),
           "is " + std::to_string(*n) + ", must be in [1, " + std::to_string(kMaxFlawsPerParticle) +
               "] (the flaw draw costs about N times this many random numbers)",
           q.get("min_flaws_per_particle"));
    c.min_flaws_per_particle = std::int32_t(*n);
  }
  c.capped = choice(q, "cap", qp, true, {{"active_fraction", true}, {"none", false}});
  c.crack_length = choice(q, "crack_length", qp, CrackLength::ParticleRadius,
                          {{"particle_radius", CrackLength::ParticleRadius},
                           {"kernel_support", CrackLength::KernelSupport}});
  if (!(m.shear_modulus > 0))
    fail(qp, "damage acts on solids only; give the material a shear_modulus > 0 (a fluid carries no tension to break)");
}

MaterialConfig SceneReader::read_library_material(const std::string& name, const toml::table& t) {
  MaterialConfig m = read_material_table("", t, true);
  m.name = m.library = name;
  m.library_file = file_;
  return m;
}

// A scene material: inline (every parameter here), or `library = "NAME"`
// plus single keys overriding the library file's.
MaterialConfig SceneReader::read_material(const std::string& name, const toml::table& t) {
  const std::string p = "materials." + name;
  if (!is_identifier(name)) fail(p, "material names may contain only letters, digits, '_' and '-'");
  for (const char* k : {"source", "units", "description"})
    if (t.contains(k))
      fail(sub(p, k),
           std::string("only library files carry '") + k +
               "'; a scene material names its library file with library = \"NAME\" (docs/scene.md)",
           t.get(k));

  const auto spec = string(t, "library", p);
  if (!spec) {
    MaterialConfig m = read_material_table(p, t, false);
    m.name = name;
    return m;
  }
  LibraryText lib;
  lib.spec = *spec;
  if (embedded_) {  // a resumed run: the library as the run first read it
    const auto it = std::find_if(embedded_->begin(), embedded_->end(),
                                 [&](const LibraryText& l) { return l.spec == *spec; });
    if (it == embedded_->end())
      fail(sub(p, "library"), "library material '" + *spec + "' is not among those the snapshot carries", t.get("library"));
    lib = *it;
  } else {
    lib.path = resolve_library(*spec, sub(p, "library"), t.get("library"));
    lib.text = read_text_file(lib.path);
  }
  const std::string path = lib.path;
  toml::table merged = parse_toml_text(lib.text, path);
  if (std::none_of(libraries_read_.begin(), libraries_read_.end(),
                   [&](const LibraryText& l) { return l.spec == lib.spec; }))
    libraries_read_.push_back(lib);
  library_of_[p] = path;
  if (merged.contains("library"))
    throw InputError(path, "library", "a library file cannot itself refer to a library material");
  record_origins(merged, p, path);
  if (const toml::node* e = t.get("eos"); e && merged.contains("eos") && e->is_string() && merged.get("eos")->is_string() &&
                                          e->as_string()->get() != merged.get("eos")->as_string()->get())
    fail(sub(p, "eos"),
         "is '" + e->as_string()->get() + "', but library material '" + *spec + "' is '" +
             merged.get("eos")->as_string()->get() +
             "'; a scene may override parameters, not the equation of state (define the material inline instead)",
         e);
  toml::table scene_part = t;
  scene_part.erase("library");
  record_origins(t, p, "");
  merge_tables(merged, scene_part);

  MaterialConfig m = read_material_table(p, merged, true);
  m.name = name;
  m.library = *spec;
  m.library_file = path;
  return m;
}

// A body given as pressure needs the u that gives it (initial_conditions.cpp
// inverts the EOS); find out now, before any output, whether there is one.
void SceneReader::check_pressure_reachable(const std::string& p, const toml::table& t, const MaterialConfig& m,
                                           double rho, double pressure) const {
  const EosParams e = eos_params_from_material(m);
  // porous: the matrix carries p_s = alpha0 p at rho_s = alpha0 rho
  const double a0 = m.porosity.enabled ? m.porosity.alpha_e : 1.0;
  if (eos_internal_energy_from_pressure(e, Real(a0 * rho), Real(a0 * pressure)) >= 0) return;
  const std::string key = sub(p, "pressure");
  if (m.eos == EosKind::Murnaghan) {
    const MurnaghanParams& c = m.murnaghan;
    const double base = 1 + c.n * pressure / c.K0;
    fail(key,
         "material '" + m.name + "' uses the Murnaghan EOS, which is isothermal: the pressure follows from the density (" +
             fmt(eos_evaluate(e, Real(rho), Real(0)).p) + " Pa at density " + fmt(rho) +
             "). Give internal_energy instead" +
             (base > 0 ? ", or density = " + fmt(c.rho0 * std::pow(base, 1 / c.n)) + " for this pressure" : std::string()),
         t.get("pressure"));
  }
  fail(key,
       "no internal energy u >= 0 gives this pressure at density " + fmt(rho) + " with material '" + m.name +
           "' (at u = 0 the pressure is already " + fmt(eos_evaluate(e, Real(rho), Real(0)).p) +
           " Pa); give internal_energy instead, or a lower density",
       t.get("pressure"));
}

// The shapes a region (a lattice body's shape, an entry of its `add` or
// `subtract`, a [[regions]] entry) can take, and each one's keys.
bool is_region_shape(const std::string& s) {
  return s == "box" || s == "sphere" || s == "ring" || s == "polygon" || s == "cylinder";
}
std::vector<const char*> region_keys(const std::string& s) {
  if (s == "box") return {"min", "max"};
  if (s == "sphere") return {"center", "radius"};
  if (s == "ring") return {"center", "radius", "inner_radius"};
  if (s == "cylinder") return {"center", "radius", "length", "axis"};
  if (s == "polygon") return {"vertices"};
  return {};
}

// A region's geometric keys from table t at path p (core/region.hpp).
Region SceneReader::read_region_shape(const std::string& p, const toml::table& t, const std::string& shape) const {
  Region r;
  if (shape == "box") {
    r.shape = RegionShape::Box;
    const auto lo = vector(t, "min", p);
    if (!lo) fail(p + ".min", "missing required key (the box's lower corner, " + std::to_string(dim_) + " numbers [m])");
    const auto hi = vector(t, "max", p);
    if (!hi) fail(p + ".max", "missing required key (the box's upper corner, " + std::to_string(dim_) + " numbers [m])");
    for (int a = 0; a < dim_; ++a)
      if (!((*hi)[a] > (*lo)[a]))
        fail(p + ".max",
             "entry " + std::to_string(a) + " is " + fmt((*hi)[a]) + ", must be > min (" + fmt((*lo)[a]) + ")",
             t.get("max"));
    for (int a = 0; a < 3; ++a) {
      r.min[a] = (*lo)[a];
      r.max[a] = (*hi)[a];
    }
    return r;
  }
  if (shape == "polygon") {
    if (dim_ != 2) fail(p + ".shape", "a polygon is a 2-D shape (use a box, sphere or cylinder in 3-D)", t.get("shape"));
    r.shape = RegionShape::Polygon;
    const toml::node* n = t.get("vertices");
    if (!n) fail(p + ".vertices", "missing required key (the polygon's corners in order, [[x0, y0], [x1, y1], ...] [m])");
    const toml::array* arr = n->as_array();
    if (!arr || arr->size() < 3 || arr->size() > std::size_t(kMaxPolygonVertices))
      fail(p + ".vertices", "expected an array of 3 to " + std::to_string(kMaxPolygonVertices) + " points [x, y]", n);
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::array* v = (*arr)[i].as_array();
      const std::string key = p + ".vertices";
      if (!v || v->size() != 2) fail(key, "entry " + std::to_string(i) + ": expected a point [x, y]", n);
      for (int a = 0; a < 2; ++a) r.vertices[i][a] = as_number((*v)[std::size_t(a)], key, "point " + std::to_string(i) + " ");
    }
    r.vertex_count = int(arr->size());
    double area2 = 0;  // twice the signed area (shoelace)
    for (int i = 0, j = r.vertex_count - 1; i < r.vertex_count; j = i++)
      area2 += r.vertices[j][0] * r.vertices[i][1] - r.vertices[i][0] * r.vertices[j][1];
    if (!(std::fabs(area2) > 0)) fail(p + ".vertices", "the polygon encloses no area", n);
    region_bounds<2>(r);
    return r;
  }
  // round shapes
  r.shape = shape == "sphere" ? RegionShape::Sphere : shape == "ring" ? RegionShape::Ring : RegionShape::Cylinder;
  if (r.shape == RegionShape::Cylinder && dim_ != 3)
    fail(p + ".shape", "a cylinder is a 3-D shape (in 2-D a box is its section)", t.get("shape"));
  const auto c = vector(t, "center", p);
  if (!c) fail(p + ".center", "missing required key (the centre, " + std::to_string(dim_) + " numbers [m])");
  for (int a = 0; a < 3; ++a) r.center[a] = (*c)[a];
  r.radius = required_number(t, "radius", p, "the outer radius [m], > 0");
  require(r.radius > 0, t, "radius", p, r.radius, "> 0");
  if (r.shape == RegionShape::Ring) {
    r.inner_radius = required_number(t, "inner_radius", p, "the inner radius [m], >= 0 and < radius");
    require(r.inner_radius >= 0 && r.inner_radius < r.radius, t, "inner_radius", p, r.inner_radius, ">= 0 and < radius");
  }
  if (r.shape == RegionShape::Cylinder) {
    r.length = required_number(t, "length", p, "the cylinder's length along its axis [m], > 0");
    require(r.length > 0, t, "length", p, r.length, "> 0");
    if (auto ax = vector(t, "axis", p)) {
      const double len = std::sqrt((*ax)[0] * (*ax)[0] + (*ax)[1] * (*ax)[1] + (*ax)[2] * (*ax)[2]);
      if (!(len > 0)) fail(p + ".axis", "is the zero vector; give the cylinder's axis direction", t.get("axis"));
      for (int a = 0; a < 3; ++a) r.axis[a] = (*ax)[a] / len;
    }
  }
  if (dim_ == 3) region_bounds<3>(r);
  else if (dim_ == 2) region_bounds<2>(r);
  else region_bounds<1>(r);
  return r;
}

// An inline shape table { shape = "...", ... } (add, subtract, [[regions]]).
Region SceneReader::read_region_table(const std::string& p, const toml::table& t, std::vector<std::string> extra) const {
  const auto shape = string(t, "shape", p);
  if (!shape) fail(p + ".shape", "missing required key (one of: box, sphere, ring, polygon, cylinder)");
  if (!is_region_shape(*shape))
    fail(p + ".shape", "unknown shape '" + *shape + "'; expected one of: box, sphere, ring, polygon, cylinder", t.get("shape"));
  extra.push_back("shape");
  for (const char* k : region_keys(*shape)) extra.push_back(k);
  check_keys(t, p, extra);
  return read_region_shape(p, t, *shape);
}

// A [[regions]] entry: a name, a shape, and optionally the rigid tool it
// follows (regions.csv, docs/user-guide.md).
MeasureRegionConfig SceneReader::read_measure_region(const std::string& p, const toml::table& t, const Scene& scene) const {
  MeasureRegionConfig m;
  m.region = read_region_table(p, t, {"name", "follow"});
  const auto name = string(t, "name", p);
  if (!name) fail(p + ".name", "missing required key (the region's name in regions.csv, e.g. \"tray\")");
  if (name->empty() || name->find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
                           std::string::npos)
    fail(p + ".name", "'" + *name + "' must be letters, digits, '_' or '-' (it is a CSV field)", t.get("name"));
  for (const MeasureRegionConfig& other : scene.regions)
    if (other.name == *name) fail(p + ".name", "'" + *name + "' names an earlier region too", t.get("name"));
  m.name = *name;
  if (const toml::node* f = t.get("follow")) {
    const auto* v = f->as_integer();
    if (!v) fail(p + ".follow", "expected the index of a rigid-tool body (an integer), got " + type_name(*f), f);
    const std::int64_t k = v->get();
    if (k < 0 || std::size_t(k) >= scene.bodies.size() || !scene.bodies[std::size_t(k)].rigid_tool())
      fail(p + ".follow", "is " + std::to_string(k) + ", not the index of a rigid tool (a body with boundary = \"driven\", "
                          "or \"moving\" with an angular_velocity)", f);
    m.follow = int(k);
  }
  return m;
}

// A rigid tool's keys (physics/rigid_body.hpp; docs/scene.md): after
// `boundary` and the shape, so the default rotation centre is known.
void SceneReader::read_rigid_tool(const std::string& p, const toml::table& t, BodyConfig& b) const {
  const bool moving = b.boundary == BoundaryKind::Moving, driven = b.boundary == BoundaryKind::Driven;
  if (auto w = number(t, "angular_velocity", p)) {
    if (!(moving || driven))
      fail(p + ".angular_velocity", "only a boundary = \"moving\" or \"driven\" body turns as a rigid tool",
           t.get("angular_velocity"));
    if (dim_ == 1) fail(p + ".angular_velocity", "nothing turns in 1-D", t.get("angular_velocity"));
    b.angular_velocity = *w;
  }
  if (moving && b.angular_velocity != 0 && t.contains("velocity_gradient"))
    fail(p + ".velocity_gradient",
         "a turning tool moves rigidly (velocity and angular_velocity); velocity_gradient is for grips that stretch",
         t.get("velocity_gradient"));
  if (driven && t.contains("velocity_gradient"))
    fail(p + ".velocity_gradient", "a driven tool moves rigidly; give its initial velocity and angular_velocity",
         t.get("velocity_gradient"));
  const bool tool = b.rigid_tool();
  for (const char* key : {"rotation_axis", "rotation_center"})
    if (t.contains(key) && !tool)
      fail(p + "." + key,
           "only a rigid tool turns (boundary = \"moving\" with a non-zero angular_velocity, or \"driven\")",
           t.get(key));
  for (const char* key : {"applied_force", "applied_torque", "driven_axes", "driven_rotation", "tool_mass", "tool_inertia"})
    if (t.contains(key) && !driven)
      fail(p + "." + key, "only a driven tool (boundary = \"driven\") responds to forces", t.get(key));
  if (!tool) return;
  if (dim_ != 3 && t.contains("rotation_axis"))
    fail(p + ".rotation_axis", "a 2-D tool turns about z; rotation_axis is for 3-D scenes", t.get("rotation_axis"));
  if (auto n = vector(t, "rotation_axis", p)) {
    const double len = std::sqrt((*n)[0] * (*n)[0] + (*n)[1] * (*n)[1] + (*n)[2] * (*n)[2]);
    if (!(len > 0)) fail(p + ".rotation_axis", "is the zero vector; give the axis' direction", t.get("rotation_axis"));
    for (int a = 0; a < 3; ++a) b.rotation_axis[a] = (*n)[a] / len;
  }
  if (auto c = vector(t, "rotation_center", p)) {
    if (driven)
      fail(p + ".rotation_center", "a driven tool turns about its centre of mass; rotation_center is for boundary = \"moving\"",
           t.get("rotation_center"));
    b.rotation_center = *c;
  } else {
    for (int a = 0; a < 3; ++a) b.rotation_center[a] = b.shape == BodyShape::Box ? 0.5 * (b.min[a] + b.max[a]) : b.center[a];
  }
  if (!driven) return;
  if (auto f = vector(t, "applied_force", p)) b.applied_force = *f;
  if (auto q = number(t, "applied_torque", p)) {
    if (dim_ == 1) fail(p + ".applied_torque", "nothing turns in 1-D", t.get("applied_torque"));
    b.applied_torque = *q;
  }
  if (const toml::node* n = t.get("driven_axes")) {
    const toml::array* arr = n->as_array();
    if (!arr) fail(p + ".driven_axes", "expected an array of " + std::to_string(dim_) + " booleans, got " + type_name(*n), n);
    check_length(*arr, p + ".driven_axes", n);
    for (int a = 0; a < dim_; ++a) {
      const auto* v = (*arr)[std::size_t(a)].as_boolean();
      if (!v) fail(p + ".driven_axes", "entry " + std::to_string(a) + ": expected true or false", n);
      b.driven_axes[a] = v->get();
    }
  }
  if (auto r = boolean(t, "driven_rotation", p)) {
    if (dim_ == 1 && *r) fail(p + ".driven_rotation", "nothing turns in 1-D", t.get("driven_rotation"));
    b.driven_rotation = *r;
  }
  if (dim_ == 1) b.driven_rotation = false;
  if (auto m = number(t, "tool_mass", p)) {
    require(*m > 0, t, "tool_mass", p, *m, "> 0 (leave it out for the mass of the tool's particles)");
    b.tool_mass = *m;
  }
  if (auto I = number(t, "tool_inertia", p)) {
    require(*I > 0, t, "tool_inertia", p, *I, "> 0 (leave it out for the moment of inertia of the tool's particles)");
    b.tool_inertia = *I;
  }
}

BodyConfig SceneReader::read_body(const std::string& p, const toml::table& t,
                                  const std::vector<MaterialConfig>& mats) {
  BodyConfig b;
  if (const toml::node* s = t.get("shape"); s && s->is_string() && s->as_string()->get() == "polytrope")
    return read_polytrope_body(p, t, mats);
  if (const toml::node* s = t.get("shape"); s && s->is_string() && s->as_string()->get() == "layered")
    return read_layered_body(p, t, mats);
  const auto shape = string(t, "shape", p);
  if (!shape) fail(p + ".shape", "missing required key (one of: box, sphere, ring, polygon, cylinder, polytrope, layered)");
  if (!is_region_shape(*shape))
    fail(p + ".shape", "unknown shape '" + *shape + "'; expected one of: box, sphere, ring, polygon, cylinder, polytrope, layered",
         t.get("shape"));
  std::vector<std::string> known = {"shape", "material", "spacing", "lattice", "density", "pressure", "internal_energy",
                                    "velocity", "velocity_gradient", "boundary", "boundary_state", "wall_slip", "wall_friction",
                                    "wall_normal", "angular_velocity", "rotation_axis", "rotation_center", "applied_force",
                                    "applied_torque", "driven_axes", "driven_rotation", "tool_mass", "tool_inertia", "add",
                                    "subtract"};
  for (const char* k : region_keys(*shape)) known.push_back(k);
  check_keys(t, p, known);

  b.material_id = material_index(t, p, mats);
  b.material = mats[std::size_t(b.material_id)].name;

  b.region = read_region_shape(p, t, *shape);
  b.shape = *shape == "sphere"     ? BodyShape::Sphere
            : *shape == "ring"     ? BodyShape::Ring
            : *shape == "polygon"  ? BodyShape::Polygon
            : *shape == "cylinder" ? BodyShape::Cylinder
                                   : BodyShape::Box;
  for (int a = 0; a < 3; ++a) {
    b.min[a] = a < dim_ ? b.region.min[a] : 0;
    b.max[a] = a < dim_ ? b.region.max[a] : 0;
    b.center[a] = b.region.center[a];
  }
  b.radius = b.region.radius;
  b.inner_radius = b.region.inner_radius;
  // Composed shapes: one lattice over the shape, the regions added, less the
  // regions cut out (a bed with a tool's place left empty, a container).
  for (const char* list : {"add", "subtract"}) {
    const toml::node* n = t.get(list);
    if (!n) continue;
    const toml::array* arr = n->as_array();
    if (!arr || arr->empty())
      fail(p + "." + list, std::string("expected a non-empty array of shape tables, e.g. ") + list +
                               " = [{ shape = \"box\", min = [...], max = [...] }]", n);
    for (std::size_t k = 0; k < arr->size(); ++k) {
      const std::string q = p + "." + list + "[" + std::to_string(k) + "]";
      const toml::table* e = (*arr)[k].as_table();
      if (!e) fail(q, "expected a table { shape = ..., ... }", &(*arr)[k]);
      (std::string(list) == "add" ? b.add : b.subtract).push_back(read_region_table(q, *e));
    }
  }

  b.spacing = required_number(t, "spacing", p, "the lattice spacing [m], > 0");
  require(b.spacing > 0, t, "spacing", p, b.spacing, "> 0");
  // Guard against a typo asking for an absurd number of particles.
  double count = 1;
  for (int a = 0; a < dim_; ++a) count *= std::ceil((b.max[a] - b.min[a]) / b.spacing);
  if (count > 1e10)
    fail(p + ".spacing", "gives about " + fmt(count) + " particles (more than 1e10); is the spacing a typo?",
         t.get("spacing"));

  b.lattice = choice(t, "lattice", p, Lattice::Cubic,
                     {{"cubic", Lattice::Cubic}, {"hcp", Lattice::HexagonalClosePacked}});
  if (b.lattice == Lattice::HexagonalClosePacked && dim_ == 1)
    fail(p + ".lattice", "'hcp' needs simulation.dimension 2 or 3 (in 1-D use 'cubic')", t.get("lattice"));

  b.density = required_number(t, "density", p, "the initial density [kg/m^3], > 0");
  require(b.density > 0, t, "density", p, b.density, "> 0");

  // The thermal state: exactly one of pressure and internal energy.
  const auto pressure = number(t, "pressure", p);
  const auto energy = number(t, "internal_energy", p);
  if (pressure && energy)
    fail(p, "both 'pressure' and 'internal_energy' are given; give exactly one", t.get("internal_energy"));
  if (!pressure && !energy)
    fail(p, "neither 'pressure' [Pa] nor 'internal_energy' [J/kg] is given; give exactly one");
  if (pressure) {
    require(*pressure >= 0, t, "pressure", p, *pressure, ">= 0");
    b.pressure = *pressure;
    check_pressure_reachable(p, t, mats[b.material_id], b.density, *pressure);
  } else {
    require(*energy >= 0, t, "internal_energy", p, *energy, ">= 0");
    b.internal_energy = *energy;
  }

  if (auto v = vector(t, "velocity", p)) b.velocity = *v;
  if (const toml::node* n = t.get("velocity_gradient")) {
    const std::string key = sub(p, "velocity_gradient");
    const toml::array* rows = n->as_array();
    if (!rows) fail(key, "expected an array of " + std::to_string(dim_) + " rows of " + std::to_string(dim_) +
                             " numbers [1/s], got " + type_name(*n), n);
    check_length(*rows, key, n);
    for (int r = 0; r < dim_; ++r) {
      const toml::node& row = (*rows)[std::size_t(r)];
      const toml::array* cols = row.as_array();
      if (!cols) fail(key, "row " + std::to_string(r) + ": expected an array of " + std::to_string(dim_) + " numbers", &row);
      check_length(*cols, key, &row);
      for (int c = 0; c < dim_; ++c)
        b.velocity_gradient[r][c] = as_number((*cols)[std::size_t(c)], key, "row " + std::to_string(r) + " entry " +
                                                                             std::to_string(c) + " ");
    }
  }
  b.boundary = choice(t, "boundary", p, BoundaryKind::None,
                      {{"none", BoundaryKind::None},
                       {"fixed", BoundaryKind::Fixed},
                       {"moving", BoundaryKind::Moving},
                       {"driven", BoundaryKind::Driven}});
  read_rigid_tool(p, t, b);
  if (b.boundary == BoundaryKind::Fixed && t.contains("velocity_gradient"))
    fail(p + ".velocity_gradient",
         "a boundary = \"fixed\" body is at rest; use boundary = \"moving\" for particles that keep velocity + L x",
         t.get("velocity_gradient"));
  if (b.boundary == BoundaryKind::Fixed)
    for (int a = 0; a < dim_; ++a)
      if (b.velocity[a] != 0)
        fail(p + ".velocity", "a boundary = \"fixed\" body is at rest; use boundary = \"moving\" to prescribe a velocity",
             t.get("velocity"));
  if (t.contains("boundary_state")) {
    if (b.boundary == BoundaryKind::None)
      fail(p + ".boundary_state", "only a boundary body (boundary = \"fixed\", \"moving\" or \"driven\") has a boundary_state",
           t.get("boundary_state"));
    b.boundary_state = choice(t, "boundary_state", p, BoundaryState::Frozen,
                              {{"frozen", BoundaryState::Frozen},
                               {"evolving", BoundaryState::Evolving},
                               {"extrapolated", BoundaryState::Extrapolated}});
  }
  // Walls (issue #12): no-slip (the default: the wall's velocity enters the
  // velocity gradient and the viscosity like any neighbour's), free-slip
  // (only the relative velocity along the wall normal counts, and only the
  // normal part of the wall's force) or Coulomb (free-slip plus friction
  // wall_friction x the normal push; physics/wall_friction.hpp).
  for (const char* key : {"wall_slip", "wall_normal", "wall_friction"})
    if (t.contains(key) && b.boundary == BoundaryKind::None)
      fail(p + "." + key, "only a boundary body (boundary = \"fixed\", \"moving\" or \"driven\") is a wall", t.get(key));
  b.wall_slip = choice(t, "wall_slip", p, WallSlip::NoSlip,
                       {{"no_slip", WallSlip::NoSlip}, {"free_slip", WallSlip::FreeSlip}, {"coulomb", WallSlip::Coulomb}});
  if (b.sliding_wall() && b.rigid_tool())
    fail(p + ".wall_slip",
         "a turning or driven tool is a no-slip wall (a sliding wall's normal does not turn with it); remove wall_slip",
         t.get("wall_slip"));
  if (b.sliding_wall()) {
    const auto n = vector(t, "wall_normal", p);
    if (!n)
      fail(p + ".wall_normal", std::string("missing: a ") + (b.wall_slip == WallSlip::Coulomb ? "coulomb" : "free_slip") +
                                   " wall needs its unit normal (pointing into the material it holds)");
    double len = 0;
    for (int a = 0; a < dim_; ++a) len += (*n)[a] * (*n)[a];
    if (!(len > 0)) fail(p + ".wall_normal", "is the zero vector; give the wall's normal, e.g. [0, 1] for a floor",
                         t.get("wall_normal"));
    for (int a = 0; a < dim_; ++a) b.wall_normal[a] = (*n)[a] / std::sqrt(len);
  } else if (t.contains("wall_normal")) {
    fail(p + ".wall_normal", "only a sliding wall uses a normal (wall_slip = \"free_slip\" or \"coulomb\")",
         t.get("wall_normal"));
  }
  if (b.wall_slip == WallSlip::Coulomb) {
    b.wall_friction = required_number(t, "wall_friction", p, "the Coulomb friction coefficient mu of a coulomb wall");
    require(b.wall_friction > 0, t, "wall_friction", p, b.wall_friction,
            "> 0 (a frictionless wall is wall_slip = \"free_slip\")");
  } else if (t.contains("wall_friction")) {
    fail(p + ".wall_friction", "only a coulomb wall has a friction coefficient (wall_slip = \"coulomb\")",
         t.get("wall_friction"));
  }
  return b;
}

void SceneReader::read_domain(const toml::table& t, DomainConfig& d) {
  const std::string p = "domain";
  check_keys(t, p, {"periodic", "min", "max"});
  bool any_periodic = false;
  if (const toml::node* n = t.get("periodic")) {
    const toml::array* arr = n->as_array();
    if (!arr) fail(p + ".periodic", "expected an array of " + std::to_string(dim_) + " booleans, got " + type_name(*n), n);
    check_length(*arr, p + ".periodic", n);
    for (int a = 0; a < dim_; ++a) {
      const auto* v = (*arr)[a].as_boolean();
      if (!v)
        fail(p + ".periodic", "entry " + std::to_string(a) + ": expected true or false, got " + type_name((*arr)[a]), n);
      d.periodic[a] = v->get();
      any_periodic = any_periodic || d.periodic[a];
    }
  }
  const auto lo = vector(t, "min", p);
  const auto hi = vector(t, "max", p);
  if (any_periodic && !lo) fail(p + ".min", "missing; required when an axis is periodic (domain.periodic)");
  if (any_periodic && !hi) fail(p + ".max", "missing; required when an axis is periodic (domain.periodic)");
  if (lo.has_value() != hi.has_value())
    fail(lo ? p + ".max" : p + ".min", "missing; domain.min and domain.max go together");
  if (lo) {
    for (int a = 0; a < dim_; ++a)
      if (!((*hi)[a] > (*lo)[a]))
        fail(p + ".max",
             "entry " + std::to_string(a) + " is " + fmt((*hi)[a]) + ", must be > min (" + fmt((*lo)[a]) + ")",
             t.get("max"));
    d.min = *lo;
    d.max = *hi;
  }
}

EnergyDepositConfig SceneReader::read_energy_deposit(const std::string& p, const toml::table& t) {
  check_keys(t, p, {"energy", "center", "radius", "profile"});
  EnergyDepositConfig e;
  e.energy = required_number(t, "energy", p, "the energy added, in J");
  require(e.energy > 0, t, "energy", p, e.energy, "> 0");
  const auto c = vector(t, "center", p);
  if (!c) fail(sub(p, "center"), "missing required key (where the energy goes, one coordinate per axis)");
  e.center = *c;
  e.radius = required_number(t, "radius", p, "the radius the energy is spread over, in m");
  require(e.radius > 0, t, "radius", p, e.radius, "> 0");
  e.profile = choice<DepositProfile>(t, "profile", p, DepositProfile::Kernel,
                                     {{"kernel", DepositProfile::Kernel}, {"uniform", DepositProfile::Uniform}});
  return e;
}

void SceneReader::read_output(const toml::table& t, OutputConfig& o) {
  const std::string p = "output";
  check_keys(t, p, {"name", "interval", "snapshots", "conserved_interval"});
  if (auto s = string(t, "name", p)) {
    if (!is_identifier(*s))
      fail(p + ".name", "is '" + *s + "'; a file stem may contain only letters, digits, '_' and '-'", t.get("name"));
    o.name = *s;
  }
  if (auto x = number(t, "interval", p)) {
    require(*x >= 0, t, "interval", p, *x, ">= 0 (0 = initial and final snapshots only)");
    o.interval = *x;
  }
  if (auto b = boolean(t, "snapshots", p)) o.snapshots = *b;
  if (auto x = number(t, "conserved_interval", p)) {
    require(*x >= 0, t, "conserved_interval", p, *x, ">= 0 (0 = a row every step)");
    o.conserved_interval = *x;
  }
}

// ---- self-gravity (docs/scene.md "[gravity]"; issue #5) ------------------------

void SceneReader::read_gravity(const toml::table& t, GravityConfig& g) {
  const std::string p = "gravity";
  check_keys(t, p, {"mode", "theta", "order", "G", "softening", "leaf_size", "group_size"});
  g.mode = choice(t, "mode", p, GravityMode::Off,
                  {{"off", GravityMode::Off}, {"direct", GravityMode::Direct}, {"barnes_hut", GravityMode::BarnesHut}});
  if (g.mode != GravityMode::Off && dim_ != 3)
    fail(p + ".mode", "self-gravity needs simulation.dimension = 3 (it is " + std::to_string(dim_) + ")", t.get("mode"));
  if (auto x = number(t, "theta", p)) {
    require(*x >= 0 && *x <= 1, t, "theta", p, *x, "in [0, 1] (0 opens every node: direct summation)");
    g.theta = *x;
  }
  g.order = choice(t, "order", p, MultipoleOrder::Quadrupole,
                   {{"monopole", MultipoleOrder::Monopole}, {"quadrupole", MultipoleOrder::Quadrupole}});
  if (auto x = number(t, "G", p)) {
    require(*x > 0, t, "G", p, *x, "> 0 [m^3 kg^-1 s^-2]");
    g.G = *x;
  }
  // softening: "smoothing_length" (eps = h) or a fixed length [m] >= 0.
  if (const toml::node* n = t.get("softening")) {
    if (const auto* str = n->as_string()) {
      if (str->get() != "smoothing_length") {
        const std::string guess = closest(str->get(), {"smoothing_length"});
        fail(p + ".softening",
             "unknown value '" + str->get() + "'; expected \"smoothing_length\" or a length [m] >= 0" +
                 (guess.empty() ? "" : " (did you mean '" + guess + "'?)"),
             n);
      }
      g.softening = GravitySoftening::SmoothingLength;
    } else if (n->is_integer() || n->is_floating_point()) {
      const double x = as_number(*n, p + ".softening", "");
      require(x >= 0, t, "softening", p, x, ">= 0 [m] (0 = point masses), or \"smoothing_length\"");
      g.softening = GravitySoftening::Fixed;
      g.softening_length = x;
    } else {
      fail(p + ".softening", "expected \"smoothing_length\" or a length [m], got " + type_name(*n), n);
    }
  }
  if (auto n = integer(t, "leaf_size", p)) {
    if (*n < 1 || *n > 1024) fail(p + ".leaf_size", "is " + std::to_string(*n) + ", must be in [1, 1024]", t.get("leaf_size"));
    g.leaf_size = static_cast<int>(*n);
  }
  if (auto n = integer(t, "group_size", p)) {
    if (*n < 0 || *n > 65536)
      fail(p + ".group_size", "is " + std::to_string(*n) + ", must be in [0, 65536] (0 or 1: every particle walks alone)",
           t.get("group_size"));
    g.group_size = static_cast<int>(*n);
  }
}

// shape = "polytrope": a self-gravitating polytrope (docs/scene.md).
BodyConfig SceneReader::read_polytrope_body(const std::string& p, const toml::table& t,
                                            const std::vector<MaterialConfig>& mats) {
  BodyConfig b;
  b.shape = BodyShape::Polytrope;
  b.lattice = Lattice::HexagonalClosePacked;
  check_keys(t, p,
             {"shape", "material", "center", "radius", "mass", "polytropic_index", "particles", "lattice", "velocity"});
  if (dim_ != 3) fail(p + ".shape", "'polytrope' needs simulation.dimension = 3", t.get("shape"));

  b.material_id = material_index(t, p, mats);
  b.material = mats[std::size_t(b.material_id)].name;
  if (mats[b.material_id].eos != EosKind::IdealGas)
    fail(p + ".material", "a polytrope needs an ideal_gas material (material '" + b.material + "' is not)",
         t.get("material"));

  if (auto c = vector(t, "center", p)) b.center = *c;
  b.radius = required_number(t, "radius", p, "the outer radius [m], > 0");
  require(b.radius > 0, t, "radius", p, b.radius, "> 0");
  b.mass = required_number(t, "mass", p, "the total mass [kg], > 0");
  require(b.mass > 0, t, "mass", p, b.mass, "> 0");
  if (auto x = number(t, "polytropic_index", p)) {
    require(*x > 0 && *x < 5, t, "polytropic_index", p, *x, "in (0, 5) (a finite radius)");
    b.polytropic_index = *x;
  }
  const auto n = integer(t, "particles", p);
  if (!n) fail(p + ".particles", "missing required key (the approximate number of particles, >= 100)");
  if (*n < 100 || *n > 1'000'000'000)
    fail(p + ".particles", "is " + std::to_string(*n) + ", must be in [100, 1e9]", t.get("particles"));
  b.particles = *n;
  b.lattice = choice(t, "lattice", p, Lattice::HexagonalClosePacked,
                     {{"cubic", Lattice::Cubic}, {"hcp", Lattice::HexagonalClosePacked}});
  if (auto v = vector(t, "velocity", p)) b.velocity = *v;
  for (int a = 0; a < 3; ++a) {
    b.min[a] = b.center[a] - b.radius;
    b.max[a] = b.center[a] + b.radius;
  }
  return b;
}

// shape = "layered": a differentiated body in hydrostatic equilibrium
// (docs/scene.md; scene/layered_body.hpp). The structure is computed here,
// so a body that has none is refused with its key, and radius and mass are
// known to what follows (the [collision] set-up, the overlap check).
BodyConfig SceneReader::read_layered_body(const std::string& p, const toml::table& t,
                                          const std::vector<MaterialConfig>& mats) {
  BodyConfig b;
  b.shape = BodyShape::Layered;
  check_keys(t, p, {"shape", "center", "layers", "mass", "particles", "velocity", "seed"});
  if (dim_ != 3) fail(p + ".shape", "'layered' needs simulation.dimension = 3", t.get("shape"));
  if (!gravity_on_)
    fail(p + ".shape", "a layered body is held together by its own gravity: it needs a [gravity] table "
                       "(mode = \"direct\" or \"barnes_hut\")", t.get("shape"));
  if (auto c = vector(t, "center", p)) b.center = *c;
  if (auto v = vector(t, "velocity", p)) b.velocity = *v;
  const auto n = integer(t, "particles", p);
  if (!n) fail(p + ".particles", "missing required key (the approximate number of particles, >= 100)");
  if (*n < 100 || *n > 1'000'000'000)
    fail(p + ".particles", "is " + std::to_string(*n) + ", must be in [100, 1e9]", t.get("particles"));
  b.particles = *n;
  if (auto seed = integer(t, "seed", p)) {
    if (*seed < 0) fail(p + ".seed", "is " + std::to_string(*seed) + ", must be >= 0", t.get("seed"));
    b.seed = std::uint64_t(*seed);
  }

  const std::string lp = p + ".layers";
  const toml::node* ln = t.get("layers");
  if (!ln) fail(lp, "missing required key (the layers from the centre out, e.g. [{ material = \"iron\", radius = 3e5 }, "
                    "{ material = \"basalt\", radius = 6e5 }])");
  const toml::array* arr = ln->as_array();
  if (!arr || arr->empty()) fail(lp, "expected a non-empty array of tables, got " + type_name(*ln), ln);
  bool by_radius = false;
  double fraction_sum = 0, previous = 0;
  for (std::size_t k = 0; k < arr->size(); ++k) {
    const std::string q = lp + "[" + std::to_string(k) + "]";
    const toml::table* lt = (*arr)[k].as_table();
    if (!lt) fail(q, "expected a table { material = ..., radius = ... } or { material = ..., mass_fraction = ... }, got " +
                         type_name((*arr)[k]), &(*arr)[k]);
    check_keys(*lt, q, {"material", "radius", "mass_fraction"});
    LayerConfig layer;
    layer.material_id = material_index(*lt, q, mats);
    const MaterialConfig& m = mats[std::size_t(layer.material_id)];
    layer.material = m.name;
    if (m.eos != EosKind::Murnaghan && m.eos != EosKind::Tillotson)
      fail(q + ".material", "material '" + m.name + "' has an ideal-gas EOS, which has no density at zero pressure "
                            "(a layer needs murnaghan or tillotson)", lt->get("material"));
    if (m.porosity.enabled)
      fail(q + ".material", "material '" + m.name + "' is porous; the hydrostatic set-up does not handle p-alpha "
                            "porosity yet (use a non-porous material for the layer)", lt->get("material"));
    const bool has_r = lt->contains("radius"), has_f = lt->contains("mass_fraction");
    if (has_r == has_f) fail(q, "give exactly one of radius (the layer's outer radius [m]) and mass_fraction", &(*arr)[k]);
    if (k == 0) by_radius = has_r;
    else if (has_r != by_radius)
      fail(q, std::string("layers[0] gives ") + (by_radius ? "a radius" : "a mass_fraction") +
                  "; every layer must give the same", &(*arr)[k]);
    if (has_r) {
      layer.radius = required_number(*lt, "radius", q, "the layer's outer radius [m]");
      require(layer.radius > previous, *lt, "radius", q, layer.radius,
              k == 0 ? "> 0" : "> the radius of the layer below (" + fmt(previous) + ")");
      previous = layer.radius;
    } else {
      layer.mass_fraction = required_number(*lt, "mass_fraction", q, "the layer's fraction of the body's mass");
      require(layer.mass_fraction > 0 && layer.mass_fraction <= 1, *lt, "mass_fraction", q, layer.mass_fraction, "in (0, 1]");
      fraction_sum += layer.mass_fraction;
    }
    b.layers.push_back(layer);
  }
  if (by_radius) {
    if (t.contains("mass"))
      fail(p + ".mass", "the layers give their radii, which fix the mass; give mass only with mass_fraction layers",
           t.get("mass"));
  } else {
    b.mass = required_number(t, "mass", p, "the body's total mass [kg], > 0 (the layers give mass fractions)");
    require(b.mass > 0, t, "mass", p, b.mass, "> 0");
    if (std::fabs(fraction_sum - 1) > 1e-6)
      fail(lp, "the mass fractions add up to " + fmt(fraction_sum) + ", not 1", ln);
    for (LayerConfig& layer : b.layers) layer.mass_fraction /= fraction_sum;
  }
  try {
    const HydrostaticProfile pr = layered_profile(layered_spec(mats, b), G_);
    b.radius = pr.layer_radius.back();
    if (by_radius) b.mass = pr.mass;
  } catch (const std::exception& e) {
    fail(lp, std::string("no hydrostatic structure: ") + e.what() +
                 " (a body too massive for its materials' EOS, or a layer too thin?)", ln);
  }
  b.material_id = b.layers.back().material_id;
  b.material = b.layers.back().material;
  for (int a = 0; a < 3; ++a) {
    b.min[a] = b.center[a] - b.radius;
    b.max[a] = b.center[a] + b.radius;
  }
  return b;
}

// [collision] (docs/scene.md "Collisions"; issue #52 item 3).
void SceneReader::read_collision(const toml::table& t, Scene& scene) {
  const std::string p = "collision";
  check_keys(t, p, {"target", "impactor", "impact_speed", "impact_speed_vesc", "v_infinity", "impact_angle",
                    "separation", "spin_target", "spin_impactor"});
  CollisionConfig& c = scene.collision;
  c.enabled = true;
  if (scene.simulation.dimension != 3 || scene.gravity.mode == GravityMode::Off)
    fail(p, "needs a 3-D scene with self-gravity ([gravity]): the orbit and the escape speed come from G M");
  // a body index or a list of them
  auto bodies = [&](std::string_view name) {
    const toml::node* n = t.get(name);
    const std::string key = sub(p, name);
    if (!n) fail(key, "missing required key (the index of a [[bodies]] entry, or a list of them)");
    std::vector<int> out;
    auto one = [&](const toml::node& v) {
      const auto* i = v.as_integer();
      if (!i) fail(key, "expected a body index (an integer), got " + type_name(v), &v);
      if (i->get() < 0 || i->get() >= std::int64_t(scene.bodies.size()))
        fail(key, "is " + std::to_string(i->get()) + ", but the scene has bodies 0 to " +
                      std::to_string(scene.bodies.size() - 1), &v);
      const BodyConfig& b = scene.bodies[std::size_t(i->get())];
      const std::string body = "bodies[" + std::to_string(i->get()) + "]";
      if (b.boundary != BoundaryKind::None) fail(key, body + " is a boundary body; a colliding body must be free", &v);
      if (b.velocity[0] != 0 || b.velocity[1] != 0 || b.velocity[2] != 0)
        fail(key, body + " has a velocity; the collision sets it (leave " + body + ".velocity out)", &v);
      out.push_back(int(i->get()));
    };
    if (const toml::array* a = n->as_array()) {
      if (a->empty()) fail(key, "is an empty list", n);
      for (const toml::node& v : *a) one(v);
    } else {
      one(*n);
    }
    return out;
  };
  c.target = bodies("target");
  c.impactor = bodies("impactor");
  for (int i : c.impactor)
    if (std::find(c.target.begin(), c.target.end(), i) != c.target.end())
      fail(p + ".impactor", "bodies[" + std::to_string(i) + "] is in both the target and the impactor", t.get("impactor"));
  int speeds = 0;
  if (auto x = number(t, "impact_speed", p)) {
    require(*x > 0, t, "impact_speed", p, *x, "> 0 [m/s]");
    c.impact_speed = *x;
    ++speeds;
  }
  if (auto x = number(t, "impact_speed_vesc", p)) {
    require(*x > 0, t, "impact_speed_vesc", p, *x, "> 0 (the speed at contact over the mutual escape speed)");
    c.impact_speed_vesc = *x;
    ++speeds;
  }
  if (auto x = number(t, "v_infinity", p)) {
    require(*x >= 0, t, "v_infinity", p, *x, ">= 0 [m/s]");
    c.v_infinity = *x;
    ++speeds;
  }
  if (speeds != 1)
    fail(p, speeds == 0 ? "needs the impact speed: one of impact_speed [m/s], impact_speed_vesc, v_infinity [m/s]"
                        : "give only one of impact_speed, impact_speed_vesc and v_infinity");
  c.impact_angle = required_number(t, "impact_angle", p, "degrees between the line of centres and the relative "
                                                         "velocity at contact, 0 = head-on");
  require(c.impact_angle >= 0 && c.impact_angle < 90, t, "impact_angle", p, c.impact_angle, "in [0, 90) degrees");
  c.separation = required_number(t, "separation", p, "the centres' distance at the start, in touching distances");
  require(c.separation >= 1, t, "separation", p, c.separation, ">= 1 (touching distances R_t + R_i)");
  if (auto w = vector(t, "spin_target", p)) c.spin_target = *w;
  if (auto w = vector(t, "spin_impactor", p)) c.spin_impactor = *w;
}

Scene SceneReader::read(const toml::table& root) {
  Scene scene;
  scene.file = file_;
  check_keys(root, "", {"simulation", "materials", "bodies", "domain", "output", "gravity", "energy_deposits", "collision",
                        "regions"});
  read_simulation(root, scene.simulation);
  if (const toml::table* g = table(root, "gravity", "")) read_gravity(*g, scene.gravity);
  G_ = scene.gravity.G;
  gravity_on_ = scene.gravity.mode != GravityMode::Off;

  // Materials, in declaration order (toml++ keeps tables sorted by key, so
  // order by source position; ones created by --set come last).
  const toml::table* mats = table(root, "materials", "");
  if (!mats) fail("materials", "missing required table: define at least one [materials.NAME]");
  std::vector<std::pair<const toml::key*, const toml::node*>> entries;
  for (const auto& [k, n] : *mats) entries.emplace_back(&k, &n);
  auto position = [](const toml::key* k) {
    const auto& b = k->source().begin;
    return b.line == 0 ? std::pair<std::uint64_t, std::uint64_t>(~0ull, 0) : std::pair<std::uint64_t, std::uint64_t>(b.line, b.column);
  };
  std::stable_sort(entries.begin(), entries.end(),
                   [&](const auto& a, const auto& b) { return position(a.first) < position(b.first); });
  if (entries.empty()) fail("materials", "at least one material is required ([materials.NAME])", root.get("materials"));
  for (const auto& [k, n] : entries) {
    const std::string name(k->str());
    if (!n->is_table()) fail("materials." + name, "expected a table ([materials." + name + "]), got " + type_name(*n), n);
    scene.materials.push_back(read_material(name, *n->as_table()));
  }

  // Quasi-static runs: every Murnaghan solid softened to the longitudinal
  // wave speed c_q = simulation.quasi_static_sound_speed (at rho0), its K0
  // and G scaled by (c_q / c_l)^2 < 1; a solid of another EOS, or porous,
  // is refused (its softening is not one factor).
  if (const double cq = scene.simulation.quasi_static_sound_speed; cq > 0) {
    const toml::table* st = table(root, "simulation", "");
    for (MaterialConfig& m : scene.materials) {
      if (!(m.shear_modulus > 0)) continue;
      if (m.eos != EosKind::Murnaghan || m.porosity.enabled)
        fail("simulation.quasi_static_sound_speed",
             "softens Murnaghan solids only; materials." + m.name + " is " +
                 (m.porosity.enabled ? std::string("porous") : std::string("not Murnaghan")),
             st ? st->get("quasi_static_sound_speed") : nullptr);
      const double cl = std::sqrt((m.murnaghan.K0 + 4.0 / 3.0 * m.shear_modulus) / m.murnaghan.rho0);
      if (cl <= cq) continue;
      m.stiffness_scale = (cq / cl) * (cq / cl);
      m.murnaghan.K0 *= m.stiffness_scale;
      m.shear_modulus *= m.stiffness_scale;
    }
  }

  // Bodies: an array of tables ([[bodies]]).
  const toml::node* bodies = root.get("bodies");
  if (!bodies) fail("bodies", "missing: at least one [[bodies]] entry is required");
  const toml::array* arr = bodies->as_array();
  if (!arr) fail("bodies", "expected an array of tables: write [[bodies]], not [bodies]", bodies);
  if (arr->empty()) fail("bodies", "at least one body is required", bodies);
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const std::string p = "bodies[" + std::to_string(i) + "]";
    const toml::table* t = (*arr)[i].as_table();
    if (!t) fail(p, "expected a table, got " + type_name((*arr)[i]), &(*arr)[i]);
    scene.bodies.push_back(read_body(p, *t, scene.materials));
  }

  if (const toml::table* d = table(root, "domain", "")) read_domain(*d, scene.domain);
  if (const toml::node* deposits = root.get("energy_deposits")) {
    const toml::array* arr = deposits->as_array();
    if (!arr) fail("energy_deposits", "expected an array of tables: write [[energy_deposits]]", deposits);
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const std::string p = "energy_deposits[" + std::to_string(i) + "]";
      const toml::table* t = (*arr)[i].as_table();
      if (!t) fail(p, "expected a table, got " + type_name((*arr)[i]), &(*arr)[i]);
      scene.energy_deposits.push_back(read_energy_deposit(p, *t));
    }
  }
  if (const toml::node* regions = root.get("regions")) {
    const toml::array* arr = regions->as_array();
    if (!arr) fail("regions", "expected an array of tables: write [[regions]]", regions);
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const std::string p = "regions[" + std::to_string(i) + "]";
      const toml::table* t = (*arr)[i].as_table();
      if (!t) fail(p, "expected a table, got " + type_name((*arr)[i]), &(*arr)[i]);
      scene.regions.push_back(read_measure_region(p, *t, scene));
    }
    if (scene.materials.size() > std::size_t(kMaxRegionMaterials))
      fail("regions", "measuring regions count at most " + std::to_string(kMaxRegionMaterials) + " materials; the scene has " +
                          std::to_string(scene.materials.size()), regions);
  }
  if (const toml::table* c = table(root, "collision", "")) read_collision(*c, scene);
  // A [collision] relaxes its bodies in their own frames, held in place, and
  // launches them at damping_end (global damping would damp the orbit).
  if (scene.collision.enabled && scene.simulation.damping_time > 0) {
    const toml::table* st = table(root, "simulation", "");
    if (st && st->contains("damping_frame") && scene.simulation.damping_frame != DampingFrame::Body)
      fail("simulation.damping_frame", "a [collision] relaxes each body in its own frame and launches it at "
                                       "damping_end: use \"body\" (or leave the key out)", st->get("damping_frame"));
    scene.simulation.damping_frame = DampingFrame::Body;
  }
  const toml::table* out_table = table(root, "output", "");
  if (out_table) read_output(*out_table, scene.output);
  // Resource guards (issue #13): a bounded number of snapshots, and a
  // conserved.csv of at most ~1e4 rows unless asked for more.
  constexpr double kMaxSnapshots = 1e5;
  if (scene.output.interval > 0 && scene.simulation.end_time / scene.output.interval > kMaxSnapshots)
    fail("output.interval",
         "is " + fmt(scene.output.interval) + " s, which would write " +
             fmt(std::ceil(scene.simulation.end_time / scene.output.interval) + 1) + " snapshots up to end_time = " +
             fmt(scene.simulation.end_time) + " s; at most 1e5 are allowed",
         out_table ? out_table->get("interval") : nullptr);
  if (!(out_table && out_table->contains("conserved_interval")))
    scene.output.conserved_interval = scene.simulation.end_time / 1e4;

  // Something must move: a scene of boundary bodies only has nothing to integrate.
  if (std::all_of(scene.bodies.begin(), scene.bodies.end(),
                  [](const BodyConfig& b) { return b.boundary != BoundaryKind::None; }))
    fail("bodies", "every body is a boundary (boundary = \"fixed\" or \"moving\"): there is nothing to integrate",
         root.get("bodies"));
  {
    std::size_t tools = 0;
    for (std::size_t k = 0; k < scene.bodies.size(); ++k)
      if (scene.bodies[k].rigid_tool() && ++tools > std::size_t(kMaxRigidTools))
        fail("bodies[" + std::to_string(k) + "]",
             "is rigid tool number " + std::to_string(tools) + "; a run takes at most " + std::to_string(kMaxRigidTools) +
                 " (turning or driven bodies)");
  }

  // Solids (a material with a shear modulus) evolve the density with the
  // continuity equation: summation underestimates it at free surfaces.
  // Without simulation.density, a scene with a solid gets continuity.
  const toml::table* sim_table = table(root, "simulation", "");
  const bool density_given = sim_table && sim_table->contains("density");
  for (const MaterialConfig& m : scene.materials) {
    // porous fluids may use either form, but default to continuity like solids
    // (their free surfaces, e.g. a porous target's, need it); so do fluids
    // with a condensed EOS (Murnaghan, Tillotson; issue #50): summation
    // gives a free surface a kernel-deficit density, which their stiff cold
    // term turns into tension of order A (rho/rho0 - 1) - a 3-D basalt sphere
    // of 312 particles at rest reached 6e23 J of kinetic energy in 10 steps
    // (test_energy_watchdog: CondensedFluid.*)
    const bool condensed = m.eos == EosKind::Murnaghan || m.eos == EosKind::Tillotson;
    if ((m.porosity.enabled || condensed) && !(m.shear_modulus > 0) && !density_given)
      scene.simulation.density = DensityForm::Continuity;
    if (!(m.shear_modulus > 0) || scene.simulation.density == DensityForm::Continuity) continue;
    if (density_given)
      fail("simulation.density",
           "material '" + m.name + "' is a solid (shear_modulus > 0), which needs density = \"continuity\"",
           sim_table->get("density"));
    scene.simulation.density = DensityForm::Continuity;
  }

  // The geometric pressure force is written for continuity density and the
  // fluid equations (physics/hydro.hpp); a solid's stress passes keep theirs.
  if (scene.simulation.pressure_force == PressureForce::Geometric) {
    const toml::node* at = sim_table ? sim_table->get("pressure_force") : nullptr;
    if (scene.simulation.density != DensityForm::Continuity)
      fail("simulation.pressure_force", "\"geometric\" needs simulation.density = \"continuity\"", at);
    for (const MaterialConfig& m : scene.materials)
      if (m.shear_modulus > 0)
        fail("simulation.pressure_force", "\"geometric\" is for fluids; material '" + m.name +
                                              "' is a solid (shear_modulus > 0), whose stress passes keep the standard form", at);
  }

  // The viscosity switch is evolved by the hydro force loop only; a scene
  // with a solid runs the solid passes, which take the material's constant
  // coefficients.
  const auto solid_in_scene = std::find_if(scene.materials.begin(), scene.materials.end(),
                                           [](const MaterialConfig& m) { return m.shear_modulus > 0; });
  for (const MaterialConfig& m : scene.materials)
    if (m.viscosity.switch_on && solid_in_scene != scene.materials.end())
      fail("materials." + m.name + ".viscosity.switch",
           "the viscosity switch is not supported yet in a scene with a solid (material '" + solid_in_scene->name +
               "' has shear_modulus > 0); use constant coefficients");

  // The staggered stress update is a leapfrog scheme for solids; porous and
  // damaged materials and extrapolated walls are not staggered yet (alpha
  // and D follow from the stress and density that the update advances,
  // and a wall takes its state from the free particles before pass 1;
  // leapfrog.hpp).
  if (scene.simulation.stress_update == StressUpdate::Staggered) {
    const std::string key = "simulation.stress_update";
    const toml::node* at = sim_table ? sim_table->get("stress_update") : nullptr;
    if (scene.simulation.integrator != Integrator::Leapfrog)
      fail(key, "\"staggered\" is a leapfrog scheme: it needs simulation.integrator = \"leapfrog\"", at);
    if (std::none_of(scene.materials.begin(), scene.materials.end(),
                     [](const MaterialConfig& m) { return m.shear_modulus > 0; }))
      fail(key, "\"staggered\" advances a solid's stress, but no material has a shear modulus", at);
    for (const MaterialConfig& m : scene.materials)
      if (m.porosity.enabled || m.damage.enabled)
        fail(key, "\"staggered\" does not support porous or damaged materials yet (material '" + m.name +
                      "'); use \"predicted\"", at);
    for (const BodyConfig& b : scene.bodies)
      if (b.boundary != BoundaryKind::None && b.boundary_state == BoundaryState::Extrapolated)
        fail(key, "\"staggered\" does not support boundary_state = \"extrapolated\" walls yet; use \"predicted\"", at);
  }

  // Self-gravity has no periodic images (no Ewald sums): open boundaries only.
  if (scene.gravity.mode != GravityMode::Off)
    for (int a = 0; a < dim_; ++a)
      if (scene.domain.periodic[a])
        fail("gravity.mode", "self-gravity needs open boundaries, but domain.periodic makes axis " +
                                 std::to_string(a) + " periodic; set gravity.mode = \"off\" or make every axis open");

  // Bodies must lie inside the domain along periodic axes.
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodyConfig& b = scene.bodies[i];
    const std::string p = "bodies[" + std::to_string(i) + "]";
    for (int a = 0; a < dim_; ++a) {
      if (!scene.domain.periodic[a]) continue;
      const std::string axis = std::to_string(a);
      if (b.min[a] < scene.domain.min[a])
        fail(p + ".min", "entry " + axis + " is " + fmt(b.min[a]) + ", below domain.min (" +
                             fmt(scene.domain.min[a]) + ") on periodic axis " + axis + "; bodies must lie inside a periodic domain");
      if (b.max[a] > scene.domain.max[a])
        fail(p + ".max", "entry " + axis + " is " + fmt(b.max[a]) + ", above domain.max (" +
                             fmt(scene.domain.max[a]) + ") on periodic axis " + axis + "; bodies must lie inside a periodic domain");
    }
  }
  return scene;
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& file_label, const std::vector<std::string>& overrides,
                  const std::vector<LibraryText>* libraries) {
  toml::table root;
  try {
    root = toml::parse(text, file_label);
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    throw InputError(file_label, "",
                     "malformed TOML at line " + std::to_string(at.line) + ", column " + std::to_string(at.column) +
                         ": " + std::string(e.description()));
  }

  std::map<std::string, std::string> set_by;
  for (const auto& o : overrides) set_by[apply_override(root, o, file_label)] = o;

  SceneReader reader(file_label, set_by, libraries);
  Scene scene = reader.read(root);
  scene.source_text = text;
  scene.overrides = overrides;
  scene.libraries = reader.libraries_read();

  // Scene::text is the file as written (comments kept, so it re-parses to the
  // same material order) followed by a comment block listing the overrides.
  scene.text = text;
  if (!overrides.empty()) {
    if (!scene.text.empty() && scene.text.back() != '\n') scene.text += '\n';
    scene.text += "\n# ---- rubble: --set overrides applied on top of the text above ----\n";
    for (std::string o : overrides) {
      std::replace(o.begin(), o.end(), '\n', ' ');
      scene.text += "# --set " + o + "\n";
    }
  }
  return scene;
}

Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "", "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, "", "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file for reading");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "error while reading the file");
  return parse_scene(buf.str(), path, overrides);
}

}  // namespace rubble

// ---- the material library (materials.hpp) ------------------------------------

namespace rubble {

std::string materials_directory() {
  if (const char* env = std::getenv("RUBBLE_MATERIALS"); env != nullptr && *env != '\0') return env;
#ifdef RUBBLE_MATERIALS_DIR
  return RUBBLE_MATERIALS_DIR;
#else
  return "";
#endif
}

std::vector<std::string> library_material_names() {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  const std::string dir = materials_directory();
  if (dir.empty() || !fs::is_directory(dir, ec)) return names;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file(ec) && entry.path().extension() == ".toml") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

MaterialConfig load_material(const std::string& name_or_path, const std::vector<std::string>& overrides) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::string path, name = name_or_path;
  if (ends_with(name_or_path, ".toml")) {
    path = name_or_path;
    name = fs::path(path).stem().string();
    if (!fs::is_regular_file(path, ec)) throw InputError(path, "", "no such material file");
  } else {
    const std::string dir = materials_directory();
    const std::vector<std::string> names = library_material_names();
    if (dir.empty()) throw InputError(name_or_path, "", "no material library directory is known; set RUBBLE_MATERIALS");
    if (!is_identifier(name_or_path) || std::find(names.begin(), names.end(), name_or_path) == names.end()) {
      const std::string guess = closest(name_or_path, names);
      throw InputError(name_or_path, "",
                       "unknown material; the library (" + dir + ") has: " +
                           (names.empty() ? std::string("nothing") : join(names)) +
                           (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                           "; a material file can be given by its path (NAME.toml)");
    }
    path = (fs::path(dir) / (name_or_path + ".toml")).string();
  }
  toml::table root = parse_toml_file(path);
  std::map<std::string, std::string> set_by;
  for (const auto& o : overrides) set_by[apply_override(root, o, path)] = o;
  return SceneReader(path, set_by).read_library_material(name, root);
}

}  // namespace rubble
