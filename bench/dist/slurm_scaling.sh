#!/usr/bin/env bash
# Wall time of a sharded catalogue build on a local Slurm cluster with 1, 2 and 4 array tasks
# (docs/distributed.md "Measured"). Starts its own cluster (scripts/slurm/local-cluster.sh).
#   bench/dist/slurm_scaling.sh BUILD_DIR OUT_DIR [catalog build args]
# Default args: 12 shaders of varied cost, N = 50, 16 probes (the full catalogue is N = 200 x 53
# shaders, ~12 min per run on 2 cores; scale with `proctex catalog plan`).
set -euo pipefail
build=${1:?BUILD_DIR}
out=${2:?OUT_DIR}
shift 2
args=${*:-"--shaders bricks,caustics,checker,circle,clouds,grass,marble,rust,spots,stripes,tiles,wood --samples 50 --probes 16 --seed 1"}
root=$(cd "$(dirname "$0")/../.." && pwd)
proctex=$(cd "$build" && pwd)/cli/proctex
mkdir -p "$out"
out=$(cd "$out" && pwd)
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$(cd "$build" && pwd)/pocl-cache}
cluster=$out/cluster
eval "$("$root/scripts/slurm/local-cluster.sh" start "$cluster")"
trap '"$root/scripts/slurm/local-cluster.sh" stop "$cluster"' EXIT
# Warm the PoCL kernel cache first: the first build of a shader compiles its kernels (seconds of
# CPU), which would be charged to whichever configuration runs first.
shaders=$(grep -o -- "--shaders [^ ]*" <<<"$args" || true)
# shellcheck disable=SC2086
"$proctex" -q catalog build --db "$out/warm.sqlite" $shaders --samples 4 --probes 0 --set max_iterations=1 >/dev/null
echo "| tasks | CPUs per task | wall (s) incl. merge + verify | sum of shader CPU s | load before |"
echo "|---|---|---|---|---|"
for spec in ${CONFIGS:-1:2 2:1 4:1}; do
  tasks=${spec%%:*} cpus=${spec##*:}
  run=$out/tasks-$tasks
  rm -rf "$run"
  load=$(cut -d' ' -f1 /proc/loadavg)
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  ids=$("$root/scripts/slurm/submit-catalog.sh" --shards "$tasks" --cpus "$cpus" --out "$run" --proctex "$proctex" -- $args)
  while squeue -h -j "${ids// /,}" 2>/dev/null | grep -q .; do sleep 1; done
  t1=$(date +%s.%N)
  [[ -f "$run/catalog.sqlite" ]] || { echo "run with $tasks tasks failed: $(cat "$run"/logs/*.log)" >&2; exit 1; }
  # shellcheck disable=SC2086
  cpu=$("$proctex" catalog plan -n 1 $shaders --costs "$run/catalog.sqlite" --json | grep -o '"total": [0-9.]*' | cut -d' ' -f2)
  printf "| %s | %s | %.1f | %.1f | %s |\n" "$tasks" "$cpus" "$(echo "$t1 - $t0" | bc)" "$cpu" "$load"
done
