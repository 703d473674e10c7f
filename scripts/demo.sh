#!/usr/bin/env bash
# make demo: the main job of proctex - a photo in, a procedural shader and its parameters out.
#   1. builds (or reuses) a catalogue of the whole shader library in build/demo/catalog.sqlite,
#   2. matches the shipped CC0 photo examples/brick.png against it,
#   3. writes the match result (JSON), a 1024x1024 render of the match, target and match side by
#      side, and the contact sheet of every shader at its defaults; prints where they are.
# Usage: scripts/demo.sh [path/to/proctex]   (the Makefile passes build/cli/proctex)
set -euo pipefail
proctex=${1:-build/cli/proctex}
out=build/demo
photo=examples/brick.png
mkdir -p "$out"

# The demo's own catalogue, never the user's default one (~/.cache/proctex/catalog.sqlite, see
# docs/catalog.md), so the demo never changes a user's file.
# 48 samples per shader (the default since session 17) and no coverage probes (a measurement the
# match does not use): about 2 minutes for the 53 shaders on a 2-core machine (4 the first time,
# compiling kernels), so a fresh `make demo` (dependencies, C++ build ~4-5 min, catalogue, match)
# stays near 10 minutes. The build is incremental: a second run checks the file and skips every
# unchanged shader (about a second).
# A denser catalogue (--samples 200, the thesis's density, ~12 minutes) matches photos no better
# (docs/performance.md, session 15).
db=$out/catalog.sqlite
samples=48

"$proctex" devices
echo
echo "demo: catalogue of the shader library ($samples samples per shader) in $db"
"$proctex" catalog build --db "$db" --samples "$samples" --probes 0
echo
echo "demo: matching $photo (CC0, see examples/SOURCES.md)"
"$proctex" match "$photo" --db "$db" -o "$out/match.json" --render "$out/match.png" --size 1024 \
  --compare "$out/compare.png"
echo
"$proctex" shaders sheet -o "$out/shaders.png" --size 192
echo
here=$(pwd)
echo "demo: results"
echo "  match result (shader, parameters, similarity, verdict): $here/$out/match.json"
echo "  the match rendered at 1024x1024:                        $here/$out/match.png"
echo "  photo and match side by side:                           $here/$out/compare.png"
echo "  every shader at its defaults:                           $here/$out/shaders.png"
echo "  catalogue used:                                         $here/$db"
echo "Try your own photo: $proctex match PHOTO --db $db --render out.png --size 2048 --compare cmp.png"
echo
echo "demo: the service and web UI (match, library, morph, synth) with this catalogue:"
echo "  $proctex serve --db $db"
echo "  then open http://127.0.0.1:8080/ and drop $photo on the page (docs/service.md);"
echo "  on http://127.0.0.1:8080/synth drop a small exemplar (16-512 px) to synthesise more of it"
