#!/usr/bin/env bash
# Build shard I of N of the catalogue into OUT/shard-I-of-N.sqlite (+ OUT/shard-I-of-N.json, the
# build report). The one command every engine runs: Slurm array tasks (scripts/slurm/), GitHub
# Actions matrix jobs (.github/workflows/catalog.yml), or a shell loop.
#
#   scripts/dist/build-shard.sh I N OUT [catalog build arguments: --seed 1 --samples 200 --costs F ...]
#
# PROCTEX: the proctex binary (default: proctex on PATH, else build/cli/proctex). Rerunning a killed
# shard continues it (every finished shader is kept); the result equals an uninterrupted run.
set -uo pipefail
[[ $# -ge 3 ]] || { echo "usage: $0 I N OUT [catalog build args...]" >&2; exit 2; }
i=$1 n=$2 out=$3
shift 3
proctex=${PROCTEX:-$(command -v proctex || echo "$(dirname "$0")/../../build/cli/proctex")}
mkdir -p "$out"
"$proctex" -q catalog build --db "$out/shard-$i-of-$n.sqlite" --shard "$i/$n" "$@" --json >"$out/shard-$i-of-$n.json.tmp"
rc=$?
if [[ $rc -eq 0 ]]; then
  mv "$out/shard-$i-of-$n.json.tmp" "$out/shard-$i-of-$n.json"
else
  rm -f "$out/shard-$i-of-$n.json.tmp"
fi
exit $rc
