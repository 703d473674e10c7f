#!/usr/bin/env bash
# make bench: runs every benchmark in bench/ and leaves markdown tables in build/bench-results/
# for docs/performance.md (copy them in with the date and the machine).
set -euo pipefail
build=${1:-build}
results=$build/bench-results
mkdir -p "$results"
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/$build/pocl-cache}
{
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(free -g | awk '/Mem:/{print $2}') GB"
  echo "date: $(date -u +%Y-%m-%d)"
  echo "commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
} > "$results/machine.txt"
cat "$results/machine.txt"
"$build/bench/bench_render" --markdown "$results/render.md" --benchmark_min_time=0.2
echo "== $build/bench/bench_image (PNG writing)"
"$build/bench/bench_image"
for b in "$build"/bench/bench_metrics*; do
  [[ -x "$b" ]] || continue
  echo "== $b"
  "$b"
done
if [[ -x "$build/bench/bench_morph" ]]; then
  echo "== $build/bench/bench_morph (120 frames at 512x512, builds a bricks catalogue first)"
  "$build/bench/bench_morph" --repetitions 3 --markdown "$results/morph.md"
fi
if [[ -x "$build/bench/bench_match_eval" && -x "$build/cli/proctex" ]] && command -v python3 >/dev/null; then
  # Issue 12: the report half of the labelled real-texture set (docs/realset.md). The images are
  # fetched from Debian game-data packages once (~1.2 GB of downloads into $build/realset); the
  # catalogue is built (incrementally) at $PROCTEX_BENCH_CATALOG, default $build/bench-cat48.sqlite.
  echo "== $build/bench/bench_match_eval --real (report split of bench/realset/labels.json)"
  python3 bench/realset/build.py --out "$build/realset" --split report
  cat48=${PROCTEX_BENCH_CATALOG:-$build/bench-cat48.sqlite}
  "$build/cli/proctex" catalog build --db "$cat48" --samples 48 --probes 0
  "$build/bench/bench_match_eval" --db "$cat48" --real bench/realset/labels.json --split report \
    --real-images "$build/realset/images" --pictures "$results/match-real" \
    --markdown "$results/match-real.md" --json "$results/match-real.json"
  # ... and 53 random synthetic targets (shader identified, similarity against the noise ceiling,
  # "reproduced") plus the project photos (../shared/textures); about 15 minutes.
  echo "== $build/bench/bench_match_eval --targets 53 (synthetic targets and the project photos)"
  "$build/bench/bench_match_eval" --db "$cat48" --targets 53 --photos ../shared/textures \
    --pictures "$results/match-synthetic" --markdown "$results/match-synthetic.md" --json "$results/match-synthetic.json"
fi
if [[ -x "$build/bench/bench_serve" && -f "$build/demo/catalog.sqlite" ]]; then
  echo "== $build/bench/bench_serve (proctex serve: slider renders, first preview, service vs CLI; demo catalogue)"
  "$build/bench/bench_serve" --db "$build/demo/catalog.sqlite" --markdown "$results/serve.md"
fi
if [[ -x "$build/bench/bench_rgbn" ]]; then
  echo "== $build/bench/bench_rgbn (2048^2 filters/curvature/views, 128^2 stamp/pen edits)"
  "$build/bench/bench_rgbn" --benchmark_min_time=0.3
  echo "== $build/bench/bench_rgbn_mip (normal-map MIP: Blinn-Phong error against the supersampled truth)"
  "$build/bench/bench_rgbn_mip" --size 128 | tee "$results/rgbn_mip.md" || echo "bench_rgbn_mip: a target was missed"
fi
if [[ -x "$build/bench/bench_synth" ]] && command -v gmic >/dev/null 2>&1; then
  echo "== $build/bench/bench_synth (proctex synth vs G'MIC on 10 exemplars; a few minutes)"
  bench/synth_exemplars.sh "$build/bench-synth/exemplars"
  "$build/bench/bench_synth" --exemplars "$build/bench-synth/exemplars" --work "$build/bench-synth" \
    --proctex "$build/cli/proctex" --markdown "$results/synth.md" --sheet "$results/synth-bench.png"
fi
if [[ -x "$build/cli/proctex" && -d /usr/share/games/etr/terrains ]] && command -v oiiotool >/dev/null 2>&1; then
  echo "== bench/synth_graph.sh (proctex synth --graph: 16384^2 from three 256^2 exemplars; several minutes)"
  bench/synth_graph.sh "$build/cli/proctex" "$build/bench-synth-graph" | tee "$results/synth-graph.txt"
fi
echo "bench: tables in $results/"
