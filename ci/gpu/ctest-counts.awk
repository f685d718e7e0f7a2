# ctest_counts for ci/gpu/check: reads a ctest log and prints
#   "passed failed skipped total|failed names|skipped names"
# (ctest counts a skipped test, e.g. a GoogleTest GTEST_SKIP, as passed in
# its percentage line; here it is counted apart). Handles the summary lines
# of CTest 3.x and 4.x; ci/gpu/tests/ctest-counts checks both.
#   awk -f ci/gpu/ctest-counts.awk LOG
# "99% tests passed, 5 tests failed out of 489"; CTest 4.x writes
# "100% tests passed out of 25" when none failed
/tests passed(, [0-9]+ tests? failed)? out of [0-9]+/ {
  for (i = 1; i <= NF; i++) { if ($i == "out") total += $(i + 2); if ($i == "failed" && $(i - 1) ~ /^tests?$/) failed += $(i - 2) }
}
/^The following tests FAILED:/ { list = "f"; next }
/^The following tests did not run:/ { list = "s"; next }
list && /^[ \t]+[0-9]+ - / {
  # "  12 - Scenes/X.Y/Sod3D  # GetParam() = ... (Skipped)" -> "Scenes/X.Y/Sod3D";
  # CTest 4.x adds the labels: "  13 - Cli.X (Failed)    unit" -> "Cli.X"
  sub(/^[ \t]+[0-9]+ - /, "")
  sub(/[ \t]+# GetParam\(\).*$/, "")
  sub(/[ \t]+\((Failed|Skipped|Not Run|Timeout|SEGFAULT|Subprocess aborted|Exception|[^()]*)\)([ \t].*)?$/, "")
  if (list == "f") fnames = fnames (fnames ? ", " : "") $0
  else { skipped++; snames = snames (snames ? ", " : "") $0 }
  next
}
list && !/^[ \t]/ { list = "" }
END { printf "%d %d %d %d|%s|%s\n", total - failed - skipped, failed, skipped, total, fnames, snames }
