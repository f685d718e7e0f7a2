#pragma once
// Reading a run's CSV files back in a rung: any column by name, and
// conserved.csv's (solver/include/rubble/io/conserved_log.hpp writes it)
// time, energy, momentum and angular momentum columns.
#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rubble::verification {

struct ConservedRow {
  double t, kinetic, internal, gravitational, total;
  double momentum[3];  // the components the run's dimension has; 0 for the others
  double angular_momentum[3];  // likewise (2-D: z only; 1-D: none)
};

// A run's CSV file opened at its first row: the stream and the header's
// column names (throws naming the file when it cannot be read).
struct CsvFile {
  std::ifstream f;
  std::vector<std::string> cols;
  explicit CsvFile(const std::string& path) : f(path) {
    if (!f) throw std::runtime_error("cannot read " + path);
    std::string line;
    std::getline(f, line);
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
  }
};

// Column `name` of any CSV file a run writes (conserved.csv,
// boundary_forces.csv, regions.csv), as numbers, one per row.
inline std::vector<double> read_csv_column(const std::string& path, const std::string& name) {
  CsvFile csv(path);
  std::ifstream& f = csv.f;
  const std::vector<std::string>& cols = csv.cols;
  std::string line;
  const auto it = std::find(cols.begin(), cols.end(), name);
  if (it == cols.end()) throw std::runtime_error(path + ": no column " + name);
  const std::size_t col = std::size_t(it - cols.begin());
  std::vector<double> out;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string c;
    for (std::size_t k = 0; k <= col && std::getline(ss, c, ','); ++k)
      if (k == col) out.push_back(std::stod(c));
  }
  return out;
}

inline std::vector<ConservedRow> read_conserved_csv(const std::string& path) {
  CsvFile csv(path);
  std::ifstream& f = csv.f;
  const std::vector<std::string>& cols = csv.cols;
  std::string line;
  auto col = [&](const std::string& name) {
    const auto it = std::find(cols.begin(), cols.end(), name);
    if (it == cols.end()) throw std::runtime_error(path + ": no column " + name);
    return std::size_t(it - cols.begin());
  };
  const std::size_t ct = col("time"), ck = col("kinetic"), ci = col("internal"), cg = col("gravitational"),
                    ce = col("total");
  auto optional = [&](const char* name) {  // cols.size(): not written
    const auto it = std::find(cols.begin(), cols.end(), name);
    return it == cols.end() ? cols.size() : std::size_t(it - cols.begin());
  };
  const std::size_t cp[3] = {optional("momentum_x"), optional("momentum_y"), optional("momentum_z")};
  const std::size_t cl[3] = {optional("angular_momentum_x"), optional("angular_momentum_y"),
                             optional("angular_momentum_z")};
  std::vector<ConservedRow> rows;
  while (std::getline(f, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) v.push_back(std::stod(c));
    if (v.size() != cols.size()) throw std::runtime_error(path + ": a row with " + std::to_string(v.size()) +
                                                          " values under " + std::to_string(cols.size()) + " columns");
    auto at = [&](std::size_t c) { return c < v.size() ? v[c] : 0.0; };
    rows.push_back({v[ct], v[ck], v[ci], v[cg], v[ce], {at(cp[0]), at(cp[1]), at(cp[2])},
                    {at(cl[0]), at(cl[1]), at(cl[2])}});
  }
  return rows;
}

}  // namespace rubble::verification
