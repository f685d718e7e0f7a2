#pragma once
// HDF5 snapshots: one file per output (DESIGN.md, "Snapshot").
//
// A snapshot holds one dataset per particle field that is allocated and
// flagged `snapshot` in the field table (particle_store.hpp), named exactly
// as in the table: vector fields (`x`, `v`) are N x Dim, scalar fields are N,
// `material_id` is int32; floating-point fields are stored in the native
// type of Real. Every dataset carries a `unit` string attribute. The root
// group carries `time` (double), `dimension` (int), `step` (int64) and the
// strings `version`, `commit` and `scene` (the full scene text).
//
// Files are written to PATH.tmp and renamed to PATH once complete, so a
// crash never leaves a half-written snapshot under the real name. Any HDF5
// failure throws std::runtime_error naming the file and the failing call.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rubble/particles/particle_store.hpp"

namespace rubble {

struct SnapshotMeta {
  double time = 0;            // simulated time [s]
  std::int64_t step = 0;      // step count
  std::string scene_text;     // the full scene file, verbatim
  std::string version;        // code version
  std::string commit;         // source commit
};

// Write `ps` (its allocated snapshot fields) and `meta` to `path`.
template <int D>
void write_snapshot(const std::string& path, const ParticleStore<D>& ps, const SnapshotMeta& meta);

// Read a snapshot written by write_snapshot. `ps` is reset first: n and
// every snapshot field present in the file are filled, all other fields end
// up empty (the caller allocates what the run needs beyond them). Throws if
// the file's `dimension` is not D or a dataset has the wrong shape.
template <int D>
void read_snapshot(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta);

// The datasets write_snapshot writes for `ps`: (name, components per
// particle), in field-table order. This is what XdmfWriter::add_snapshot
// wants to describe the same file.
template <int D>
std::vector<std::pair<std::string, int>> snapshot_fields(const ParticleStore<D>& ps);

// The conventional file name of output number `index`: "STEM.NNNN.h5".
std::string snapshot_filename(const std::string& stem, int index);

}  // namespace rubble
