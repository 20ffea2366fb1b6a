#!/usr/bin/env bash
# Builds the experiments and runs every one of them, writing CSV and PNG files and an index.md that
# shows each figure with what it shows (and the paper's number beside ours where the paper gives
# one), then checks that every expected file is there and parses.
#
#   scripts/experiments.sh [--quick] [--no-build] [--build-dir DIR] [--out DIR]
#
# Default: the full runs (the convergence study with 500 tests at 5 densities), about 10 minutes on
# 2 cores. --quick: small runs for a smoke check (under a minute; ctest runs it, label
# "experiments"). Defaults: build dir build/, output results/experiments/. The forest_gen planner
# table needs ../shared/maps beside the repository and is left out (said so) without it.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH

quick=0
build=1
build_dir=build
out=results/experiments
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --no-build) build=0 ;;
    --build-dir) build_dir="$2"; shift ;;
    --out) out="$2"; shift ;;
    *) echo "experiments.sh: unknown option '$1' (expected --quick, --no-build, --build-dir DIR, --out DIR)" >&2; exit 2 ;;
  esac
  shift
done

if [ "$build" = 1 ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DTIMEOPT_BUILD_EXPERIMENTS=ON >/dev/null
  cmake --build "$build_dir" -j"$(nproc)" --target experiment_temporal_figures experiment_certified_vs_paper \
    experiment_tracking_vs_lambda experiment_convergence experiment_flight_loops experiment_planner_forest >/dev/null
fi
mkdir -p "$out"
start=$(date +%s)
step() {  # step NAME COMMAND...: one progress line per experiment
  local name="$1"; shift
  local t0; t0=$(date +%s)
  printf 'experiments: %-22s ... ' "$name"
  "$@" > "$out/$name.log" 2>&1 || { echo "FAILED (see $out/$name.log)"; exit 1; }
  echo "done in $(( $(date +%s) - t0 )) s"
}

if [ "$quick" = 1 ]; then reps=1; tests=20; densities="0.05 0.15"; levels="1 3 5"; pairs=3
else reps=7; tests=500; densities="0.05 0.1 0.15 0.2 0.25"; levels="1 2 3 4 5"; pairs=100; fi

step temporal_figures "$build_dir/experiment_temporal_figures" --out "$out" --repetitions "$reps"
step certified_vs_paper "$build_dir/experiment_certified_vs_paper" --out "$out" --repetitions "$reps"
step tracking_vs_lambda "$build_dir/experiment_tracking_vs_lambda" --out "$out"
# shellcheck disable=SC2086
step convergence "$build_dir/experiment_convergence" --out "$out" --tests "$tests" --densities $densities
# shellcheck disable=SC2086
step flight_loops "$build_dir/experiment_flight_loops" --out "$out" --levels $levels
forest=0
if [ -d ../shared/maps/forest_gen ]; then
  forest=1
  step planner_forest "$build_dir/experiment_planner_forest" --out "$out/planner_forest.csv" --max-pairs "$pairs"
else
  echo "experiments: planner_forest         ... skipped: ../shared/maps/forest_gen not found"
fi

# ---- every expected file is there and parses ----
csvs="allocation k_sweep rho_sweep solve_times certified_vs_paper tracking_vs_lambda convergence convergence_summary flight_loops"
pngs="allocation k_sweep rho_sweep solve_times convergence convergence_budgets convergence_density convergence_topview_decoupled convergence_topview_coupled flight_loops flight_paths tracking_vs_lambda"
if [ "$forest" = 1 ]; then csvs="$csvs planner_forest planner_forest_iterations"; pngs="$pngs planner_forest_iterations"; fi
status=0
for c in $csvs; do
  f="$out/$c.csv"
  # A header and at least one row, every row with the header's number of fields (comments aside).
  if [ ! -s "$f" ] || ! awk -F, '/^#/ {next} NR > 0 && !n {n = NF; next} NF != n {bad = 1} {rows++} END {exit (bad || rows < 1)}' "$f"; then
    echo "experiments: $f is missing or does not parse" >&2; status=1
  fi
done
for p in $pngs; do
  f="$out/$p.png"
  if [ ! -s "$f" ] || [ "$(head -c 8 "$f" | od -An -tx1 | tr -d ' \n')" != "89504e470d0a1a0a" ]; then
    echo "experiments: $f is missing or not a PNG" >&2; status=1
  fi
done

# ---- index.md ----
field() {  # field FILE ROW-MATCH COLUMN: a value from a CSV row whose first field matches
  awk -F, -v m="$2" -v c="$3" '$1 == m {print $c; exit}' "$1"
}
summary() {  # summary DENSITY FORMULATION COLUMN from convergence_summary.csv
  awk -F, -v d="$1" -v f="$2" -v c="$3" '$1 == d && $2 == f {print $c; exit}' "$out/convergence_summary.csv"
}
first_density=$(echo $densities | cut -d' ' -f1)
last_density=$(echo $densities | awk '{print $NF}')
{
  echo "# Experiments"
  echo
  echo "Written by \`scripts/experiments.sh$([ "$quick" = 1 ] && echo ' --quick')\` on $(date -u +%Y-%m-%d) in $(( $(date +%s) - start )) s."
  echo "Each figure links its CSV; the paper is Gao et al., IROS 2018."
  echo
  echo "## Time allocation against a heuristic (paper Fig. 3)"
  echo "![allocation](allocation.png)"
  echo
  echo "The optimal time allocation against uniform time scaling of the same curve ([allocation.csv](allocation.csv)):"
  echo "on the sharp turn $(field "$out/allocation.csv" sharp_turn 3) s against $(field "$out/allocation.csv" sharp_turn 4) s."
  echo "The paper's example: optimal 31.47 s against heuristic 56.52 s (1.80 x; ours $(field "$out/allocation.csv" sharp_turn 5) x on our turn)."
  echo
  echo "## rho and K (paper Fig. 5)"
  echo "![rho sweep](rho_sweep.png)"
  echo
  echo "Raising rho trades time for a smoother acceleration ([rho_sweep.csv](rho_sweep.csv))."
  echo
  echo "![K sweep](k_sweep.png)"
  echo
  echo "T against the cells per piece K converges from above ([k_sweep.csv](k_sweep.csv))."
  echo
  echo "## Solve times"
  echo "![solve times](solve_times.png)"
  echo
  echo "Our SOCP (with its structured path) against Ipopt on the same problems ([solve_times.csv](solve_times.csv))."
  echo
  echo "## Convergence with and without decoupling (paper Fig. 4)"
  echo "![convergence](convergence.png)"
  echo
  echo "![cost reduction against the budget](convergence_budgets.png)"
  echo
  echo "![convergence against density](convergence_density.png)"
  echo
  echo "Both trajectories of one test over its forest, coloured by speed on one scale (the paper's Fig. 4(a)/(b)):"
  echo
  echo "![with decoupling](convergence_topview_decoupled.png) ![without decoupling](convergence_topview_coupled.png)"
  echo
  echo "Cost / initial cost against solver time, $tests tests per density ([convergence.csv](convergence.csv), [convergence_summary.csv](convergence_summary.csv))."
  echo "Median cost reduction at 0.5 ms: density $first_density decoupled $(summary "$first_density" decoupled 13), coupled $(summary "$first_density" coupled 13);"
  echo "density $last_density decoupled $(summary "$last_density" decoupled 13), coupled $(summary "$last_density" coupled 13)."
  echo "At 50 ms: density $first_density decoupled $(summary "$first_density" decoupled 5), coupled $(summary "$first_density" coupled 5);"
  echo "density $last_density decoupled $(summary "$last_density" decoupled 5), coupled $(summary "$last_density" coupled 5)."
  echo "Both curves timed by the same jerk-limited temporal stage: median flight time at density $last_density decoupled $(summary "$last_density" decoupled 11) s, coupled $(summary "$last_density" coupled 11) s;"
  echo "squared jerk $(summary "$last_density" decoupled 10) against $(summary "$last_density" coupled 10) m^2/s^5; clearance $(summary "$last_density" decoupled 9) against $(summary "$last_density" coupled 9) m."
  echo "Median time to converge at density $last_density: decoupled $(summary "$last_density" decoupled 8) ms, coupled $(summary "$last_density" coupled 8) ms."
  echo "The paper reports (Fig. 4(d), a bar chart) a larger reduction for the decoupled formulation at every density;"
  echo "each formulation's reduction here is relative to its own initial cost, which for the coupled one includes its dynamic terms."
  echo
  echo "## Flights with rising limits (paper Sect. V-C)"
  echo "![flight loops](flight_loops.png)"
  echo
  echo "![flight paths](flight_paths.png)"
  echo
  echo "Lap times and the flown largest ratios of a jerk-input quadrotor, jerk-limited profiles ([flight_loops.csv](flight_loops.csv))."
  echo
  echo "## Paper vs certified rows, and lambda_a"
  echo "![tracking against lambda_a](tracking_vs_lambda.png)"
  echo
  echo "Bounding the acceleration change per cell (lambda_a) against the simulated tracking ([tracking_vs_lambda.csv](tracking_vs_lambda.csv));"
  echo "certified rows against the paper's on random curves: [certified_vs_paper.csv](certified_vs_paper.csv)."
  if [ "$forest" = 1 ]; then
    echo
    echo "## The planner on forest_gen"
    echo "![spatial convergence on forest_gen](planner_forest_iterations.png)"
    echo
    echo "Every plan of the forest_gen pairs ([planner_forest.csv](planner_forest.csv), iterations in [planner_forest_iterations.csv](planner_forest_iterations.csv))."
  fi
} > "$out/index.md"
echo "experiments: written $out/index.md in $(( $(date +%s) - start )) s"
exit "$status"
