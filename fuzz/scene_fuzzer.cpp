// libFuzzer harness for the scene parser and --set handling (issue #13
// item 8). An input is scene text, optionally preceded by override lines
//   #set KEY=VALUE
// (each one --set, in order). The parser must either return a Scene or
// throw rubble::InputError: any other exception, a crash, a sanitizer
// report or a hang is a finding.
//
// Build and run (fuzz/README.md): configure with clang and -DRUBBLE_FUZZ=ON,
// then   build-fuzz/fuzz_scene fuzz/corpus -dict=fuzz/scene.dict
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/core/error.hpp"
#include "rubble/run.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> overrides;
  while (text.rfind("#set ", 0) == 0) {
    const std::size_t end = text.find('\n');
    overrides.push_back(text.substr(5, end == std::string::npos ? std::string::npos : end - 5));
    text = end == std::string::npos ? std::string() : text.substr(end + 1);
  }
  try {
    const rubble::Scene scene = rubble::parse_scene(text, "fuzz.toml", overrides);
    (void)scene;
  } catch (const rubble::InputError&) {
    // the expected answer to bad input
  }
  return 0;
}
