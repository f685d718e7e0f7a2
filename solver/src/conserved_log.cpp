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
  std::string h = "time,step,dt,mass";
  for (int k = 0; k < dimension; ++k) h += std::string(",momentum_") + kAxis[k];
  for (int k : angular_components(dimension)) h += std::string(",angular_momentum_") + kAxis[k];
  h += ",kinetic,internal,gravitational,total,wall_work,floor_energy,booked_total";
  return h;
}

ConservedLog::ConservedLog(const std::string& path, int dimension)
    : path_(path), dim_(dimension), file_(nullptr, &std::fclose) {
  if (dim_ < 1 || dim_ > 3) throw std::invalid_argument("ConservedLog: dimension must be 1, 2 or 3");
  file_.reset(std::fopen(path_.c_str(), "w"));
  if (!file_) throw std::runtime_error("conserved log '" + path_ + "': cannot create: " + std::strerror(errno));
  if (std::fprintf(file_.get(), "%s\n", header(dim_).c_str()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("conserved log '" + path_ + "': writing the header failed: " + std::strerror(errno));
}

ConservedLog::ConservedLog(const std::string& path, int dimension, const std::string& history, std::int64_t last_step)
    : path_(path), dim_(dimension), file_(nullptr, &std::fclose) {
  if (dim_ < 1 || dim_ > 3) throw std::invalid_argument("ConservedLog: dimension must be 1, 2 or 3");
  std::string kept = header(dim_) + "\n";
  if (std::ifstream in(history); in) {
    std::string line;
    std::getline(in, line);
    if (line != header(dim_))
      throw std::runtime_error("conserved log '" + history + "': its header is not that of a " + std::to_string(dim_) +
                               "-D run; cannot continue it");
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
    if (!out.flush())
      throw std::runtime_error("conserved log '" + tmp + "': cannot write: " + std::strerror(errno));
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("conserved log '" + path_ + "': rename failed: " + std::strerror(errno));
  }
  file_.reset(std::fopen(path_.c_str(), "a"));
  if (!file_) throw std::runtime_error("conserved log '" + path_ + "': cannot open to append: " + std::strerror(errno));
}

void ConservedLog::append(const ConservedRecord& r) {
  std::string line;
  char buf[40];
  auto put = [&](double v) {
    std::snprintf(buf, sizeof buf, "%.17g", v);
    if (!line.empty()) line += ',';
    line += buf;
  };
  put(r.time);
  line += ',' + std::to_string(r.step);
  put(r.dt);
  put(r.mass);
  for (int k = 0; k < dim_; ++k) put(r.momentum[k]);
  for (int k : angular_components(dim_)) put(r.angular_momentum[k]);
  put(r.kinetic);
  put(r.internal);
  put(r.gravitational);
  put(r.total);
  put(r.wall_work);
  put(r.floor_energy);
  put(r.booked_total);
  line += '\n';
  if (std::fputs(line.c_str(), file_.get()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("conserved log '" + path_ + "': write failed: " + std::strerror(errno));
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
