#pragma once
// The material library (reference_data/materials/, one TOML file per
// material, each with its source). Keys and rules:
// docs/scene.md, "Materials".
#include <string>
#include <vector>

#include "rubble/physics/eos/eos.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

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

// The EOS parameters of a material: eos_params_from_material
// (rubble/drivers/run_physics.hpp, with every scene-to-physics conversion).

}  // namespace rubble
