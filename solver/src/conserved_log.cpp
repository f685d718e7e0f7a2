// conserved.csv writer and the measurement of conserved quantities.
// See rubble/io/conserved_log.hpp.
#include "rubble/io/conserved_log.hpp"

#include <cerrno>
#include <cstring>
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
  h += ",kinetic,internal,gravitational,total";
  return h;
}

ConservedLog::ConservedLog(const std::string& path, int dimension)
    : path_(path), dim_(dimension), file_(nullptr, &std::fclose) {
  if (dim_ < 1 || dim_ > 3) throw std::invalid_argument("ConservedLog: dimension must be 1, 2 or 3");
  file_.reset(std::fopen(path_.c_str(), "w"));
  if (!file_) throw std::runtime_error("conserved log '" + path_ + "': cannot create: " + std::strerror(errno));
  if (std::fprintf(file_.get(), "%s\n", header(dim_).c_str()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("conserved log '" + path_ + "': writing the header failed");
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
  line += '\n';
  if (std::fputs(line.c_str(), file_.get()) < 0 || std::fflush(file_.get()) != 0)
    throw std::runtime_error("conserved log '" + path_ + "': write failed: " + std::strerror(errno));
}

template <int D>
ConservedRecord measure_conserved(const ParticleStore<D>& ps, double time, std::int64_t step, double dt) {
  ConservedRecord r;
  r.time = time;
  r.step = step;
  r.dt = dt;
  const bool has_u = !ps.u.empty();
  const bool has_phi = !ps.phi.empty();  // self-gravity on
  for (std::size_t i = 0; i < ps.n; ++i) {
    const double m = ps.m[i];
    double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) {
      x[k] = ps.x[i][k];
      v[k] = ps.v[i][k];
    }
    r.mass += m;
    for (int k = 0; k < 3; ++k) r.momentum[k] += m * v[k];
    // L = m x cross v; with the missing axes zero this gives L_z alone in
    // 2-D and nothing in 1-D.
    r.angular_momentum[0] += m * (x[1] * v[2] - x[2] * v[1]);
    r.angular_momentum[1] += m * (x[2] * v[0] - x[0] * v[2]);
    r.angular_momentum[2] += m * (x[0] * v[1] - x[1] * v[0]);
    r.kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (has_u) r.internal += m * ps.u[i];
    if (has_phi) r.gravitational += 0.5 * m * double(ps.phi[i]);
  }
  r.total = r.kinetic + r.internal + r.gravitational;
  return r;
}

template ConservedRecord measure_conserved<1>(const ParticleStore<1>&, double, std::int64_t, double);
template ConservedRecord measure_conserved<2>(const ParticleStore<2>&, double, std::int64_t, double);
template ConservedRecord measure_conserved<3>(const ParticleStore<3>&, double, std::int64_t, double);

}  // namespace rubble
