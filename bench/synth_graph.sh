#!/usr/bin/env bash
# Issue 13 item 3: the multiscale exemplar graph demo and its 16384^2 measurement (docs/synth.md).
# usage: bench/synth_graph.sh PROCTEX WORK_DIR [SIZE]
# Needs extremetuxracer-data (scripts/install-deps.sh --with-bench) and oiiotool. Writes
# WORK/terrain.json, WORK/terrain-SIZE.png (+ /usr/bin/time -v output), a 1024 px reduction, a
# 512 px crop at full resolution and a zoom sequence (16x per frame) into WORK.
set -euo pipefail
proctex=${1:?usage: bench/synth_graph.sh PROCTEX WORK_DIR [SIZE]}
work=${2:?usage: bench/synth_graph.sh PROCTEX WORK_DIR [SIZE]}
size=${3:-16384}
etr=/usr/share/games/etr/terrains
for f in grass02 rock02 pebbles04; do
  [[ -f $etr/$f.png ]] || { echo "synth_graph: missing $etr/$f.png (apt-get install extremetuxracer-data)" >&2; exit 1; }
done
mkdir -p "$work"
# Han's fig. 4.2 topology: grass (root) -> rock 4x finer, -> pebbles 8x finer; pebbles look like themselves 2x closer.
cat > "$work/terrain.json" <<JSON
{"exemplars": ["$etr/grass02.png", "$etr/rock02.png", "$etr/pebbles04.png"],
 "edges": [{"from": 0, "to": 1, "scale": 4}, {"from": 0, "to": 2, "scale": 8}, {"from": 2, "to": 2, "scale": 2}]}
JSON
export PROCTEX_CACHE_DIR=${PROCTEX_CACHE_DIR:-$work/cache}
rnd=1,1,0.5,0.3
# Warm the analysis cache first, so the big run measures synthesis and writing.
"$proctex" synth --graph "$work/terrain.json" -o "$work/warm.png" --size 64 --randomness $rnd --json |
  grep -E '"analysis_(seconds|cached)"'
# zoom 6: a root pixel is 64 output pixels, the 16384^2 output spans the root exemplar once.
zoom=$(( 6 - (14 - $(awk -v s="$size" 'BEGIN{l=0; while (2^l < s) l++; print l}')) ))
(( zoom < 0 )) && zoom=0
echo "uptime before: $(uptime)"
/usr/bin/time -v "$proctex" synth --graph "$work/terrain.json" -o "$work/terrain-$size.png" --size "$size" \
  --zoom "$zoom" --randomness $rnd --json 2> "$work/time-$size.txt" > "$work/terrain-$size.json"
echo "uptime after: $(uptime)"
grep -E 'Elapsed|User time|System time|Maximum resident' "$work/time-$size.txt"
grep -E '"synthesis_seconds"|"strips"' "$work/terrain-$size.json"
oiiotool "$work/terrain-$size.png" --resize 1024x1024 -o "$work/terrain-1024.jpg"
oiiotool "$work/terrain-$size.png" --cut 512x512+$(( size / 2 ))+$(( size / 2 )) -o "$work/terrain-crop.jpg"
# A zoom sequence: 256^2 windows around the same point of the plane, 16x closer each.
frames=()
for z in 0 4 8 12; do
  x=$(( (128 << z) - 128 ))
  "$proctex" -q synth --graph "$work/terrain.json" -o "$work/zoom$z.png" --window $x,$x,256,256 --zoom $z --randomness $rnd
  frames+=("$work/zoom$z.png")
done
oiiotool "${frames[@]}" --mosaic:pad=4 4x1 -o "$work/zoom.jpg"
echo "synth_graph: pictures in $work"
