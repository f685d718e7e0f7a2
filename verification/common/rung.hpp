#pragma once
// The plumbing every rung shares, so that a rung's driver holds only its
// physics: the options rungs have in common and their reading (RungArgs),
// the main that turns an exception into exit status 2 (rung_main), a quiet
// run of a scene (run_into, run_in_memory) and the snapshots it wrote
// (snapshot_files), the keys a record opens with
// (record_head) and the exit status from the judged checks
// (RungArgs::exit_status).
//
//   struct Args : rubble::verification::RungArgs {
//     double v0 = 0.05;
//     Args() : RungArgs({.taken = "--scene --records --out --label --set", .out = "my_rung_out",
//                        .required = "--scene"}) {}
//     bool own_option(rubble::verification::ArgReader& r) override { return r.value("--v0", v0); }
//     void validate() override {
//       if (!(v0 > 0)) throw std::runtime_error("--v0 must be > 0");
//     }
//   };
//   int run(const Args& args) { ... return args.exit_status(checks); }
//   int main(int argc, char** argv) {
//     return rubble::verification::rung_main<Args>("my_rung: error: ", argc, argv, run);
//   }
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "args.hpp"
#include "record.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/run.hpp"

namespace rubble::verification {

// Which of the options rungs share a rung takes (any other stays an
// "unknown argument"), and the defaults it gives them.
struct SharedOptions {
  std::string taken;  // the options, separated by spaces: "--scene --records --label --set"
  std::string out = "";
  std::string label = "";
  std::string records = "reports/records";
  // Those that must be given: "--scene --resolutions" throws "need --scene
  // and --resolutions" when either is missing.
  std::string required = "";
};

// The options rungs share. A rung's arguments derive from RungArgs: the
// constructor says which shared options the rung takes (SharedOptions);
// own_option reads the rung's own options, validate judges the whole.
struct RungArgs {
  std::string scene;                        // --scene FILE
  std::string records;                      // --records DIR: where the JSON records go
  std::string out;                          // --out DIR: the run's output folder
  std::string label;                        // --label NAME: the records' case
  std::vector<double> resolutions;          // --resolutions 1,2,...
  std::vector<std::string> sets;            // --set key=value (repeated): scene overrides
  std::vector<std::string> known_failures;  // --known-failure TEXT (repeated): record.hpp rung_exit_status
  bool checks = false;                      // --checks: judge the thresholds
  bool report_only = false;                 // --report-only: checks recorded, exit status 0
  bool keep = false;                        // --keep: keep the output folder

  virtual ~RungArgs() = default;

  // Reads every argument from argv[first] on (2 after a leading mode word),
  // then validates them; throws "unknown argument ...", "missing value
  // after ..." or validate's message.
  void parse(int argc, char** argv, int first = 1) {
    ArgReader r(argc, argv, first);
    while (!r.done())
      if (!(read_shared(r) || own_option(r))) r.unknown();
    check_required();
    validate();
  }

  // The exit status of the run from its judged checks: 0 with
  // --report-only, else rung_exit_status (1 when a check that is not a
  // documented known failure fails).
  int exit_status(const std::vector<Check>& judged) const {
    return report_only ? 0 : rung_exit_status(judged, known_failures);
  }

 protected:
  explicit RungArgs(SharedOptions o)
      : records(std::move(o.records)),
        out(std::move(o.out)),
        label(std::move(o.label)),
        taken_(std::move(o.taken)),
        required_(std::move(o.required)) {}
  RungArgs(const RungArgs&) = default;
  RungArgs& operator=(const RungArgs&) = default;

  // The rung's own options: consumes the current argument when it is one
  // (ArgReader's value, flag, list, ...) and says whether it did.
  virtual bool own_option(ArgReader&) { return false; }
  // Throws where the arguments do not make a run; may fill defaults that
  // depend on them.
  virtual void validate() {}

 private:
  bool read_shared(ArgReader& r) {
    std::istringstream words(taken_);
    for (std::string w; words >> w;)
      if (read_one(r, w)) return true;
    return false;
  }
  void check_required() const {
    std::istringstream words(required_);
    std::string all;
    bool missing = false;
    for (std::string w; words >> w;) {
      all += (all.empty() ? "" : " and ") + w;
      missing = missing || (w == "--scene" && scene.empty()) || (w == "--records" && records.empty()) ||
                (w == "--out" && out.empty()) || (w == "--label" && label.empty()) ||
                (w == "--resolutions" && resolutions.empty());
    }
    if (missing) throw std::runtime_error("need " + all);
  }
  bool read_one(ArgReader& r, const std::string& name) {
    const char* n = name.c_str();
    if (name == "--scene") return r.value(n, scene);
    if (name == "--records") return r.value(n, records);
    if (name == "--out") return r.value(n, out);
    if (name == "--label") return r.value(n, label);
    if (name == "--resolutions") return r.list(n, resolutions);
    if (name == "--set") return r.append(n, sets);
    if (name == "--known-failure") return r.append(n, known_failures);
    if (name == "--checks") return r.flag(n, checks);
    if (name == "--report-only") return r.flag(n, report_only);
    if (name == "--keep") return r.flag(n, keep);
    throw std::logic_error("RungArgs: '" + name + "' is no shared rung option");
  }
  std::string taken_, required_;
};

// A rung's main: `body` reads the arguments, runs and returns the exit
// status (0 passed, 1 a check failed); an exception (bad usage, a failed
// run) prints `error_prefix` and its message on stderr and exits with 2.
template <class Body>
int rung_main(const char* error_prefix, Body&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s%s\n", error_prefix, e.what());
    return 2;
  }
}
// The same for a rung whose arguments are `Args` (a RungArgs): parses them
// and returns run(args).
template <class Args, class Run>
int rung_main(const char* error_prefix, int argc, char** argv, Run&& run) {
  return rung_main(error_prefix, [&] {
    Args args;
    args.parse(argc, argv);
    return run(static_cast<const Args&>(args));
  });
}

// A run of `scene` through the pipeline of `rubble run`, quietly, with its
// output (snapshots, conserved.csv) in the folder `out`, emptied first.
inline FinalState run_into(const Scene& scene, const std::filesystem::path& out) {
  std::filesystem::remove_all(out);
  RunOptions opt;
  opt.out_dir = out.string();
  opt.write_output = true;
  opt.quiet = true;
  return run_scene(scene, opt);
}

// The same run without output: the final state only.
inline FinalState run_in_memory(const Scene& scene) {
  RunOptions opt;
  opt.write_output = false;
  opt.quiet = true;
  return run_scene(scene, opt);
}

// The snapshots a run wrote into `out` for the scene's output name, in order
// (snapshot_filename's numbering, up to the first missing one).
inline std::vector<std::filesystem::path> snapshot_files(const std::filesystem::path& out, const std::string& name) {
  std::vector<std::filesystem::path> files;
  for (int k = 0;; ++k) {
    std::filesystem::path f = out / snapshot_filename(name, k);
    if (!std::filesystem::exists(f)) return files;
    files.push_back(std::move(f));
  }
}

// The keys a record opens with (docs/report-format.md): the rung, the case,
// the resolution and what it counts, the particle count and the dimension;
// the rung appends the rest with Json::with.
inline Json record_head(const std::string& rung, const std::string& case_name, const Json& resolution,
                        const std::string& resolution_name, const Json& n_particles, int dimension) {
  return Json::object({{"rung", rung},
                       {"case", case_name},
                       {"resolution", resolution},
                       {"resolution_name", resolution_name},
                       {"n_particles", n_particles},
                       {"dimension", dimension}});
}

}  // namespace rubble::verification
