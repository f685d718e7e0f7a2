// Output of runs: HDF5 snapshots, the XDMF index, conserved.csv, progress.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "rubble/io/conserved_log.hpp"
#include "rubble/io/progress.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/io/xdmf.hpp"

namespace fs = std::filesystem;
using namespace rubble;

namespace {

// A fresh directory under the system temp dir, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("rubble_test_io_") + std::to_string(getpid()) + "_" + info->test_suite_name() +
                       "_" + info->name();
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep)) out.push_back(item);
  return out;
}

// Every snapshot field allocated, plus omega and phi (allocated, not
// snapshot fields).
template <int D>
ParticleStore<D> make_store(std::size_t n) {
  ParticleStore<D> ps;
  Features needs;
  needs.summation_density = true;
  needs.gravity = true;  // a_grav (a snapshot field) and phi
  needs.solid = true;     // S (a snapshot field) and dSdt
  needs.boundary = true;  // boundary flags and wall_force (snapshot fields)
  needs.rigid_tools = true;  // tool and tool_offset (snapshot fields)
  needs.porosity = true;    // alpha (a snapshot field) and dalphadt
  needs.plasticity = true;  // eps_p (a snapshot field)
  needs.inelastic_volume = true;  // eps_v (a snapshot field)
  needs.damage = true;  // damage_root, the flaws and flaws_active (snapshot fields)
  needs.viscosity_switch = true;  // av_alpha (a snapshot field) and dav_alpha_dt
  needs.free_slip = needs.wall_friction = true;  // wall_anchor (a snapshot field), the wall fields
  ps.allocate(n, needs);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < D; ++k) {
      ps.x[i][k] = Real(0.1) * Real(i) + Real(k) / Real(3);  // not exact in binary: tests bit-exactness
      ps.v[i][k] = -Real(i) - Real(0.7) * Real(k);
      ps.dvdt[i][k] = 5;
    }
    ps.m[i] = 1 + Real(i) / 7;
    ps.rho[i] = 1000 + Real(i);
    ps.p[i] = Real(1e5) * Real(i);
    ps.u[i] = Real(2.5) + Real(i);
    ps.h[i] = Real(0.01);
    ps.cs[i] = 300 + Real(i);
    ps.material_id[i] = static_cast<std::int32_t>(i % 3);
    ps.omega[i] = Real(0.9);
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) ps.S[i].m[a][b] = Real(0.3) * Real(i) + Real(a) - Real(b) / Real(3);
    ps.boundary[i] = static_cast<std::int32_t>(i % 2);
    ps.damage_root[i] = Real(0.01) * Real(i);
    ps.flaw_count[i] = static_cast<std::int32_t>(1 + i % 4);
    ps.flaw_eps_min[i] = Real(1e-4) / Real(1 + i);
    ps.flaw_eps_max[i] = Real(2e-4) / Real(1 + i);
    ps.flaws_active[i] = Real(i % 4);
    ps.av_alpha[i] = Real(0.1) + Real(0.07) * Real(i);
    for (int k = 0; k < D; ++k) ps.wall_anchor[i][k] = ps.x[i][k] - Real(1e-7) * Real(i + k);
  }
  return ps;
}

template <class T>
bool same(const std::vector<T>& a, const std::vector<T>& b) {
  return a == b;
}
template <int D>
bool same(const std::vector<Vec<D>>& a, const std::vector<Vec<D>>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < D; ++k)
      if (a[i][k] != b[i][k]) return false;
  return true;
}

SnapshotMeta make_meta() {
  SnapshotMeta meta;
  meta.time = 1.25e-3;
  meta.step = 4242;
  meta.scene_text = "[simulation]\ndimension = 3\nname = \"rho \xcf\x81 test\"\n# comment, \"quotes\" & <tags>\n";
  meta.version = "0.1.0";
  meta.commit = "abc1234";
  return meta;
}

// Minimal HDF5 reads for checking files independently of read_snapshot.
bool h5_attr_exists(hid_t obj, const char* name) { return H5Aexists(obj, name) > 0; }
std::string h5_vlen_string_attr(hid_t obj, const char* name) {
  const hid_t attr = H5Aopen(obj, name, H5P_DEFAULT);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  char* text = nullptr;
  std::string out = "<unreadable>";
  if (attr >= 0 && H5Aread(attr, type, &text) >= 0 && text) out = text;
  H5free_memory(text);
  H5Tclose(type);
  if (attr >= 0) H5Aclose(attr);
  return out;
}

template <int N>
struct Dim {
  static constexpr int value = N;
};
template <class T>
class SnapshotTest : public ::testing::Test {};
using Dims = ::testing::Types<Dim<1>, Dim<2>, Dim<3>>;
TYPED_TEST_SUITE(SnapshotTest, Dims);

}  // namespace

// ---- snapshots -----------------------------------------------------------------

TYPED_TEST(SnapshotTest, RoundTripIsExact) {
  constexpr int D = TypeParam::value;
  TempDir dir;
  const std::string path = dir.file("run.0007.h5");
  const auto ps = make_store<D>(11);
  const auto meta = make_meta();
  write_snapshot(path, ps, meta);
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));

  ParticleStore<D> back;
  back.allocate(3, Features{});  // stale content must be replaced
  SnapshotMeta meta_back;
  read_snapshot(path, back, meta_back);

  EXPECT_EQ(back.n, ps.n);
  for (const auto& f : field_table<D>()) {
    std::visit(
        [&](auto member) {
          if (f.snapshot) {
            EXPECT_TRUE(same(ps.*member, back.*member)) << "field " << f.name;
          } else {
            EXPECT_TRUE((back.*member).empty()) << "non-snapshot field " << f.name << " read back";
          }
        },
        f.member);
  }
  EXPECT_EQ(meta_back.time, meta.time);
  EXPECT_EQ(meta_back.step, meta.step);
  EXPECT_EQ(meta_back.scene_text, meta.scene_text);
  EXPECT_EQ(meta_back.version, meta.version);
  EXPECT_EQ(meta_back.commit, meta.commit);
}

TYPED_TEST(SnapshotTest, FileLayoutAndAttributes) {
  constexpr int D = TypeParam::value;
  TempDir dir;
  const std::string path = dir.file("layout.h5");
  const auto ps = make_store<D>(4);
  write_snapshot(path, ps, make_meta());

  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  for (const char* a : {"time", "dimension", "step", "version", "commit", "scene"})
    EXPECT_TRUE(h5_attr_exists(file, a)) << "root attribute " << a;
  int dimension = 0;
  const hid_t attr = H5Aopen(file, "dimension", H5P_DEFAULT);
  H5Aread(attr, H5T_NATIVE_INT, &dimension);
  H5Aclose(attr);
  EXPECT_EQ(dimension, D);
  EXPECT_EQ(h5_vlen_string_attr(file, "scene"), make_meta().scene_text);

  for (const auto& f : field_table<D>()) {
    const std::string name(f.name);
    const bool exists = H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0;
    EXPECT_EQ(exists, f.snapshot) << name;  // all allocated here: exactly the snapshot fields
    if (!exists) continue;
    const hid_t dset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    EXPECT_EQ(h5_vlen_string_attr(dset, "unit"), std::string(f.unit)) << name;
    // Shape: N x D for vector fields, N for scalars; material_id is int32.
    const hid_t space = H5Dget_space(dset);
    hsize_t dims[3] = {0, 0, 0};
    const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
    // N x D x D for tensors (S).
    const bool vector = std::holds_alternative<std::vector<Vec<D>> ParticleStore<D>::*>(f.member);
    const bool tensor = std::holds_alternative<std::vector<Mat<D>> ParticleStore<D>::*>(f.member);
    EXPECT_EQ(rank, tensor ? 3 : vector ? 2 : 1) << name;
    EXPECT_EQ(dims[0], ps.n) << name;
    if (vector || tensor) {
      EXPECT_EQ(dims[1], hsize_t(D)) << name;
    }
    if (tensor) {
      EXPECT_EQ(dims[2], hsize_t(D)) << name;
    }
    const hid_t type = H5Dget_type(dset);
    if (name == "material_id" || name == "id" || name == "boundary" || name == "flaw_count" || name == "tool") {
      EXPECT_GT(H5Tequal(type, H5T_NATIVE_INT32), 0);
    } else {
      EXPECT_EQ(H5Tget_size(type), sizeof(Real)) << name;
    }
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(dset);
  }
  H5Fclose(file);
}

TYPED_TEST(SnapshotTest, OnlyAllocatedFieldsAreWritten) {
  constexpr int D = TypeParam::value;
  TempDir dir;
  const std::string path = dir.file("partial.h5");
  auto ps = make_store<D>(6);
  ps.p.clear();  // e.g. a scene that never needs these
  ps.cs.clear();
  ps.h.clear();
  ps.a_grav.clear();  // no self-gravity
  ps.S.clear();       // no solids
  ps.boundary.clear();  // no boundary bodies
  ps.wall_force.clear();
  ps.tool.clear();  // no rigid tools
  ps.tool_offset.clear();
  ps.alpha.clear();     // no porosity
  ps.eps_p.clear();     // no plasticity
  ps.eps_v.clear();     // no dilatancy
  ps.damage_root.clear();  // no damage
  ps.flaw_count.clear();
  ps.flaw_eps_min.clear();
  ps.flaw_eps_max.clear();
  ps.flaws_active.clear();
  ps.av_alpha.clear();  // no viscosity switch
  ps.wall_anchor.clear();  // no Coulomb walls
  write_snapshot(path, ps, make_meta());

  ParticleStore<D> back;
  SnapshotMeta meta;
  read_snapshot(path, back, meta);
  EXPECT_EQ(back.allocated_fields(), (std::vector<std::string>{"x", "v", "m", "rho", "u", "material_id", "id"}));
  std::vector<std::string> listed;
  for (const auto& [name, comps] : snapshot_fields(ps)) {
    listed.push_back(name);
    EXPECT_EQ(comps, name == "x" || name == "v" ? D : 1) << name;
  }
  EXPECT_EQ(listed, back.allocated_fields());
}

TEST(Snapshot, WrongDimensionIsRefused) {
  TempDir dir;
  const std::string path = dir.file("two_d.h5");
  write_snapshot(path, make_store<2>(3), make_meta());
  ParticleStore<3> ps;
  SnapshotMeta meta;
  try {
    read_snapshot(path, ps, meta);
    FAIL() << "reading a 2-D snapshot as 3-D must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2-D"), std::string::npos) << e.what();
  }
}

TEST(Snapshot, FailedWritesLeaveNothingBehind) {
  TempDir dir;
  // A directory that does not exist: the error names the file and the call.
  const std::string missing = dir.file("no_such_dir/run.0000.h5");
  try {
    write_snapshot(missing, make_store<3>(2), make_meta());
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(missing), std::string::npos) << what;
    EXPECT_NE(what.find("H5Fcreate"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(missing + ".tmp"));

  // An inconsistent store must not replace a good earlier snapshot.
  const std::string path = dir.file("run.0001.h5");
  const auto good = make_store<3>(5);
  write_snapshot(path, good, make_meta());
  auto bad = make_store<3>(5);
  bad.rho.resize(4);
  EXPECT_THROW(write_snapshot(path, bad, make_meta()), std::runtime_error);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  ParticleStore<3> back;
  SnapshotMeta meta;
  read_snapshot(path, back, meta);
  EXPECT_TRUE(same(back.rho, good.rho));

  // Overwriting an existing snapshot replaces it.
  auto newer = make_store<3>(2);
  write_snapshot(path, newer, make_meta());
  read_snapshot(path, back, meta);
  EXPECT_EQ(back.n, 2u);
  EXPECT_EQ(fs::directory_iterator(dir.path()) == fs::directory_iterator(), false);
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();

  EXPECT_THROW(read_snapshot(dir.file("absent.h5"), back, meta), std::runtime_error);
}

TEST(Snapshot, FileName) {
  EXPECT_EQ(snapshot_filename("out/impact", 7), "out/impact.0007.h5");
  EXPECT_EQ(snapshot_filename("run", 12345), "run.12345.h5");
}

TEST(Snapshot, PythonH5pyReadsIt) {
  if (std::system("python3 -c 'import h5py, numpy' > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3 with h5py and numpy is not available; cannot check h5py readability";
  TempDir dir;
  const std::string path = dir.file("py.0000.h5");
  ParticleStore<3> ps;
  ps.allocate(4, Features{});
  for (std::size_t i = 0; i < 4; ++i) {
    for (int k = 0; k < 3; ++k) ps.x[i][k] = Real(0.5) * Real(i) + Real(k);
    ps.m[i] = Real(2);
    ps.material_id[i] = static_cast<std::int32_t>(i);
  }
  write_snapshot(path, ps, make_meta());

  const std::string script = dir.file("check.py");
  std::ofstream(script) << R"PY(import sys, h5py, numpy as np
path, real_bytes = sys.argv[1], int(sys.argv[2])
with h5py.File(path, "r") as f:
    a = f.attrs
    assert a["dimension"] == 3, a["dimension"]
    assert a["time"] == 1.25e-3 and a["step"] == 4242
    scene = a["scene"]
    scene = scene.decode() if isinstance(scene, bytes) else scene
    assert scene.startswith("[simulation]\n") and "rho \u03c1 test" in scene, repr(scene)
    assert a["version"] == "0.1.0" and a["commit"] == "abc1234"
    x = f["x"][...]
    assert x.shape == (4, 3) and x.dtype == np.dtype("f%d" % real_bytes), (x.shape, x.dtype)
    assert np.array_equal(x, 0.5 * np.arange(4)[:, None] + np.arange(3)[None, :])
    assert f["x"].attrs["unit"] == "m" and f["rho"].attrs["unit"] == "kg/m^3"
    mid = f["material_id"][...]
    assert mid.dtype == np.int32 and list(mid) == [0, 1, 2, 3]
    assert np.all(f["m"][...] == 2.0)
    assert "omega" not in f and "dvdt" not in f
print("h5py ok")
)PY";
  const std::string cmd = "python3 '" + script + "' '" + path + "' " + std::to_string(sizeof(Real));
  EXPECT_EQ(std::system(cmd.c_str()), 0) << "h5py could not read the snapshot as expected: " << cmd;
}

// ---- XDMF ----------------------------------------------------------------------

namespace {

// Minimal well-formedness check: tags nest and close properly.
bool xml_well_formed(const std::string& s, std::string& why) {
  std::vector<std::string> open;
  std::size_t i = 0;
  while ((i = s.find('<', i)) != std::string::npos) {
    if (s.compare(i, 2, "<?") == 0 || s.compare(i, 2, "<!") == 0) {
      i = s.find('>', i);
      if (i == std::string::npos) return why = "unterminated declaration", false;
      continue;
    }
    std::size_t j = i + 1;
    bool quoted = false;
    while (j < s.size() && (quoted || s[j] != '>')) {
      if (s[j] == '"') quoted = !quoted;
      ++j;
    }
    if (j >= s.size()) return why = "unterminated tag", false;
    const std::string tag = s.substr(i + 1, j - i - 1);
    if (tag.empty()) return why = "empty tag", false;
    const std::string name = tag.substr(tag[0] == '/' ? 1 : 0, tag.find_first_of(" \t\n/", 1) - (tag[0] == '/'));
    if (tag[0] == '/') {
      if (open.empty() || open.back() != name) return why = "unexpected </" + name + ">", false;
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(name);
    }
    i = j + 1;
  }
  if (!open.empty()) return why = "<" + open.back() + "> never closed", false;
  return true;
}

// Values of attribute `attr` on every `<tag ` element, in order.
std::vector<std::string> attribute_values(const std::string& s, const std::string& tag, const std::string& attr) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while ((i = s.find("<" + tag + " ", i)) != std::string::npos) {
    const std::size_t end = s.find('>', i);
    const std::size_t a = s.find(" " + attr + "=\"", i);
    if (a != std::string::npos && a < end) {
      const std::size_t v = a + attr.size() + 3;
      out.push_back(s.substr(v, s.find('"', v) - v));
    }
    i = end;
  }
  return out;
}

template <int D>
void check_xdmf(const TempDir& dir) {
  const std::string path = dir.file("run.xdmf");
  XdmfWriter xdmf(path, D);
  const std::vector<double> times = {0.0, 0.5, 1.25e-3};
  const std::vector<std::size_t> counts = {4, 4, 5};
  std::set<std::string> names;
  for (std::size_t s = 0; s < times.size(); ++s) {
    const auto ps = make_store<D>(counts[s]);
    const auto fields = snapshot_fields(ps);
    for (const auto& f : fields) names.insert(f.first);
    xdmf.add_snapshot(snapshot_filename("run", int(s)), times[s], counts[s], fields);
    xdmf.write();  // after every snapshot
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    const std::string text = read_text(path);
    std::string why;
    EXPECT_TRUE(xml_well_formed(text, why)) << why << "\n" << text;
    EXPECT_EQ(attribute_values(text, "Time", "Value").size(), s + 1);
  }
  const std::string text = read_text(path);
  EXPECT_EQ(text, xdmf.xml());
  EXPECT_NE(text.find(R"(GridType="Collection" CollectionType="Temporal")"), std::string::npos);

  // One Uniform grid per snapshot, with its time and particle count.
  EXPECT_EQ(attribute_values(text, "Grid", "GridType"),
            (std::vector<std::string>{"Collection", "Uniform", "Uniform", "Uniform"}));
  const auto time_values = attribute_values(text, "Time", "Value");
  ASSERT_EQ(time_values.size(), times.size());
  for (std::size_t s = 0; s < times.size(); ++s) EXPECT_EQ(std::strtod(time_values[s].c_str(), nullptr), times[s]);
  const auto elements = attribute_values(text, "Topology", "NumberOfElements");
  ASSERT_EQ(elements.size(), counts.size());
  for (std::size_t s = 0; s < counts.size(); ++s) EXPECT_EQ(elements[s], std::to_string(counts[s]));
  for (const auto& t : attribute_values(text, "Topology", "TopologyType")) EXPECT_EQ(t, "Polyvertex");

  // Geometry from `x` only; every other field is an attribute.
  for (const auto& g : attribute_values(text, "Geometry", "GeometryType")) EXPECT_EQ(g, D == 3 ? "XYZ" : "X_Y_Z");
  std::vector<std::string> expected_attrs;
  for (std::size_t s = 0; s < times.size(); ++s)
    for (const auto& f : snapshot_fields(make_store<D>(1)))
      if (f.first != "x") expected_attrs.push_back(f.first);
  EXPECT_EQ(attribute_values(text, "Attribute", "Name"), expected_attrs);
  EXPECT_NE(text.find(R"(<Attribute Name="material_id" AttributeType="Scalar")"), std::string::npos);
  EXPECT_NE(text.find(std::string(R"(<Attribute Name="v" AttributeType=")") + (D == 1 ? "Scalar" : "Vector")),
            std::string::npos);

  // Only datasets of the snapshot are referenced (nothing padded exists).
  std::size_t i = 0;
  while ((i = text.find(".h5:/", i)) != std::string::npos) {
    i += 5;
    const std::string ref = text.substr(i, text.find('<', i) - i);
    EXPECT_TRUE(names.count(ref)) << "XDMF references dataset '" << ref << "'";
  }
}

}  // namespace

TEST(Xdmf, TemporalCollection1D) {
  TempDir dir;
  check_xdmf<1>(dir);
}
TEST(Xdmf, TemporalCollection2D) {
  TempDir dir;
  check_xdmf<2>(dir);
}
TEST(Xdmf, TemporalCollection3D) {
  TempDir dir;
  check_xdmf<3>(dir);
}

// The deviatoric stress is stored N x Dim x Dim in every dimension; the XDMF
// DataItem must name the same shape (N 1 1 in 1-D), or readers reject it.
TEST(Xdmf, StressShapeMatchesTheDataset) {
  for (int d = 1; d <= 3; ++d) {
    XdmfWriter w("s.xdmf", d);
    w.add_snapshot("s.0000.h5", 0.0, 7, {{"x", d}, {"S", d * d}});
    const std::string xml = w.xml();
    const std::size_t a = xml.find(R"(<Attribute Name="S")");
    ASSERT_NE(a, std::string::npos) << d;
    const std::string dims = d == 1 ? "7 1 1" : "7 " + std::to_string(d) + " " + std::to_string(d);
    EXPECT_NE(xml.find("Dimensions=\"" + dims + "\"", a), std::string::npos) << d << "\n" << xml;
  }
}

// Each snapshot costs O(1): after the first write the index is appended
// in place (same file, same inode) rather than rewritten whole; a file
// changed behind the writer's back is rewritten whole.
TEST(Xdmf, AppendsInPlace) {
  TempDir dir;
  const std::string path = dir.file("run.xdmf");
  XdmfWriter w(path, 2);
  auto inode = [&] {
    struct stat st {};
    stat(path.c_str(), &st);
    return st.st_ino;
  };
  w.add_snapshot("run.0000.h5", 0.0, 3, {{"x", 2}, {"rho", 1}});
  w.write();
  const auto first = inode();
  for (int k = 1; k < 5; ++k) {
    w.add_snapshot(snapshot_filename("run", k), 0.1 * k, 3, {{"x", 2}, {"rho", 1}});
    w.write();
    EXPECT_EQ(inode(), first) << "snapshot " << k << " rewrote the file";
    EXPECT_EQ(read_text(path), w.xml());
  }
  std::ofstream(path, std::ios::app) << "<!-- edited -->\n";
  w.add_snapshot("run.0005.h5", 0.5, 3, {{"x", 2}, {"rho", 1}});
  w.write();
  EXPECT_EQ(read_text(path), w.xml());
}

TEST(Xdmf, Errors) {
  EXPECT_THROW(XdmfWriter("a.xdmf", 4), std::invalid_argument);
  XdmfWriter w("a.xdmf", 3);
  EXPECT_THROW(w.add_snapshot("a.0000.h5", 0, 1, {{"m", 1}}), std::invalid_argument);  // no x
  XdmfWriter unwritable("/nonexistent_dir_rubble/a.xdmf", 3);
  unwritable.add_snapshot("a.0000.h5", 0, 1, {{"x", 3}});
  EXPECT_THROW(unwritable.write(), std::runtime_error);
}

// ---- conserved.csv -----------------------------------------------------------------

TEST(ConservedLog, HeaderByDimension) {
  const std::string energy = "kinetic,internal,gravitational,total,wall_work,floor_energy,booked_total";
  EXPECT_EQ(ConservedLog::header(1), "time,step,dt,mass,momentum_x," + energy);
  EXPECT_EQ(ConservedLog::header(2), "time,step,dt,mass,momentum_x,momentum_y,angular_momentum_z," + energy);
  EXPECT_EQ(ConservedLog::header(3),
            "time,step,dt,mass,momentum_x,momentum_y,momentum_z,angular_momentum_x,angular_momentum_y,"
            "angular_momentum_z," + energy);
}

TEST(ConservedLog, RowsMatchHeaderAtFullPrecision) {
  for (int dim = 1; dim <= 3; ++dim) {
    TempDir dir;
    const std::string path = dir.file("conserved.csv");
    ConservedRecord r;
    r.time = 0.1;
    r.step = 1234567890123;
    r.dt = 1.0 / 3.0;
    r.mass = 6.02214076e23;
    r.momentum[0] = -1e-300;
    r.momentum[1] = 2.0 / 7.0;
    r.momentum[2] = 3;
    r.angular_momentum[0] = 4;
    r.angular_momentum[1] = 5;
    r.angular_momentum[2] = 6.5;
    r.kinetic = 7;
    r.internal = 8;
    r.gravitational = -9;
    r.total = 6;
    r.book(0.5, 0.25);
    {
      ConservedLog log(path, dim);
      log.append(r);
      // Flushed per line: readable while the log is still open.
      EXPECT_EQ(split(read_text(path), '\n').size(), 2u) << dim << "-D";
      r.step += 1;
      log.append(r);
    }
    const auto lines = split(read_text(path), '\n');
    ASSERT_EQ(lines.size(), 3u);
    EXPECT_EQ(lines[0], ConservedLog::header(dim));
    const auto names = split(lines[0], ',');
    const auto values = split(lines[1], ',');
    ASSERT_EQ(values.size(), names.size()) << dim << "-D";
    EXPECT_EQ(names.size(), 11u + dim + (dim == 2 ? 1 : dim == 3 ? 3 : 0));
    auto value = [&](const std::string& name) {
      for (std::size_t k = 0; k < names.size(); ++k)
        if (names[k] == name) return std::strtod(values[k].c_str(), nullptr);
      ADD_FAILURE() << "no column " << name;
      return 0.0;
    };
    EXPECT_EQ(value("time"), r.time);
    EXPECT_EQ(values[1], "1234567890123");
    EXPECT_EQ(value("dt"), r.dt);  // %.17g round-trips doubles exactly
    EXPECT_EQ(value("mass"), r.mass);
    EXPECT_EQ(value("momentum_x"), r.momentum[0]);
    if (dim >= 2) {
      EXPECT_EQ(value("momentum_y"), r.momentum[1]);
    }
    if (dim == 2) {
      EXPECT_EQ(value("angular_momentum_z"), 6.5);
    }
    if (dim == 3) {
      EXPECT_EQ(value("angular_momentum_y"), 5);
    }
    EXPECT_EQ(value("gravitational"), -9);
    EXPECT_EQ(value("total"), 6);
    EXPECT_EQ(value("wall_work"), 0.5);
    EXPECT_EQ(value("floor_energy"), 0.25);
    EXPECT_EQ(value("booked_total"), 5.25);  // total - wall_work - floor_energy
  }
}

TEST(ConservedLog, UnwritablePathThrows) {
  EXPECT_THROW(ConservedLog("/nonexistent_dir_rubble/conserved.csv", 3), std::runtime_error);
}

// A full disk (/dev/full: every write fails with ENOSPC) is reported with
// the OS's reason (issue #13 item 6).
TEST(ConservedLog, FullDiskGivesTheReason) {
  if (access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no writable /dev/full on this system";
  try {
    ConservedLog log("/dev/full", 2);
    log.append(ConservedRecord{});
    ADD_FAILURE() << "writing to /dev/full must fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
  }
}

TEST(MeasureConserved, ThreeParticles3D) {
  ParticleStore<3> ps;
  ps.allocate(3, Features{});
  // m    x          v          u
  // 1  (1,0,0)   (0,1,0)    10
  // 2  (0,1,0)   (0,0,3)    20
  // 3  (0,0,2)   (1,0,0)    30
  const double m[3] = {1, 2, 3}, u[3] = {10, 20, 30};
  const double x[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 2}}, v[3][3] = {{0, 1, 0}, {0, 0, 3}, {1, 0, 0}};
  for (int i = 0; i < 3; ++i) {
    ps.m[i] = Real(m[i]);
    ps.u[i] = Real(u[i]);
    for (int k = 0; k < 3; ++k) {
      ps.x[i][k] = Real(x[i][k]);
      ps.v[i][k] = Real(v[i][k]);
    }
  }
  const ConservedRecord r = measure_conserved(ps, 0.5, 7, 1e-3);
  EXPECT_EQ(r.time, 0.5);
  EXPECT_EQ(r.step, 7);
  EXPECT_EQ(r.dt, 1e-3);
  EXPECT_DOUBLE_EQ(r.mass, 6);
  // P = 1(0,1,0) + 2(0,0,3) + 3(1,0,0) = (3,1,6)
  EXPECT_DOUBLE_EQ(r.momentum[0], 3);
  EXPECT_DOUBLE_EQ(r.momentum[1], 1);
  EXPECT_DOUBLE_EQ(r.momentum[2], 6);
  // L = 1 (1,0,0)x(0,1,0) + 2 (0,1,0)x(0,0,3) + 3 (0,0,2)x(1,0,0)
  //   = (0,0,1) + 2 (3,0,0) + 3 (0,2,0) = (6,6,1)
  EXPECT_DOUBLE_EQ(r.angular_momentum[0], 6);
  EXPECT_DOUBLE_EQ(r.angular_momentum[1], 6);
  EXPECT_DOUBLE_EQ(r.angular_momentum[2], 1);
  // K = 1/2 (1*1 + 2*9 + 3*1) = 11; U = 1*10 + 2*20 + 3*30 = 140
  EXPECT_DOUBLE_EQ(r.kinetic, 11);
  EXPECT_DOUBLE_EQ(r.internal, 140);
  EXPECT_DOUBLE_EQ(r.gravitational, 0);
  EXPECT_DOUBLE_EQ(r.total, 151);
}

TEST(MeasureConserved, ThreeParticles2D) {
  ParticleStore<2> ps;
  ps.allocate(3, Features{});
  // m    x       v        u
  // 1  (1,0)   (0,2)     1
  // 2  (0,3)   (1,0)     1
  // 3  (2,2)   (1,-1)    1
  const double m[3] = {1, 2, 3};
  const double x[3][2] = {{1, 0}, {0, 3}, {2, 2}}, v[3][2] = {{0, 2}, {1, 0}, {1, -1}};
  for (int i = 0; i < 3; ++i) {
    ps.m[i] = Real(m[i]);
    ps.u[i] = 1;
    for (int k = 0; k < 2; ++k) {
      ps.x[i][k] = Real(x[i][k]);
      ps.v[i][k] = Real(v[i][k]);
    }
  }
  const ConservedRecord r = measure_conserved(ps, 0, 0, 0);
  EXPECT_DOUBLE_EQ(r.mass, 6);
  EXPECT_DOUBLE_EQ(r.momentum[0], 5);   // 0 + 2 + 3
  EXPECT_DOUBLE_EQ(r.momentum[1], -1);  // 2 + 0 - 3
  EXPECT_DOUBLE_EQ(r.momentum[2], 0);
  // L_z = sum m (x vy - y vx) = 1(2) + 2(-3) + 3(-2-2) = -16
  EXPECT_DOUBLE_EQ(r.angular_momentum[2], -16);
  EXPECT_DOUBLE_EQ(r.angular_momentum[0], 0);
  EXPECT_DOUBLE_EQ(r.angular_momentum[1], 0);
  EXPECT_DOUBLE_EQ(r.kinetic, 6);  // 1/2 (1*4 + 2*1 + 3*2)
  EXPECT_DOUBLE_EQ(r.internal, 6);
  EXPECT_DOUBLE_EQ(r.total, 12);

  // The logged 2-D row carries L_z in its column.
  TempDir dir;
  const std::string path = dir.file("conserved.csv");
  {
    ConservedLog log(path, 2);
    log.append(r);
  }
  const auto lines = split(read_text(path), '\n');
  ASSERT_EQ(lines.size(), 2u);
  const auto names = split(lines[0], ','), values = split(lines[1], ',');
  ASSERT_EQ(names.size(), values.size());
  EXPECT_EQ(names[6], "angular_momentum_z");
  EXPECT_EQ(std::strtod(values[6].c_str(), nullptr), -16);
}

TEST(MeasureConserved, ThreeParticles1D) {
  ParticleStore<1> ps;
  ps.allocate(3, Features{});
  const double m[3] = {1, 2, 3}, x[3] = {0, 1, 2}, v[3] = {1, -1, 2};
  for (int i = 0; i < 3; ++i) {
    ps.m[i] = Real(m[i]);
    ps.x[i][0] = Real(x[i]);
    ps.v[i][0] = Real(v[i]);
  }
  ps.u.clear();  // no internal energy field: counts as zero
  const ConservedRecord r = measure_conserved(ps, 0, 0, 0);
  EXPECT_DOUBLE_EQ(r.momentum[0], 5);  // 1 - 2 + 6
  EXPECT_DOUBLE_EQ(r.kinetic, 7.5);    // 1/2 (1 + 2 + 12)
  EXPECT_DOUBLE_EQ(r.internal, 0);
  for (double l : r.angular_momentum) EXPECT_EQ(l, 0);
  EXPECT_DOUBLE_EQ(r.total, 7.5);
}

// ---- progress ----------------------------------------------------------------------

namespace {
std::string file_text(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  return s;
}
}  // namespace

TEST(Progress, PlainLinesEveryTenPercent) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p(1.0, true, f, /*terminal=*/false);
    for (int step = 0; step <= 1000; ++step) p.update(step / 1000.0, 1e-3, step);
    p.finish();
    p.finish();  // idempotent
  }
  const auto lines = split(file_text(f), '\n');
  std::fclose(f);
  // t = 0, then 10 %, 20 %, ... 100 %, then the closing line.
  EXPECT_EQ(lines.size(), 12u);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines.back().rfind("done:", 0), 0u) << lines.back();
  EXPECT_NE(lines.back().find("100.0%"), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("step 1000"), std::string::npos) << lines.back();
  for (const auto& l : lines) EXPECT_EQ(l.find('\r'), std::string::npos);
}

TEST(Progress, TerminalBarIsRateLimited) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p(2.0, true, f, /*terminal=*/true);
    for (int step = 0; step <= 1000; ++step) p.update(step / 500.0, 2e-3, step);
    p.finish();
  }
  const std::string text = file_text(f);
  std::fclose(f);
  // First draw, the final one, and at most a few in between (10 per second).
  const auto redraws = std::count(text.begin(), text.end(), '\r');
  EXPECT_GE(redraws, 2);
  EXPECT_LE(redraws, 5);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
  const std::string last = text.substr(text.rfind('\r'));
  EXPECT_NE(last.find("100.0%"), std::string::npos) << last;
  EXPECT_NE(last.find("ETA"), std::string::npos) << last;
  EXPECT_NE(last.find("step 1000"), std::string::npos) << last;
}

TEST(Progress, DisabledPrintsNothingAndUpdateIsCheap) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress off(1.0, false, f, true);
    off.update(0.5, 1e-3, 1);
    off.finish();
  }
  EXPECT_TRUE(file_text(f).empty());

  // Called every step: a million updates cost well under a second.
  Progress on(1.0, true, f, false);
  const auto t0 = std::chrono::steady_clock::now();
  for (int step = 0; step < 1000000; ++step) on.update(step * 1e-6, 1e-6, step);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  on.finish();
  std::fclose(f);
  EXPECT_LT(s, 1.0);
}
