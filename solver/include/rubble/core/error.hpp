#pragma once
// Errors a user can act on. InputError names the file, the key and the
// problem; the command-line program prints what() and exits non-zero.
#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rubble {

class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& key, const std::string& problem)
      : std::runtime_error(file + ": " + (key.empty() ? std::string() : "key '" + key + "': ") + problem),
        file_(file), key_(key) {}
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_, key_;
};

// A run that cannot go on (non-finite value, collapsing time step).
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  // where the wall time went until the failure (the run loop fills it on
  // the way out, so `rubble run --timings` prints it on a failed run too);
  // empty for a failure before the loop
  std::vector<std::pair<std::string, double>> phase_seconds;
  double wall_seconds = 0;
};

// The energy watchdog stopped the run (issue #50 item 1): one step changed
// the booked total energy by more than its bound and the integrator could not
// retry it with a smaller step. The particles that gained the most, by index
// in the store as it is after the step, with their gains [J].
class EnergyJumpError : public RunError {
 public:
  EnergyJumpError(const std::string& what, double change, double bound, std::vector<std::size_t> particles,
                  std::vector<double> gains)
      : RunError(what), change(change), bound(bound), particles(std::move(particles)), gains(std::move(gains)) {}
  double change, bound;
  std::vector<std::size_t> particles;
  std::vector<double> gains;
};

// Output that could not be written (an unwritable or full disk, a
// directory another run holds): the message carries the OS's reason.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A number for a message, as %g prints it (never "0.000000" for 1e-9).
inline std::string fmt_g(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

}  // namespace rubble
