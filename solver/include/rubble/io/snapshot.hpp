#pragma once
// HDF5 snapshots: one file per output (DESIGN.md, "Snapshot").
//
// A snapshot holds one dataset per particle field that is allocated and
// flagged `snapshot` in the field table (particle_store.hpp), named exactly
// as in the table: vector fields (`x`, `v`) are N x Dim, scalar fields are N,
// `material_id` is int32; floating-point fields are stored in the native
// type of Real. Every dataset carries a `unit` string attribute. The root
// group carries `time` (double), `dimension` (int), `step` (int64) and the
// strings `version`, `commit` and `scene` (the full scene text). Snapshots
// of a run (not those of tests that write bare stores) also carry the
// group `restart` described at RestartState.
//
// Files are written to PATH.tmp and renamed to PATH once complete, so a
// crash never leaves a half-written snapshot under the real name. Any HDF5
// failure throws std::runtime_error naming the file and the failing call.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rubble/io/conserved_sums.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// What a run needs beyond the particles to continue from a snapshot
// exactly as it would have gone on (issue #13). Written to the group
// `restart` of the file: these values as attributes, plus every allocated
// particle field the snapshot proper leaves out (rates, Omega, the
// gravitational potential, ...), so that the resumed run starts from the
// very bits the interrupted one held and needs no new evaluation.
struct RestartState {
  double dt_proposal = 0;   // the adaptive integrator's proposal for the next step [s]
  double next_output = 0;   // time of the next regular snapshot [s]
  int next_snapshot = 0;    // number NNNN of the next regular snapshot file
  bool checkpoint = false;  // written by a stop or a periodic checkpoint, not at an output time
  std::string scene_file;   // the scene's path when the run began (for messages)
  std::string scene_source; // the scene file's text as read (Scene::source_text)
  std::vector<std::string> overrides;  // --set overrides, in order
  std::vector<LibraryText> libraries;  // library material files, as read
  std::vector<std::int64_t> body_first_id;  // body k holds ids [first[k], first[k+1])
  EnergyBooks books;        // the energy bookkeeping so far (conserved.csv's booked columns)
  // rigid tools (physics/rigid_body.hpp): kRigidStateValues per tool;
  // empty without tools
  std::vector<double> tool_state;
};

struct SnapshotMeta {
  double time = 0;            // simulated time [s]
  std::int64_t step = 0;      // step count
  std::string scene_text;     // the full scene file, verbatim
  std::string version;        // code version
  std::string commit;         // source commit
  bool restartable = false;   // write / found the `restart` group
  RestartState restart;
  int dimension = 0;          // filled by the readers
};

// The root attributes and (when present) the restart attributes of a
// snapshot of any dimension, without its particle data: how `rubble run
// --restart` learns the scene before it knows the dimension.
SnapshotMeta read_snapshot_meta(const std::string& path);

// What an XDMF index needs of a snapshot: time, particle count and datasets
// (as snapshot_fields), read without the particle data.
struct SnapshotSummary {
  double time = 0;
  std::size_t n = 0;
  std::vector<std::pair<std::string, int>> fields;
};
template <int D>
SnapshotSummary read_snapshot_summary(const std::string& path);

// Write `ps` (its allocated snapshot fields) and `meta` to `path`.
template <int D>
void write_snapshot(const std::string& path, const ParticleStore<D>& ps, const SnapshotMeta& meta);

// Read a snapshot written by write_snapshot. `ps` is reset first: n and
// every snapshot field present in the file are filled, all other fields end
// up empty (the caller allocates what the run needs beyond them). Throws if
// the file's `dimension` is not D or a dataset has the wrong shape.
template <int D>
void read_snapshot(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta);

// Read a snapshot and its `restart` group: every field the run had
// allocated, and meta.restart. Throws (naming the file) if the file has no
// restart group.
template <int D>
void read_restart(const std::string& path, ParticleStore<D>& ps, SnapshotMeta& meta);

// The datasets write_snapshot writes for `ps`: (name, components per
// particle), in field-table order. This is what XdmfWriter::add_snapshot
// wants to describe the same file.
template <int D>
std::vector<std::pair<std::string, int>> snapshot_fields(const ParticleStore<D>& ps);

// The conventional file name of output number `index`: "STEM.NNNN.h5".
std::string snapshot_filename(const std::string& stem, int index);

}  // namespace rubble
