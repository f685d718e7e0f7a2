#pragma once
// Shared by the unit tests that check scene errors: the message of the
// InputError that parsing `text` (as file "t.toml") raises, or "" when the
// scene parses.
#include <string>

#include "rubble/core/error.hpp"
#include "rubble/run.hpp"

namespace rubble::test {

inline std::string parse_error(const std::string& text) {
  try {
    parse_scene(text, "t.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace rubble::test
