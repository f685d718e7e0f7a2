#pragma once
// Shared by the unit tests that read a run's CSV files (conserved.csv,
// boundary_forces.csv): the values of one column, one per row.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace rubble::test {

// The values of column `name` of the CSV file `path` (its first line the
// header), one per row; empty when the column is missing.
inline std::vector<double> csv_column(const std::filesystem::path& path, const std::string& name) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  std::vector<std::string> head;
  {
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) head.push_back(c);
  }
  const auto col = std::find(head.begin(), head.end(), name) - head.begin();
  std::vector<double> out;
  if (std::size_t(col) >= head.size()) return out;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string c;
    for (long k = 0; k <= col && std::getline(ss, c, ','); ++k)
      if (k == col) out.push_back(std::stod(c));
  }
  return out;
}

inline std::vector<double> conserved_column(const std::filesystem::path& dir, const std::string& name) {
  return csv_column(dir / "conserved.csv", name);
}

}  // namespace rubble::test
