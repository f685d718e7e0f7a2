#pragma once
// Shared by the unit tests that read a run's conserved.csv: the values of
// column `name` in `dir`/conserved.csv, one per row (empty when the column
// is missing).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace rubble::test {

inline std::vector<double> conserved_column(const std::filesystem::path& dir, const std::string& name) {
  std::ifstream f(dir / "conserved.csv");
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

}  // namespace rubble::test
