#!/usr/bin/env bash
# Merge OUT/shard-*-of-N.sqlite into OUT/catalog.sqlite and verify it: the step after the shards on
# every engine (Slurm merge job, GitHub Actions merge job). `catalog merge` refuses shards built
# with different settings, seeds, metric versions or shader sources and names a missing shard;
# `catalog verify` re-renders K samples per shader (exit 1 on a problem). Writes OUT/merge.json,
# OUT/verify.json, OUT/catalog.json (info). OUT/catalog.sqlite appears only when all passed.
#
#   scripts/dist/merge-shards.sh N OUT [--verify-samples K]
set -euo pipefail
[[ $# -ge 2 ]] || { echo "usage: $0 N OUT [--verify-samples K]" >&2; exit 2; }
n=$1 out=$2 k=2
[[ "${3:-}" == --verify-samples ]] && k=$4
proctex=${PROCTEX:-$(command -v proctex || echo "$(dirname "$0")/../../build/cli/proctex")}
shards=()
for i in $(seq "$n"); do
  f=$(find "$out" -name "shard-$i-of-$n.sqlite" -type f | sort | head -1)  # artifacts may sit in subfolders
  [[ -n "$f" ]] && shards+=("$f")
done
[[ ${#shards[@]} -gt 0 ]] || { echo "merge-shards: no shard-*-of-$n.sqlite under $out" >&2; exit 1; }
tmp="$out/catalog.sqlite.tmp"
rm -f "$tmp" "$tmp-wal" "$tmp-shm"
"$proctex" catalog merge "$tmp" "${shards[@]}" --json >"$out/merge.json"   # names a missing shard
"$proctex" catalog verify --db "$tmp" --samples "$k" --json >"$out/verify.json" ||
  { echo "merge-shards: catalog verify failed, see $out/verify.json" >&2; exit 1; }
"$proctex" catalog info --db "$tmp" --json >"$out/catalog.json"
# Every connection is closed: the WAL was checkpointed into the file; readers leave empty -wal/-shm.
[[ -s "$tmp-wal" ]] && { echo "merge-shards: $tmp-wal is not empty" >&2; exit 1; }
rm -f "$tmp-wal" "$tmp-shm"
mv "$tmp" "$out/catalog.sqlite"
echo "merge-shards: $out/catalog.sqlite from ${#shards[@]} shards, verified"
