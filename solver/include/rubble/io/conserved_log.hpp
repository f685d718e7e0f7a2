#pragma once
// conserved.csv: one line of conserved quantities per logged step
// (DESIGN.md, "conserved.csv"). Columns, by dimension:
//   time,step,dt,mass,
//   momentum_x[,momentum_y[,momentum_z]]                (Dim columns)
//   [angular_momentum_z]                                (2-D: L_z only)
//   [angular_momentum_x,angular_momentum_y,angular_momentum_z]  (3-D)
//   kinetic,internal,gravitational,total,
//   wall_work,floor_energy,booked_total
// wall_work: the work the held (boundary) particles did on the rest since
// the run began; floor_energy: the energy the internal-energy floor added
// (eos.hpp); booked_total = total - wall_work - floor_energy, what the
// equations conserve (drivers/step_sequence.hpp, the energy watchdog).
// 1-D has no angular momentum. Values are written with full double
// precision (%.17g) and each line is flushed, so the file is complete up to
// the last step even if the run dies.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "rubble/io/conserved_sums.hpp"
#include "rubble/particles/particle_store.hpp"

namespace rubble {

struct ConservedRecord {
  double time = 0;
  std::int64_t step = 0;
  double dt = 0;
  double mass = 0;
  double momentum[3] = {0, 0, 0};          // components beyond Dim are 0
  double angular_momentum[3] = {0, 0, 0};  // L = sum m x cross v; 2-D: only [2]
  double kinetic = 0;                      // sum 1/2 m |v|^2
  double internal = 0;                     // sum m u
  double gravitational = 0;                // 1/2 sum m phi (self-gravity; 0 without)
  double total = 0;                        // kinetic + internal + gravitational
  double wall_work = 0;                    // work of held particles on the rest, since the start [J]
  double floor_energy = 0;                 // energy added by the internal-energy floor, since the start [J]
  double booked_total = 0;                 // total - wall_work - floor_energy
  // Sets the booked columns from a run's books.
  void book(double wall, double floor) {
    wall_work = wall;
    floor_energy = floor;
    booked_total = total - wall - floor;
  }
};

// A CSV file written a line at a time and flushed after each (so it is
// complete up to the last line if the run dies), whose first two columns
// are time and step: conserved.csv, boundary_forces.csv.
class CsvLog {
 public:
  // Creates (truncates) `path` and writes `header`. Throws
  // std::runtime_error naming the file if it cannot.
  CsvLog(const std::string& path, const std::string& header);
  // A resumed run (issue #13): `path` gets the header and the rows of
  // `history` (the same file of the interrupted run, may be `path` itself
  // or missing) up to and including step `last_step`, written atomically;
  // later rows are appended. A history with another header is an error
  // naming it.
  CsvLog(const std::string& path, const std::string& header, const std::string& history, std::int64_t last_step);
  void append_line(const std::string& line);  // without the newline

 private:
  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
};

// One line of such a file, values in full double precision (%.17g).
struct CsvLine {
  std::string text;
  void put(double v);
  void put(std::int64_t v);
  void put(const std::string& v);  // a field without commas or quotes (names)
};

class ConservedLog : public CsvLog {
 public:
  ConservedLog(const std::string& path, int dimension);
  ConservedLog(const std::string& path, int dimension, const std::string& history, std::int64_t last_step);
  void append(const ConservedRecord& r);
  // The header line for `dimension`, without the newline.
  static std::string header(int dimension);

 private:
  int dim_;
};

// Mass, momentum, angular momentum (about the origin), kinetic and internal
// energy of the particles, and the gravitational energy 1/2 Σ m phi from
// the potential of the last evaluation (0 when gravity is off).
// Sums run in double whatever Real is.
template <int D>
ConservedRecord measure_conserved(const ParticleStore<D>& ps, double time, std::int64_t step, double dt,
                                  const Vec<D>& g = Vec<D>::zero());
// The record of summed terms (conserved_sums.hpp); total = kinetic + internal + gravitational.
ConservedRecord conserved_record(const ConservedSums& sum, double time, std::int64_t step, double dt);

}  // namespace rubble
