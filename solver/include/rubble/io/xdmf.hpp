#pragma once
// XDMF index of a run's snapshots, so that ParaView opens the whole run as
// one time series: NAME.xdmf holds a temporal collection of Polyvertex
// grids (one per snapshot), each pointing into its HDF5 file. The file is
// brought up to date after every snapshot (write()), so a run cut short is
// still viewable up to its last output.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rubble {

class XdmfWriter {
 public:
  // `path`: the .xdmf file; `dimension`: 1, 2 or 3.
  XdmfWriter(std::string path, int dimension);

  // Register one snapshot: its HDF5 file name relative to the .xdmf file,
  // its time, particle count and datasets (name, components per particle,
  // as from snapshot_fields()). Dataset `x` is the geometry and must be
  // among `fields`; every other dataset becomes a point attribute.
  void add_snapshot(const std::string& h5_filename, double time, std::size_t n,
                    const std::vector<std::pair<std::string, int>>& fields);

  // Bring the file up to date with all snapshots so far: the first call
  // writes the whole index atomically (PATH.tmp, then rename), later ones
  // append the new entries in place before the closing tags (O(1) per
  // snapshot; should the file have changed size meanwhile, it is rewritten
  // whole). Throws std::runtime_error naming the file if it cannot.
  void write();

  // The XML write() puts in the file.
  std::string xml() const;

 private:
  struct Entry {
    std::string h5;
    double time;
    std::size_t n;
    std::vector<std::pair<std::string, int>> fields;
  };
  std::string entry_xml(const Entry& e) const;

  std::string path_;
  int dim_;
  std::vector<Entry> entries_;
  std::size_t in_file_ = 0;    // entries the file holds
  std::uintmax_t file_size_ = 0;  // its size after the last write
};

}  // namespace rubble
