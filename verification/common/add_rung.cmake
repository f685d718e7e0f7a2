# The CMake plumbing of the rungs (included by the top-level CMakeLists.txt
# before the rung folders), so that a rung's CMakeLists.txt names only its
# driver and its tests.
#
#   rung_executable(sod_rung sod_rung.cpp)
#   add_rung(sod_1d LABELS verification
#     COMMAND sod_rung --case 1d --scene ${CMAKE_CURRENT_SOURCE_DIR}/sod_1d.toml --records ${RUNG_RECORDS} ...)
#
# The measurements behind a rung's tests are in the README.md of its folder.

# Where every rung writes its JSON records (docs/report-format.md; ci/report
# reads them from there).
set(RUNG_RECORDS ${CMAKE_BINARY_DIR}/reports/records)
# The environment of a rung that loads library materials by name.
set(RUNG_MATERIALS "RUBBLE_MATERIALS=${CMAKE_SOURCE_DIR}/reference_data/materials")

# A rung driver: an executable of `sources` linked against the solver.
function(rung_executable target)
  add_executable(${target} ${ARGN})
  target_link_libraries(${target} PRIVATE rubble_solver)
endfunction()

# add_rung(NAME LABELS label... COMMAND program arg... [TIMEOUT seconds]
#          [MATERIALS] [PARALLEL])
# A ctest test NAME running COMMAND, with LABELS (verification, validation,
# slow, stress), RUN_SERIAL unless PARALLEL (a rung runs on every core and
# records its wall time), the TIMEOUT if given, and RUBBLE_MATERIALS set to
# the library (reference_data/materials) with MATERIALS.
# The COMMAND's arguments are passed as written.
function(add_rung name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "MATERIALS;PARALLEL" "TIMEOUT" "LABELS;COMMAND")
  if(ARG_UNPARSED_ARGUMENTS OR NOT ARG_COMMAND OR NOT ARG_LABELS)
    message(FATAL_ERROR "add_rung(${name}): needs LABELS and COMMAND (unparsed: ${ARG_UNPARSED_ARGUMENTS})")
  endif()
  add_test(NAME ${name} COMMAND ${ARG_COMMAND})
  set_property(TEST ${name} PROPERTY LABELS ${ARG_LABELS})
  if(NOT ARG_PARALLEL)
    set_property(TEST ${name} PROPERTY RUN_SERIAL TRUE)
  endif()
  if(ARG_TIMEOUT)
    set_property(TEST ${name} PROPERTY TIMEOUT ${ARG_TIMEOUT})
  endif()
  if(ARG_MATERIALS)
    set_property(TEST ${name} PROPERTY ENVIRONMENT "${RUNG_MATERIALS}")
  endif()
endfunction()
