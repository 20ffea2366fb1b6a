#!/usr/bin/env bash
# Lists the tests that the last ctest run skipped, each with the reason it printed, from CTest's
# log (default build/Testing/Temporary/LastTest.log). A GoogleTest skip gives the message after
# "Skipped"; a script test that exits 77 gives its "SKIP: ..." line. Prints nothing when none were
# skipped. Used by scripts/test.sh, so that a skip is never silent.
set -euo pipefail
log="${1:-build/Testing/Temporary/LastTest.log}"
[[ -f "$log" ]] || exit 0
awk '
  /^[0-9]+\/[0-9]+ Test: / { name = substr($0, index($0, "Test: ") + 6); reason = ""; out = 0; next }
  /^Output:$/ { out = 1; next }
  /^<end of output>$/ { out = 0; next }
  out && after_skip { reason = reason (reason == "" ? "" : " ") $0; after_skip = 0; next }
  out && /: Skipped$/ { after_skip = 1; gtest = 1; next }
  out && /^SKIP: / { reason = reason (reason == "" ? "" : " ") substr($0, 7); script = 1; next }
  /^Skip regular expression found in output/ || (/^Test Passed\.$/ && script) {
    skipped[++n] = name ": " (reason == "" ? "(no reason printed)" : reason)
  }
  /^"[^"]*" end time:/ { gtest = 0; script = 0; after_skip = 0 }
  END {
    if (n == 0) exit
    printf "skipped tests (%d), with their reasons:\n", n
    for (i = 1; i <= n; ++i) printf "  %s\n", skipped[i]
  }
' "$log"
