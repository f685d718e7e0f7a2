// HDF5 snapshots through the HDF5 C API. See rubble/io/snapshot.hpp.
#include "rubble/io/snapshot.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

namespace rubble {
namespace {

// Bumped whenever the restart group changes incompatibly.
constexpr int kRestartFormat = 2;  // 2: the energy books (issue #50)

// ---- errors ----------------------------------------------------------------

// While alive, HDF5 does not print its error stack to stderr: failures are
// reported once, by the exception thrown below.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// HDF5's own account of the last failure: the API-level message and the
// innermost one (the root cause, e.g. the OS error), then clear the stack.
std::string hdf5_reason() {
  std::vector<std::string> messages;
  auto walk = [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
    if (e->desc && *e->desc) static_cast<std::vector<std::string>*>(out)->emplace_back(e->desc);
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, walk, &messages);
  H5Eclear2(H5E_DEFAULT);
  if (messages.empty()) return {};
  if (messages.size() == 1) return messages.front();
  return messages.front() + " (" + messages.back() + ")";
}

[[noreturn]] void fail(const std::string& file, const std::string& call, const std::string& why = {}) {
  std::string msg = "snapshot '" + file + "': " + call + " failed";
  const std::string reason = why.empty() ? hdf5_reason() : why;
  if (!reason.empty()) msg += ": " + reason;
  throw std::runtime_error(msg);
}

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle(hid_t id, Closer closer, const std::string& file, const std::string& call)
      : id_(id), closer_(closer) {
    if (id_ < 0) fail(file, call);
  }
  ~Handle() {
    if (id_ >= 0) closer_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  // Close now and check the result (matters for files: H5Fclose flushes).
  void close(const std::string& file, const std::string& call) {
    const herr_t rc = closer_(id_);
    id_ = -1;
    if (rc < 0) fail(file, call);
  }

 private:
  hid_t id_;
  Closer closer_;
};

void check(herr_t rc, const std::string& file, const std::string& call) {
  if (rc < 0) fail(file, call);
}

// ---- element types -----------------------------------------------------------

// How one element of a field array is laid out: its scalar type and how
// many scalars it holds. A new kind of field (e.g. a tensor) adds a case.
template <class T>
struct Layout;

template <>
struct Layout<Real> {
  using Scalar = Real;
  static constexpr int components = 1;
  static constexpr bool vector = false;
};
template <>
struct Layout<std::int32_t> {
  using Scalar = std::int32_t;
  static constexpr int components = 1;
  static constexpr bool vector = false;
};
template <int D>
struct Layout<Vec<D>> {
  using Scalar = Real;
  static constexpr int components = D;
  static constexpr bool vector = true;
  static_assert(sizeof(Vec<D>) == D * sizeof(Real), "Vec<D> must be D packed Reals");
};
// A D x D tensor (the deviatoric stress S): dataset N x D x D.
template <int D>
struct Layout<Mat<D>> {
  using Scalar = Real;
  static constexpr int components = D * D;
  static constexpr bool vector = true;
  static_assert(sizeof(Mat<D>) == D * D * sizeof(Real), "Mat<D> must be D*D packed Reals");
};
template <class T>
struct IsTensor : std::false_type {};
template <int D>
struct IsTensor<Mat<D>> : std::true_type {
  static constexpr int dim = D;
};

// HDF5 memory type of a scalar; also the file type (native Real, int32).
template <class S>
hid_t native_type() {
  if constexpr (std::is_same_v<S, double>) return H5T_NATIVE_DOUBLE;
  else if constexpr (std::is_same_v<S, float>) return H5T_NATIVE_FLOAT;
  else {
    static_assert(std::is_same_v<S, std::int32_t>);
    return H5T_NATIVE_INT32;
  }
}

// ---- attributes ----------------------------------------------------------------

void write_attr(hid_t obj, const std::string& file, const char* name, hid_t type, const void* value) {
  const std::string where = std::string("'") + name + "'";
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, file, "H5Screate(" + where + ")");
  Handle attr(H5Acreate2(obj, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, file,
              "H5Acreate2(" + where + ")");
  check(H5Awrite(attr.get(), type, value), file, "H5Awrite(" + where + ")");
}

// Variable-length UTF-8 string: h5py reads it back as a Python str.
void write_string_attr(hid_t obj, const std::string& file, const char* name, const std::string& value) {
  const std::string where = std::string("'") + name + "'";
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose, file, "H5Tcopy(" + where + ")");
  check(H5Tset_size(type.get(), H5T_VARIABLE), file, "H5Tset_size(" + where + ")");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), file, "H5Tset_cset(" + where + ")");
  const char* text = value.c_str();
  write_attr(obj, file, name, type.get(), &text);
}

void read_attr(hid_t obj, const std::string& file, const char* name, hid_t type, void* value) {
  const std::string where = std::string("'") + name + "'";
  Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose, file, "H5Aopen(" + where + ")");
  check(H5Aread(attr.get(), type, value), file, "H5Aread(" + where + ")");
}

// Reads variable- and fixed-length string attributes alike.
std::string read_string_attr(hid_t obj, const std::string& file, const char* name) {
  const std::string where = std::string("'") + name + "'";
  Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose, file, "H5Aopen(" + where + ")");
  Handle ftype(H5Aget_type(attr.get()), H5Tclose, file, "H5Aget_type(" + where + ")");
  if (H5Tget_class(ftype.get()) != H5T_STRING) fail(file, "reading " + where, "attribute is not a string");
  const htri_t variable = H5Tis_variable_str(ftype.get());
  if (variable < 0) fail(file, "H5Tis_variable_str(" + where + ")");

  Handle mtype(H5Tcopy(H5T_C_S1), H5Tclose, file, "H5Tcopy(" + where + ")");
  check(H5Tset_cset(mtype.get(), H5Tget_cset(ftype.get())), file, "H5Tset_cset(" + where + ")");
  if (variable) {
    check(H5Tset_size(mtype.get(), H5T_VARIABLE), file, "H5Tset_size(" + where + ")");
    char* text = nullptr;
    check(H5Aread(attr.get(), mtype.get(), &text), file, "H5Aread(" + where + ")");
    std::string out = text ? text : "";
    H5free_memory(text);
    return out;
  }
  const std::size_t size = H5Tget_size(ftype.get());
  if (size == 0) fail(file, "H5Tget_size(" + where + ")");
  check(H5Tset_size(mtype.get(), size), file, "H5Tset_size(" + where + ")");
  std::string out(size, '\0');
  check(H5Aread(attr.get(), mtype.get(), out.data()), file, "H5Aread(" + where + ")");
  out.resize(out.find_last_not_of('\0') + 1);  // drop NUL padding (npos + 1 == 0)
  return out;
}

bool has_attr(hid_t obj, const std::string& file, const char* name) {
  const htri_t rc = H5Aexists(obj, name);
  if (rc < 0) fail(file, std::string("H5Aexists('") + name + "')");
  return rc > 0;
}

// ---- datasets --------------------------------------------------------------------

template <class T>
void write_dataset(hid_t h5file, const std::string& file, const std::string& name, std::string_view unit,
                   const std::vector<T>& data) {
  using L = Layout<T>;
  const std::string where = "'" + name + "'";
  hsize_t dims[3] = {data.size(), hsize_t(L::components), 1};
  int rank = L::vector ? 2 : 1;
  if constexpr (IsTensor<T>::value) {  // N x D x D
    dims[1] = dims[2] = hsize_t(IsTensor<T>::dim);
    rank = 3;
  }
  const hid_t type = native_type<typename L::Scalar>();
  Handle space(H5Screate_simple(rank, dims, nullptr), H5Sclose, file, "H5Screate_simple(" + where + ")");
  Handle dset(H5Dcreate2(h5file, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
              H5Dclose, file, "H5Dcreate2(" + where + ")");
  if (!data.empty())
    check(H5Dwrite(dset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), file, "H5Dwrite(" + where + ")");
  write_string_attr(dset.get(), file, "unit", std::string(unit));
}

// Reads dataset `name` into `data`; `n` is the particle count seen so far
// (-1 before the first dataset) and is set from this one.
template <class T>
void read_dataset(hid_t h5file, const std::string& file, const std::string& name, std::vector<T>& data,
                  long long& n) {
  using L = Layout<T>;
  const std::string where = "'" + name + "'";
  Handle dset(H5Dopen2(h5file, name.c_str(), H5P_DEFAULT), H5Dclose, file, "H5Dopen2(" + where + ")");
  Handle space(H5Dget_space(dset.get()), H5Sclose, file, "H5Dget_space(" + where + ")");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail(file, "H5Sget_simple_extent_ndims(" + where + ")");
  const int want_rank = IsTensor<T>::value ? 3 : L::vector ? 2 : 1;
  hsize_t dims[3] = {0, 0, 0};
  if (rank != want_rank) {
    fail(file, "reading " + where,
         "dataset has rank " + std::to_string(rank) + ", expected " + std::to_string(want_rank));
  }
  check(H5Sget_simple_extent_dims(space.get(), dims, nullptr), file, "H5Sget_simple_extent_dims(" + where + ")");
  if (IsTensor<T>::value) dims[1] *= dims[2];
  if (L::vector && dims[1] != hsize_t(L::components)) {
    fail(file, "reading " + where,
         "dataset has " + std::to_string(dims[1]) + " components, expected " + std::to_string(L::components));
  }
  if (n >= 0 && dims[0] != hsize_t(n)) {
    fail(file, "reading " + where,
         "dataset has " + std::to_string(dims[0]) + " particles, other datasets " + std::to_string(n));
  }
  n = static_cast<long long>(dims[0]);
  data.resize(dims[0]);
  if (!data.empty()) {
    const hid_t type = native_type<typename L::Scalar>();
    check(H5Dread(dset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), file, "H5Dread(" + where + ")");
  }
}

// ---- the restart group -------------------------------------------------------------

// A 1-D dataset of int64 or double values (the restart group's lists).
template <class T>
hid_t list_type() {
  return std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
}

template <class T>
void write_list(hid_t loc, const std::string& file, const char* name, const std::vector<T>& v) {
  const std::string where = std::string("'") + name + "'";
  hsize_t dims[1] = {v.size()};
  Handle space(H5Screate_simple(1, dims, nullptr), H5Sclose, file, "H5Screate_simple(" + where + ")");
  Handle dset(H5Dcreate2(loc, name, list_type<T>(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
              file, "H5Dcreate2(" + where + ")");
  if (!v.empty())
    check(H5Dwrite(dset.get(), list_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), file, "H5Dwrite(" + where + ")");
}

template <class T>
std::vector<T> read_list(hid_t loc, const std::string& file, const char* name) {
  const std::string where = std::string("'") + name + "'";
  Handle dset(H5Dopen2(loc, name, H5P_DEFAULT), H5Dclose, file, "H5Dopen2(" + where + ")");
  Handle space(H5Dget_space(dset.get()), H5Sclose, file, "H5Dget_space(" + where + ")");
  if (H5Sget_simple_extent_ndims(space.get()) != 1) fail(file, "reading " + where, "expected a 1-D dataset");
  hsize_t dims[1] = {0};
  check(H5Sget_simple_extent_dims(space.get(), dims, nullptr), file, "H5Sget_simple_extent_dims(" + where + ")");
  std::vector<T> v(dims[0]);
  if (!v.empty())
    check(H5Dread(dset.get(), list_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), file, "H5Dread(" + where + ")");
  return v;
}

template <int D>
void write_restart_group(hid_t h5, const std::string& file, const ParticleStore<D>& ps, const RestartState& r) {
  Handle g(H5Gcreate2(h5, "restart", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, file, "H5Gcreate2('restart')");
  const int format = kRestartFormat, checkpoint = r.checkpoint ? 1 : 0;
  write_attr(g.get(), file, "format", H5T_NATIVE_INT, &format);
  write_attr(g.get(), file, "dt_proposal", H5T_NATIVE_DOUBLE, &r.dt_proposal);
  write_attr(g.get(), file, "next_output", H5T_NATIVE_DOUBLE, &r.next_output);
  write_attr(g.get(), file, "next_snapshot", H5T_NATIVE_INT, &r.next_snapshot);
  write_attr(g.get(), file, "checkpoint", H5T_NATIVE_INT, &checkpoint);
  write_attr(g.get(), file, "wall_work", H5T_NATIVE_DOUBLE, &r.books.wall_work);
  write_attr(g.get(), file, "floor_energy", H5T_NATIVE_DOUBLE, &r.books.floor_energy);
  write_attr(g.get(), file, "floor_events", H5T_NATIVE_INT64, &r.books.floor_events);
  write_attr(g.get(), file, "wall_power", H5T_NATIVE_DOUBLE, &r.books.wall_power);
  write_string_attr(g.get(), file, "scene_file", r.scene_file);
  write_string_attr(g.get(), file, "scene_source", r.scene_source);
  const int n_overrides = static_cast<int>(r.overrides.size()), n_libraries = static_cast<int>(r.libraries.size());
  write_attr(g.get(), file, "overrides", H5T_NATIVE_INT, &n_overrides);
  for (int i = 0; i < n_overrides; ++i)
    write_string_attr(g.get(), file, ("override_" + std::to_string(i)).c_str(), r.overrides[i]);
  write_attr(g.get(), file, "libraries", H5T_NATIVE_INT, &n_libraries);
  for (int i = 0; i < n_libraries; ++i) {
    const std::string k = "library_" + std::to_string(i);
    write_string_attr(g.get(), file, (k + "_spec").c_str(), r.libraries[i].spec);
    write_string_attr(g.get(), file, (k + "_path").c_str(), r.libraries[i].path);
    write_string_attr(g.get(), file, (k + "_text").c_str(), r.libraries[i].text);
  }
  write_list(g.get(), file, "body_first_id", r.body_first_id);
  if (!r.tool_state.empty()) write_list(g.get(), file, "tool_state", r.tool_state);
  // the allocated fields the snapshot proper leaves out
  for (const auto& f : field_table<D>()) {
    if (f.snapshot) continue;
    std::visit(
        [&](auto member) {
          const auto& arr = ps.*member;
          if (!arr.empty()) write_dataset(g.get(), file, std::string(f.name), f.unit, arr);
        },
        f.member);
  }
}

// Reads the fields of the field table found at `loc` whose `snapshot` flag
// is `snapshot_fields` into `out`; `n` as in read_dataset.
template <int D>
void read_fields(hid_t loc, const std::string& path, bool snapshot_fields, ParticleStore<D>& out, long long& n) {
  for (const auto& f : field_table<D>()) {
    if (f.snapshot != snapshot_fields) continue;
    const std::string name(f.name);
    const htri_t exists = H5Lexists(loc, name.c_str(), H5P_DEFAULT);
    if (exists < 0) fail(path, "H5Lexists('" + name + "')");
    if (exists == 0) continue;
    std::visit([&](auto member) { read_dataset(loc, path, name, out.*member, n); }, f.member);
  }
}

RestartState read_restart_attributes(hid_t g, const std::string& path) {
  RestartState r;
  int format = 0, checkpoint = 0, n_overrides = 0, n_libraries = 0;
  read_attr(g, path, "format", H5T_NATIVE_INT, &format);
  if (format != kRestartFormat)
    fail(path, "reading the restart group",
         "restart format " + std::to_string(format) + ", this build reads format " + std::to_string(kRestartFormat));
  read_attr(g, path, "dt_proposal", H5T_NATIVE_DOUBLE, &r.dt_proposal);
  read_attr(g, path, "next_output", H5T_NATIVE_DOUBLE, &r.next_output);
  read_attr(g, path, "next_snapshot", H5T_NATIVE_INT, &r.next_snapshot);
  read_attr(g, path, "checkpoint", H5T_NATIVE_INT, &checkpoint);
  r.checkpoint = checkpoint != 0;
  read_attr(g, path, "wall_work", H5T_NATIVE_DOUBLE, &r.books.wall_work);
  read_attr(g, path, "floor_energy", H5T_NATIVE_DOUBLE, &r.books.floor_energy);
  read_attr(g, path, "floor_events", H5T_NATIVE_INT64, &r.books.floor_events);
  read_attr(g, path, "wall_power", H5T_NATIVE_DOUBLE, &r.books.wall_power);
  r.scene_file = read_string_attr(g, path, "scene_file");
  r.scene_source = read_string_attr(g, path, "scene_source");
  read_attr(g, path, "overrides", H5T_NATIVE_INT, &n_overrides);
  for (int i = 0; i < n_overrides; ++i)
    r.overrides.push_back(read_string_attr(g, path, ("override_" + std::to_string(i)).c_str()));
  read_attr(g, path, "libraries", H5T_NATIVE_INT, &n_libraries);
  for (int i = 0; i < n_libraries; ++i) {
    const std::string k = "library_" + std::to_string(i);
    r.libraries.push_back({read_string_attr(g, path, (k + "_spec").c_str()),
                           read_string_attr(g, path, (k + "_path").c_str()),
                           read_string_attr(g, path, (k + "_text").c_str())});
  }
  r.body_first_id = read_list<std::int64_t>(g, path, "body_first_id");
  const htri_t tools = H5Lexists(g, "tool_state", H5P_DEFAULT);
  if (tools < 0) fail(path, "H5Lexists('tool_state')");
  if (tools > 0) r.tool_state = read_list<double>(g, path, "tool_state");
  return r;
}

// ---- whole files -------------------------------------------------------------------

template <int D>
void write_file(const std::string& file, const ParticleStore<D>& ps, const SnapshotMeta& meta) {
  Handle h5(H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, file, "H5Fcreate");

  const int dimension = D;
  write_attr(h5.get(), file, "time", H5T_NATIVE_DOUBLE, &meta.time);
  write_attr(h5.get(), file, "dimension", H5T_NATIVE_INT, &dimension);
  write_attr(h5.get(), file, "step", H5T_NATIVE_INT64, &meta.step);
  write_string_attr(h5.get(), file, "version", meta.version);
  write_string_attr(h5.get(), file, "commit", meta.commit);
  write_string_attr(h5.get(), file, "scene", meta.scene_text);

  for (const auto& f : field_table<D>()) {
    if (!f.snapshot) continue;
    std::visit(
        [&](auto member) {
          const auto& arr = ps.*member;
          if (arr.empty()) return;  // not allocated: not written
          write_dataset(h5.get(), file, std::string(f.name), f.unit, arr);
        },
        f.member);
  }
  // body: each particle's [[bodies]] entry (issue #52 item 4), from its id
  // and the run's body_first_id (restartable snapshots: a run's own)
  const std::vector<std::int64_t>& first = meta.restart.body_first_id;
  if (meta.restartable && first.size() >= 2 && ps.id.size() == ps.n) {
    std::vector<std::int32_t> body(ps.n);
    for (std::size_t i = 0; i < ps.n; ++i)
      body[i] = std::int32_t(std::upper_bound(first.begin(), first.end(), ps.id[i]) - first.begin() - 1);
    write_dataset(h5.get(), file, "body", "1", body);
  }
  if (meta.restartable) write_restart_group<D>(h5.get(), file, ps, meta.restart);
  h5.close(file, "H5Fclose");
}

}  // namespace

// ---- public API ----------------------------------------------------------------------

template <int D>
void write_snapshot(const std::string& path, const ParticleStore<D>& ps, const SnapshotMeta& meta) {
  // A store whose arrays disagree with n would write an inconsistent file.
  for (const auto& f : field_table<D>()) {
    if (!f.snapshot) continue;
    std::visit(
        [&](auto member) {
          const auto& arr = ps.*member;
          if (!arr.empty() && arr.size() != ps.n) {
            throw std::runtime_error("snapshot '" + path + "': field '" + std::string(f.name) + "' has " +
                                     std::to_string(arr.size()) + " entries but the store has n = " +
                                     std::to_string(ps.n));
          }
        },
        f.member);
  }

  const std::string tmp = path + ".tmp";
  QuietHdf5 quiet;
  try {
    write_file<D>(tmp, ps, meta);  // every handle is closed when this returns or throws
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("snapshot '" + path + "': rename from '" + tmp + "' failed");
  }
}

namespace {

// read_snapshot and read_restart: the snapshot fields, and with `restart`
// the restart group too.
template <int D>
void read_file(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta, bool restart) {
  QuietHdf5 quiet;
  Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path, "H5Fopen");

  int dimension = 0;
  read_attr(h5.get(), path, "dimension", H5T_NATIVE_INT, &dimension);
  if (dimension != D) {
    fail(path, "read_snapshot",
         "file holds a " + std::to_string(dimension) + "-D run, expected " + std::to_string(D) + "-D");
  }
  SnapshotMeta m;
  read_attr(h5.get(), path, "time", H5T_NATIVE_DOUBLE, &m.time);
  read_attr(h5.get(), path, "step", H5T_NATIVE_INT64, &m.step);
  // The strings are informative: a file without them still reads.
  if (has_attr(h5.get(), path, "version")) m.version = read_string_attr(h5.get(), path, "version");
  if (has_attr(h5.get(), path, "commit")) m.commit = read_string_attr(h5.get(), path, "commit");
  if (has_attr(h5.get(), path, "scene")) m.scene_text = read_string_attr(h5.get(), path, "scene");

  ParticleStore<D> out;
  long long n = -1;
  read_fields<D>(h5.get(), path, true, out, n);
  const htri_t has_restart = H5Lexists(h5.get(), "restart", H5P_DEFAULT);
  if (has_restart < 0) fail(path, "H5Lexists('restart')");
  m.restartable = has_restart > 0;
  if (restart) {
    if (!m.restartable)
      fail(path, "reading the restart data",
           "the file has no 'restart' group (not a snapshot written by `rubble run`, or written before restarts existed)");
    Handle g(H5Gopen2(h5.get(), "restart", H5P_DEFAULT), H5Gclose, path, "H5Gopen2('restart')");
    read_fields<D>(g.get(), path, false, out, n);
    m.restart = read_restart_attributes(g.get(), path);
  }
  out.n = n < 0 ? 0 : static_cast<std::size_t>(n);
  h5.close(path, "H5Fclose");

  m.dimension = D;
  ps = std::move(out);
  meta = std::move(m);
}

}  // namespace

SnapshotMeta read_snapshot_meta(const std::string& path) {
  QuietHdf5 quiet;
  Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path, "H5Fopen");
  SnapshotMeta m;
  read_attr(h5.get(), path, "dimension", H5T_NATIVE_INT, &m.dimension);
  read_attr(h5.get(), path, "time", H5T_NATIVE_DOUBLE, &m.time);
  read_attr(h5.get(), path, "step", H5T_NATIVE_INT64, &m.step);
  if (has_attr(h5.get(), path, "version")) m.version = read_string_attr(h5.get(), path, "version");
  if (has_attr(h5.get(), path, "commit")) m.commit = read_string_attr(h5.get(), path, "commit");
  if (has_attr(h5.get(), path, "scene")) m.scene_text = read_string_attr(h5.get(), path, "scene");
  const htri_t has_restart = H5Lexists(h5.get(), "restart", H5P_DEFAULT);
  if (has_restart < 0) fail(path, "H5Lexists('restart')");
  m.restartable = has_restart > 0;
  if (m.restartable) {
    Handle g(H5Gopen2(h5.get(), "restart", H5P_DEFAULT), H5Gclose, path, "H5Gopen2('restart')");
    m.restart = read_restart_attributes(g.get(), path);
  }
  h5.close(path, "H5Fclose");
  return m;
}

template <int D>
SnapshotSummary read_snapshot_summary(const std::string& path) {
  QuietHdf5 quiet;
  Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path, "H5Fopen");
  SnapshotSummary out;
  read_attr(h5.get(), path, "time", H5T_NATIVE_DOUBLE, &out.time);
  for (const auto& f : field_table<D>()) {
    if (!f.snapshot) continue;
    const std::string name(f.name);
    const htri_t exists = H5Lexists(h5.get(), name.c_str(), H5P_DEFAULT);
    if (exists < 0) fail(path, "H5Lexists('" + name + "')");
    if (exists == 0) continue;
    Handle dset(H5Dopen2(h5.get(), name.c_str(), H5P_DEFAULT), H5Dclose, path, "H5Dopen2('" + name + "')");
    Handle space(H5Dget_space(dset.get()), H5Sclose, path, "H5Dget_space('" + name + "')");
    hsize_t dims[3] = {0, 1, 1};
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 1 || rank > 3) fail(path, "reading '" + name + "'", "unexpected rank " + std::to_string(rank));
    check(H5Sget_simple_extent_dims(space.get(), dims, nullptr), path, "H5Sget_simple_extent_dims('" + name + "')");
    out.n = static_cast<std::size_t>(dims[0]);
    out.fields.emplace_back(name, static_cast<int>(rank == 1 ? 1 : rank == 2 ? dims[1] : dims[1] * dims[2]));
  }
  h5.close(path, "H5Fclose");
  return out;
}

template <int D>
void read_snapshot(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta) {
  read_file<D>(path, ps, meta, false);
}

template <int D>
void read_restart(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta) {
  read_file<D>(path, ps, meta, true);
}

template <int D>
std::vector<std::pair<std::string, int>> snapshot_fields(const ParticleStore<D>& ps) {
  std::vector<std::pair<std::string, int>> fields;
  for (const auto& f : field_table<D>()) {
    if (!f.snapshot) continue;
    std::visit(
        [&](auto member) {
          using T = typename std::decay_t<decltype(ps.*member)>::value_type;
          if (!(ps.*member).empty()) fields.emplace_back(std::string(f.name), Layout<T>::components);
        },
        f.member);
  }
  return fields;
}

std::string snapshot_filename(const std::string& stem, int index) {
  char number[32];
  std::snprintf(number, sizeof number, ".%04d.h5", index);
  return stem + number;
}

#define RUBBLE_INSTANTIATE_SNAPSHOT(D)                                                                   \
  template void write_snapshot<D>(const std::string&, const ParticleStore<D>&, const SnapshotMeta&);   \
  template void read_snapshot<D>(const std::string&, ParticleStore<D>&, SnapshotMeta&);                \
  template void read_restart<D>(const std::string&, ParticleStore<D>&, SnapshotMeta&);                 \
  template SnapshotSummary read_snapshot_summary<D>(const std::string&);                               \
  template std::vector<std::pair<std::string, int>> snapshot_fields<D>(const ParticleStore<D>&);
RUBBLE_INSTANTIATE_SNAPSHOT(1)
RUBBLE_INSTANTIATE_SNAPSHOT(2)
RUBBLE_INSTANTIATE_SNAPSHOT(3)
#undef RUBBLE_INSTANTIATE_SNAPSHOT

}  // namespace rubble
