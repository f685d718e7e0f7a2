// XDMF index of a run's HDF5 snapshots. See rubble/io/xdmf.hpp.
//
// Geometry and the readers ParaView offers
// ----------------------------------------
// ParaView has two XDMF readers: "XDMF Reader" (Xdmf2 library) and the
// "Xdmf3 Reader S/T" (Xdmf3 library). Points are always 3-D inside VTK.
//  - 3-D runs: Geometry "XYZ" straight from the N x 3 dataset `x`.
//  - 1-D and 2-D runs: the only geometry type both libraries turn into
//    fully defined 3-D points is "X_Y_Z", with one DataItem per axis:
//    "XY" (Xdmf2) allocates N x 3 points and copies two columns, leaving z
//    uninitialised; and Function "JOIN($0, ...)" interlaces its arguments in
//    Xdmf2 but concatenates them in Xdmf3. So each existing axis is a
//    HyperSlab (one column) of `x`, and each missing axis is the Function
//    "$0 * 0" of column 0 (array times scalar: supported by both expression
//    parsers, giving N zeros). The snapshot holds only the field-table
//    datasets; nothing padded is stored.
#include "rubble/io/xdmf.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <variant>

#include "rubble/core/real.hpp"
#include "rubble/particles/particle_store.hpp"

namespace rubble {
namespace {

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// What the field table says about a dataset name (the table's names and
// kinds are the same for every dimension, so the 3-D table answers).
struct FieldKind {
  bool vector = false;   // stored N x Dim
  bool integer = false;  // stored as int32
  bool matrix = false;   // stored N x Dim x Dim (S, dS/dt), even in 1-D
};
FieldKind field_kind(const std::string& name) {
  using S = ParticleStore<3>;
  for (const auto& f : field_table<3>()) {
    if (f.name != name) continue;
    return {std::holds_alternative<std::vector<Vec<3>> S::*>(f.member),
            std::holds_alternative<std::vector<std::int32_t> S::*>(f.member),
            std::holds_alternative<std::vector<Mat<3>> S::*>(f.member)};
  }
  return {};
}

// A DataItem reading a whole dataset from the snapshot file.
std::string hdf_item(const std::string& h5, const std::string& name, const std::string& dims, bool integer,
                     const std::string& indent) {
  const std::string type = integer ? R"(NumberType="Int" Precision="4")"
                                   : R"(NumberType="Float" Precision=")" + std::to_string(sizeof(Real)) + "\"";
  return indent + "<DataItem Dimensions=\"" + dims + "\" " + type + " Format=\"HDF\">" + xml_escape(h5) + ":/" +
         xml_escape(name) + "</DataItem>\n";
}

}  // namespace

XdmfWriter::XdmfWriter(std::string path, int dimension) : path_(std::move(path)), dim_(dimension) {
  if (dim_ < 1 || dim_ > 3) throw std::invalid_argument("XdmfWriter: dimension must be 1, 2 or 3");
}

void XdmfWriter::add_snapshot(const std::string& h5_filename, double time, std::size_t n,
                              const std::vector<std::pair<std::string, int>>& fields) {
  bool has_x = false;
  for (const auto& f : fields) has_x = has_x || f.first == "x";
  if (!has_x) throw std::invalid_argument("XdmfWriter: snapshot '" + h5_filename + "' has no dataset 'x'");
  entries_.push_back({h5_filename, time, n, fields});
}

namespace {

const char* const kHead =
    "<?xml version=\"1.0\" ?>\n"
    "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    "<Xdmf Version=\"2.0\">\n"
    "  <Domain>\n"
    "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
const char* const kTail =
    "    </Grid>\n"
    "  </Domain>\n"
    "</Xdmf>\n";

}  // namespace

std::string XdmfWriter::xml() const {
  std::string o = kHead;
  for (const auto& e : entries_) o += entry_xml(e);
  return o + kTail;
}

// One snapshot's <Grid>.
std::string XdmfWriter::entry_xml(const Entry& e) const {
  std::ostringstream o;
  {
    const std::string N = std::to_string(e.n);
    const std::string D = std::to_string(dim_);
    const std::string in = "          ";  // indent of DataItems inside Geometry / Attribute

    o << "      <Grid Name=\"" << xml_escape(e.h5) << "\" GridType=\"Uniform\">\n"
      << "        <Time Value=\"" << number(e.time) << "\" />\n"
      << "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << N << "\" NodesPerElement=\"1\" />\n";

    // Geometry (see the note at the top of this file).
    if (dim_ == 3) {
      o << "        <Geometry GeometryType=\"XYZ\">\n" << hdf_item(e.h5, "x", N + " 3", false, in);
    } else {
      // Column c of x as an N x 1 item.
      auto column = [&](int c, const std::string& ind) {
        if (dim_ == 1) return hdf_item(e.h5, "x", N + " 1", false, ind);
        return ind + "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" + N + " 1\">\n" + ind +
               "  <DataItem Dimensions=\"3 2\" NumberType=\"Int\" Format=\"XML\">0 " + std::to_string(c) + " 1 1 " +
               N + " 1</DataItem>\n" + hdf_item(e.h5, "x", N + " " + D, false, ind + "  ") + ind + "</DataItem>\n";
      };
      o << "        <Geometry GeometryType=\"X_Y_Z\">\n";
      for (int c = 0; c < 3; ++c) {
        if (c < dim_) {
          o << column(c, in);
        } else {
          o << in << "<DataItem ItemType=\"Function\" Function=\"$0 * 0\" Dimensions=\"" << N << " 1\">\n"
            << column(0, in + "  ") << in << "</DataItem>\n";
        }
      }
    }
    o << "        </Geometry>\n";

    // Every other dataset as a point attribute.
    for (const auto& [name, comps] : e.fields) {
      if (name == "x") continue;
      const FieldKind kind = field_kind(name);
      std::string type, dims;
      if (kind.vector) {  // N x Dim, even in 1-D
        type = comps == 1 ? "Scalar" : "Vector";
        dims = N + " " + std::to_string(comps);
      } else if (kind.matrix && dim_ == 1) {  // N x 1 x 1: one value per particle
        type = "Scalar";
        dims = N + " 1 1";
      } else if (comps == 1) {
        type = "Scalar";
        dims = N;
      } else if (dim_ > 1 && comps == dim_ * dim_) {  // N x Dim x Dim (DESIGN.md: S)
        type = comps == 9 ? "Tensor" : "Matrix";
        dims = N + " " + D + " " + D;
      } else {
        type = comps == 6 ? "Tensor6" : "Matrix";
        dims = N + " " + std::to_string(comps);
      }
      o << "        <Attribute Name=\"" << xml_escape(name) << "\" AttributeType=\"" << type
        << "\" Center=\"Node\">\n"
        << hdf_item(e.h5, name, dims, kind.integer, in) << "        </Attribute>\n";
    }
    o << "      </Grid>\n";
  }
  return o.str();
}

void XdmfWriter::write() {
  // O(1) per snapshot: the entries not yet in the file go in before its
  // closing tags, in place, when the file is still the one last written
  // (same size); otherwise the whole index is rewritten atomically.
  std::error_code ec;
  const std::string tail = kTail;
  if (in_file_ > 0 && in_file_ < entries_.size() && std::filesystem::file_size(path_, ec) == file_size_ && !ec) {
    std::string more;
    for (std::size_t k = in_file_; k < entries_.size(); ++k) more += entry_xml(entries_[k]);
    more += tail;
    std::FILE* f = std::fopen(path_.c_str(), "r+b");
    if (!f) throw std::runtime_error("xdmf '" + path_ + "': cannot open it to append: " + std::strerror(errno));
    const bool ok = std::fseek(f, long(file_size_ - tail.size()), SEEK_SET) == 0 &&
                    std::fwrite(more.data(), 1, more.size(), f) == more.size();
    if (std::fclose(f) != 0 || !ok) throw std::runtime_error("xdmf '" + path_ + "': appending failed: " + std::strerror(errno));
    file_size_ += more.size() - tail.size();
    in_file_ = entries_.size();
    return;
  }
  const std::string text = xml();
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("xdmf '" + path_ + "': cannot open '" + tmp + "' for writing");
    out << text;
    out.close();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error("xdmf '" + path_ + "': writing '" + tmp + "' failed");
    }
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("xdmf '" + path_ + "': rename from '" + tmp + "' failed");
  }
  file_size_ = text.size();
  in_file_ = entries_.size();
}

}  // namespace rubble
