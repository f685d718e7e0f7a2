#pragma once
// Reading a run's conserved.csv (solver/include/rubble/io/conserved_log.hpp
// writes it) back in a rung: the time, energy and momentum columns, found by
// name.
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
};

inline std::vector<ConservedRow> read_conserved_csv(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read " + path);
  std::string line;
  std::getline(f, line);
  std::vector<std::string> cols;
  {
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cols.push_back(c);
  }
  auto col = [&](const std::string& name) {
    const auto it = std::find(cols.begin(), cols.end(), name);
    if (it == cols.end()) throw std::runtime_error(path + ": no column " + name);
    return std::size_t(it - cols.begin());
  };
  const std::size_t ct = col("time"), ck = col("kinetic"), ci = col("internal"), cg = col("gravitational"),
                    ce = col("total");
  const char* momentum_names[3] = {"momentum_x", "momentum_y", "momentum_z"};
  std::size_t cp[3];
  for (int k = 0; k < 3; ++k) {
    const auto it = std::find(cols.begin(), cols.end(), momentum_names[k]);
    cp[k] = it == cols.end() ? cols.size() : std::size_t(it - cols.begin());  // cols.size(): not written
  }
  std::vector<ConservedRow> rows;
  while (std::getline(f, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) v.push_back(std::stod(c));
    if (v.size() != cols.size()) throw std::runtime_error(path + ": a row with " + std::to_string(v.size()) +
                                                          " values under " + std::to_string(cols.size()) + " columns");
    rows.push_back({v[ct], v[ck], v[ci], v[cg], v[ce],
                    {cp[0] < v.size() ? v[cp[0]] : 0.0, cp[1] < v.size() ? v[cp[1]] : 0.0,
                     cp[2] < v.size() ? v[cp[2]] : 0.0}});
  }
  return rows;
}

}  // namespace rubble::verification
