#!/bin/sh
# Our conic solver against ECOS (Debian's r-cran-ecosolver) on the benchmark problems: the temporal
# SOCP of temporal_benchmark at m = 10, K = 50 (rho 0, 0.1, 1) and conic_benchmark's temporal-shaped
# problems (250, 1,250 and 2,500 cells). Both read the same CBF files; each reports its own median
# solve time (ours from `timeopt conic --repeat`, ECOS from its internal timer).
#   benchmarks/ecos/compare_ecos.sh [BUILD_DIR] [REPEAT]
set -eu
build=${1:-build}
repeat=${2:-21}
here=$(cd "$(dirname "$0")" && pwd)
for tool in "$build/timeopt" "$build/temporal_benchmark" "$build/conic_benchmark"; do
  [ -x "$tool" ] || { echo "compare_ecos: $tool not built (configure with -DTIMEOPT_BUILD_BENCHMARKS=ON)" >&2; exit 2; }
done
command -v Rscript >/dev/null && Rscript -e 'library(ECOSolveR)' >/dev/null 2>&1 ||
  { echo "compare_ecos: needs Rscript with ECOSolveR (apt-get install r-cran-ecosolver)" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$build/temporal_benchmark" --export-cbf "$dir" >/dev/null
"$build/conic_benchmark" --export-cbf "$dir" >/dev/null
printf '%-30s %8s %6s %10s %18s | %6s %10s %18s %s\n' problem vars its ms objective ecos_its ecos_ms ecos_objective ecos_status
for f in "$dir"/temporal_*.cbf "$dir"/conic_temporal_*.cbf; do
  rm -f "$dir/ours.json" "$dir/ecos.json"
  "$build/timeopt" conic "$f" --repeat "$repeat" --output "$dir/ours.json" || true
  Rscript "$here/ecos_cbf.R" --repeat "$(( (repeat + 2) / 3 ))" "$f" > "$dir/ecos.json"
  python3 - "$f" "$dir/ours.json" "$dir/ecos.json" <<'PY'
import json, os, sys
f, ours, ecos = sys.argv[1], json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
objective = "%18.12g" % ours["objective"] if ours.get("objective") is not None else "%18s" % ours["status"]
print("%-30s %8d %6d %10.3f %s | %6d %10.3f %18.12g %s" % (
    os.path.basename(f), ours["num_variables"], ours["iterations"], ours["solve_time_ms"],
    objective, ecos["iterations"], ecos["solve_time_ms"], ecos["objective"], ecos["status"]))
PY
done
