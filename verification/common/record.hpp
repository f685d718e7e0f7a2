#pragma once
// One JSON record per verification run (format: docs/report-format.md),
// written by every rung and rendered by ci/report. Header-only, no
// dependencies beyond rubble's Real: a tiny JSON writer is enough for flat
// records.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "rubble/core/real.hpp"

// The commit a record names (set by the build for every target; a build
// outside git says "unknown").
#ifndef RUBBLE_COMMIT
#define RUBBLE_COMMIT "unknown"
#endif

namespace rubble::verification {

// The --set overrides of a run as one string, for a record's parameters.
inline std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& x : items) s += (s.empty() ? "" : " ") + x;
  return s;
}

// A number as the shortest text that reads back as the same double
// (std::to_chars without a precision): scene overrides, the notes a rung
// adds to a scene and record values read back exactly, and a report shows
// 54.9, not the 54.899999999999999 of "%.17g".
inline std::string exact_number(double v) {
  char b[64];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

// A JSON value built from nested maps/vectors, printed in key order.
class Json {
 public:
  Json() : text_("null") {}
  Json(double v) {  // NOLINT: implicit on purpose
    text_ = std::isfinite(v) ? exact_number(v) : "null";
  }
  Json(int v) : text_(std::to_string(v)) {}
  Json(long v) : text_(std::to_string(v)) {}
  Json(long long v) : text_(std::to_string(v)) {}
  Json(std::size_t v) : text_(std::to_string(v)) {}
  Json(bool v) : text_(v ? "true" : "false") {}
  Json(const char* s) : text_(quote(s)) {}
  Json(const std::string& s) : text_(quote(s)) {}
  Json(const std::vector<double>& a) {
    text_ = "[";
    for (std::size_t i = 0; i < a.size(); ++i) text_ += (i ? "," : "") + Json(a[i]).text_;
    text_ += "]";
  }
  static Json object(const std::vector<std::pair<std::string, Json>>& kv) {
    Json j;
    j.text_ = "{";
    for (std::size_t i = 0; i < kv.size(); ++i) j.text_ += (i ? ", " : "") + quote(kv[i].first) + ": " + kv[i].second.text_;
    j.text_ += "}";
    return j;
  }
  static Json array(const std::vector<Json>& items) {
    Json j;
    j.text_ = "[";
    for (std::size_t i = 0; i < items.size(); ++i) j.text_ += (i ? ", " : "") + items[i].text_;
    j.text_ += "]";
    return j;
  }
  const std::string& str() const { return text_; }
  // This object with the keys of `kv` appended.
  Json with(const std::vector<std::pair<std::string, Json>>& kv) const {
    Json j = object(kv);
    if (kv.empty()) return *this;
    if (text_.size() < 2 || text_.front() != '{' || text_.back() != '}')
      throw std::logic_error("Json::with on a value that is not an object");
    j.text_ = text_.substr(0, text_.size() - 1) + (text_ == "{}" ? "" : ", ") + j.text_.substr(1);
    return j;
  }

 private:
  static std::string quote(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') o += '\\';
      if (c == '\n') { o += "\\n"; continue; }
      o += c;
    }
    return o + "\"";
  }
  std::string text_;
};

// A pass/fail check with its threshold and where the threshold comes from.
struct Check {
  std::string name;
  double value;
  double threshold;
  std::string op;  // "<=" or ">="
  std::string source;
  bool passed() const {
    if (op == "<=") return value <= threshold;
    if (op == "<") return value < threshold;
    if (op == ">=") return value >= threshold;
    if (op == ">") return value > threshold;
    return false;  // an unknown comparison passes nothing
  }
  Json json() const {
    return Json::object({{"name", name}, {"value", value}, {"threshold", threshold}, {"op", op},
                         {"source", source}, {"passed", passed()}});
  }
};

// Print each check (PASS/FAIL, value, criterion) and return them as a
// record's "checks" array; `all_passed` says whether every one passed.
inline Json judge_checks(const std::vector<Check>& checks, bool& all_passed) {
  all_passed = true;
  std::vector<Json> items;
  for (const Check& c : checks) {
    items.push_back(c.json());
    all_passed = all_passed && c.passed();
    std::printf("  %s %s: %.4g (%s %.4g)\n", c.passed() ? "PASS" : "FAIL", c.name.c_str(), c.value, c.op.c_str(),
                c.threshold);
  }
  return Json::array(items);
}

// What every record says of the run that made it: the backend that computed
// it ("cpu", "cuda"; "cpu" for host-only computations such as an EOS scan),
// the precision of rubble::Real, and the commit built.
inline std::vector<std::pair<std::string, Json>> run_metadata(const std::string& backend) {
  return {{"backend", backend}, {"precision", sizeof(rubble::Real) == 8 ? "double" : "float"}, {"commit", RUBBLE_COMMIT}};
}

// Write `record` (an object) with the run's metadata appended, as
// dir/file_stem.json.
inline void write_record(const std::filesystem::path& dir, const std::string& file_stem, const Json& record,
                         const std::string& backend) {
  std::filesystem::create_directories(dir);
  std::ofstream f(dir / (file_stem + ".json"));
  f << record.with(run_metadata(backend)).str() << "\n";
  if (!f) throw std::runtime_error("cannot write record " + (dir / (file_stem + ".json")).string());
}

// The exit status of a rung from its judged checks. A rung's ctest test
// fails when a check fails, unless the check is a documented known failure:
// `known_failures` lists parts of check names (given on the command line with the
// reason next to it in the rung's CMakeLists.txt, the measurements in the
// rung's README.md). A known failure still
// shows as FAIL in its record and in the ladder report. An entry that
// matches checks none of which fails any more (e.g. the same check at every
// resolution, all passing now) fails the test too, so that the entry is
// removed and the check gates again.
inline int rung_exit_status(const std::vector<Check>& checks, const std::vector<std::string>& known_failures) {
  int status = 0;
  std::vector<int> matched(known_failures.size(), 0), failing(known_failures.size(), 0);
  for (const Check& c : checks) {
    bool known = false;
    for (std::size_t k = 0; k < known_failures.size(); ++k)
      if (c.name.find(known_failures[k]) != std::string::npos) {
        known = true;
        ++matched[k];
        failing[k] += !c.passed();
      }
    if (!known && !c.passed()) status = 1;
    if (known && !c.passed()) std::fprintf(stderr, "known failure (reported, not gating): '%s'\n", c.name.c_str());
  }
  for (std::size_t k = 0; k < known_failures.size(); ++k)
    if (matched[k] > 0 && failing[k] == 0) {
      std::fprintf(stderr, "known failure now passes: every check matching '%s' passes; remove it from the rung's "
                           "--known-failure list\n", known_failures[k].c_str());
      status = 1;
    }
  return status;
}

// Least-squares slope of log(error) against log(resolution), negated: the
// observed order of convergence over a whole ladder.
inline double observed_order(const std::vector<double>& resolution, const std::vector<double>& error) {
  const std::size_t n = resolution.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = std::log(resolution[i]), y = std::log(error[i]);
    sx += x; sy += y; sxx += x * x; sxy += x * y;
  }
  return -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace rubble::verification
