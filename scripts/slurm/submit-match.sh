#!/usr/bin/env bash
# Submit batch matching to Slurm: an array of N tasks over the sorted photo list and an index job
# (afterany) that writes the complete index. Prints the two job ids.
#
#   scripts/slurm/submit-match.sh --photos /shared/photos --out /shared/matches --shards 16 \
#       [--cpus 2] [--proctex BIN] [--sbatch "--partition=cpu"] -- --db /shared/catalog.sqlite --budget 60s
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
shards=4 out= photos= cpus=2 proctex=$(command -v proctex || true) extra=
while [[ $# -gt 0 ]]; do
  case $1 in
    --shards) shards=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --photos) photos=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --proctex) proctex=$2; shift 2 ;;
    --sbatch) extra=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "submit-match: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" && -n "$photos" ]] || { echo "submit-match: --photos and --out are required" >&2; exit 2; }
[[ -x "$proctex" ]] || { echo "submit-match: proctex binary not found; pass --proctex PATH" >&2; exit 2; }
mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
photos=$(cd "$(dirname "$photos")" && pwd)/$(basename "$photos")
proctex=$(cd "$(dirname "$proctex")" && pwd)/$(basename "$proctex")
export PROCTEX_SCRIPTS=$here PROCTEX=$proctex PROCTEX_OUT=$out PROCTEX_PHOTOS=$photos PROCTEX_ARGS="$*"
# shellcheck disable=SC2086
array=$(sbatch --parsable --export=ALL --array="1-$shards" --cpus-per-task="$cpus" $extra \
  --output="$out/logs/match-%a.log" "$here/match-batch.sbatch")
array=${array%%;*}
# shellcheck disable=SC2086
index=$(sbatch --parsable --export=ALL --dependency="afterany:$array" --cpus-per-task="$cpus" $extra \
  --output="$out/logs/index.log" "$here/match-index.sbatch")
echo "$array ${index%%;*}"
