// conserved.csv writer and the measurement of conserved quantities.
// See rubble/io/conserved_log.hpp.
#include "rubble/io/conserved_log.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <stdexcept>
#include <vector>

namespace rubble {
namespace {

const char* const kAxis[3] = {"x", "y", "z"};

// The angular-momentum components logged in `dim` dimensions.
std::vector<int> angular_components(int dim) {
  if (dim == 2) return {2};
  if (dim == 3) return {0, 1, 2};
  return {};
}

}  // namespace

std::string ConservedLog::header(int dimension) {
  if (dimension < 1 || dimension > 3) throw std::invalid_argument("ConservedLog: dimension must be 1, 2 or 3");
  std::string h = "time,step,dt,mass";
  for (int k = 0; k < dimension; ++k) h += std::string(",momentum_") + kAxis[k];
  for (int k : angular_components(dimension)) h += std::string(",angular_momentum_") + kAxis[k];
  h += ",kinetic,internal,gravitational,total,wall_work,floor_energy,booked_total";
  return h;
}

CsvLog::CsvLog(const std::string& path, const std::string& header)
    : path_(path), file_(nullptr, &std::fclose) {
  file_.reset(std::fopen(path_.c_str(), "w"));
  if (!file_) throw std::runtime_error("'" + path_ + "': cannot create: " + std::strerror(errno));
  if (std::fprintf(file_.get(), "%s\n", header.c_str()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("'" + path_ + "': writing the header failed: " + std::strerror(errno));
}

CsvLog::CsvLog(const std::string& path, const std::string& header, const std::string& history, std::int64_t last_step)
    : path_(path), file_(nullptr, &std::fclose) {
  std::string kept = header + "\n";
  if (std::ifstream in(history); in) {
    std::string line;
    std::getline(in, line);
    if (line != header)
      throw std::runtime_error("'" + history + "': its header is not this run's (" + header + "); cannot continue it");
    while (std::getline(in, line)) {
      const auto a = line.find(','), b = a == std::string::npos ? a : line.find(',', a + 1);
      if (b == std::string::npos) continue;  // a line cut short by the interruption
      std::int64_t step = 0;
      try {
        step = std::stoll(line.substr(a + 1, b - a - 1));
      } catch (const std::exception&) {
        continue;
      }
      if (step <= last_step) kept += line + "\n";
    }
  }
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << kept;
    if (!out.flush()) throw std::runtime_error("'" + tmp + "': cannot write: " + std::strerror(errno));
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("'" + path_ + "': rename failed: " + std::strerror(errno));
  }
  file_.reset(std::fopen(path_.c_str(), "a"));
  if (!file_) throw std::runtime_error("'" + path_ + "': cannot open to append: " + std::strerror(errno));
}

void CsvLog::append_line(const std::string& line) {
  if (std::fputs((line + "\n").c_str(), file_.get()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("'" + path_ + "': write failed: " + std::strerror(errno));
}

void CsvLine::put(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  if (!text.empty()) text += ',';
  text += buf;
}
void CsvLine::put(const std::string& v) {
  if (!text.empty()) text += ',';
  text += v;
}
void CsvLine::put(std::int64_t v) {
  if (!text.empty()) text += ',';
  text += std::to_string(v);
}

ConservedLog::ConservedLog(const std::string& path, int dimension) : CsvLog(path, header(dimension)), dim_(dimension) {}

ConservedLog::ConservedLog(const std::string& path, int dimension, const std::string& history, std::int64_t last_step)
    : CsvLog(path, header(dimension), history, last_step), dim_(dimension) {}

void ConservedLog::append(const ConservedRecord& r) {
  CsvLine line;
  line.put(r.time);
  line.put(r.step);
  line.put(r.dt);
  line.put(r.mass);
  for (int k = 0; k < dim_; ++k) line.put(r.momentum[k]);
  for (int k : angular_components(dim_)) line.put(r.angular_momentum[k]);
  line.put(r.kinetic);
  line.put(r.internal);
  line.put(r.gravitational);
  line.put(r.total);
  line.put(r.wall_work);
  line.put(r.floor_energy);
  line.put(r.booked_total);
  append_line(line.text);
}

template <int D>
ConservedRecord measure_conserved(const ParticleStore<D>& ps, double time, std::int64_t step, double dt,
                                  const Vec<D>& g) {
  const StoreView<D> s = const_cast<ParticleStore<D>&>(ps).view();  // read only
  ConservedSums sum;
  for (std::size_t i = 0; i < ps.n; ++i) sum = sum + conserved_particle<D>(s, i, g);
  return conserved_record(sum, time, step, dt);
}

ConservedRecord conserved_record(const ConservedSums& sum, double time, std::int64_t step, double dt) {
  ConservedRecord r;
  r.time = time;
  r.step = step;
  r.dt = dt;
  r.mass = sum.mass;
  for (int k = 0; k < 3; ++k) {
    r.momentum[k] = sum.momentum[k];
    r.angular_momentum[k] = sum.angular_momentum[k];
  }
  r.kinetic = sum.kinetic;
  r.internal = sum.internal;
  r.gravitational = sum.gravitational;
  r.total = r.kinetic + r.internal + r.gravitational;
  r.booked_total = r.total;
  return r;
}

template ConservedRecord measure_conserved<1>(const ParticleStore<1>&, double, std::int64_t, double, const Vec<1>&);
template ConservedRecord measure_conserved<2>(const ParticleStore<2>&, double, std::int64_t, double, const Vec<2>&);
template ConservedRecord measure_conserved<3>(const ParticleStore<3>&, double, std::int64_t, double, const Vec<3>&);

}  // namespace rubble
