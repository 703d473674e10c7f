#!/usr/bin/env bash
# Submit a sharded catalogue build to Slurm: an array of N shard tasks and a merge + verify job
# that runs when all shards succeeded. Prints the two job ids.
#
#   scripts/slurm/submit-catalog.sh --shards 8 --out /shared/catalog-run [--cpus 4] [--proctex BIN] \
#       [--sbatch "--partition=cpu --time=1:00:00"] -- --seed 1 --samples 200 [--costs last.sqlite]
#
# Everything after -- goes to every `proctex catalog build`. The shards are balanced by build cost
# (proctex catalog plan -n 8 shows the split); give every shard the same --costs file.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
shards=4 out= cpus=2 proctex=$(command -v proctex || true) extra=
while [[ $# -gt 0 ]]; do
  case $1 in
    --shards) shards=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --proctex) proctex=$2; shift 2 ;;
    --sbatch) extra=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "submit-catalog: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" ]] || { echo "submit-catalog: --out FOLDER is required (a folder every node can see)" >&2; exit 2; }
[[ -x "$proctex" ]] || { echo "submit-catalog: proctex binary not found; pass --proctex PATH" >&2; exit 2; }
mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
proctex=$(cd "$(dirname "$proctex")" && pwd)/$(basename "$proctex")
export PROCTEX_SCRIPTS=$here PROCTEX=$proctex PROCTEX_OUT=$out PROCTEX_ARGS="$*" PROCTEX_SHARDS=$shards
# shellcheck disable=SC2086  # $extra is a word list of sbatch options
array=$(sbatch --parsable --export=ALL --array="1-$shards" --cpus-per-task="$cpus" $extra \
  --output="$out/logs/shard-%a.log" "$here/catalog-shard.sbatch")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable --export=ALL --dependency="afterok:$array" --kill-on-invalid-dep=yes --cpus-per-task="$cpus" \
  $extra --output="$out/logs/merge.log" "$here/catalog-merge.sbatch")
merge=${merge%%;*}
echo "$array $merge"
