#pragma once
// The scene reader (solver/src/scene_parser.cpp, the only code that knows
// TOML): scenes, and the material library (reference_data/materials/, one
// TOML file per material, each with its source) that scenes draw on. Every
// key: docs/scene.md.
#include <string>
#include <vector>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Parse and validate a scene. `overrides` are "dotted.key=value" strings
// (the --set option), applied to the TOML tree before validation; the value
// is parsed as TOML (so 0.5, true, "text", [1, 2] all work).
// Throws InputError naming the file, the key and the problem.
Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides = {});
// `libraries`: when given, `library = SPEC` is resolved from this list
// (by spec) instead of the disk: how a run resumes from a snapshot with the
// library values it started with (an unlisted spec is an error).
Scene parse_scene(const std::string& text, const std::string& file_label,
                  const std::vector<std::string>& overrides = {},
                  const std::vector<LibraryText>* libraries = nullptr);

// Where library materials are looked up: $RUBBLE_MATERIALS when set and not
// empty, else the source tree's reference_data/materials (fixed at build
// time as RUBBLE_MATERIALS_DIR). "" when neither is known.
std::string materials_directory();

// The library's material names (file stems of *.toml), sorted.
std::vector<std::string> library_material_names();

// Load and validate one material: a library name ("basalt") or a path to a
// material file ending in ".toml". `overrides` are "key=value" relative to
// the material ("tillotson.A=3e10", "rho_limit=0.9"), applied before
// validation like `rubble run --set`. Throws InputError naming the file,
// the key and the problem.
MaterialConfig load_material(const std::string& name_or_path, const std::vector<std::string>& overrides = {});

// A material's physics parameters (its EOS: eos_params_from_material):
// rubble/drivers/run_physics.hpp, with every scene-to-physics conversion.

}  // namespace rubble
