#!/usr/bin/env bash
# make demo: renders every shader of the library at its defaults into a labelled contact sheet.
set -euo pipefail
proctex=${1:-build/cli/proctex}
out=build/demo
mkdir -p "$out"
"$proctex" devices
echo
"$proctex" shaders sheet -o "$out/shaders.png" --size 192
echo
echo "demo: contact sheet of every shader at its defaults: $(pwd)/$out/shaders.png"
