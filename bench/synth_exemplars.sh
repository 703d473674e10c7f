#!/usr/bin/env bash
# Extracts the bench_synth exemplars (128x128 PNG) from installed Debian texture packages
# (scripts/install-deps.sh --with-bench installs them). Usage: bench/synth_exemplars.sh OUT_DIR
# Each line: name, package, source file, oiiotool operation (resize of the whole texture or a crop).
set -euo pipefail
out=${1:?usage: bench/synth_exemplars.sh OUT_DIR}
mkdir -p "$out"
nb=/usr/share/games/neverball/textures/mtrl
etr=/usr/share/games/etr/terrains
cb=/usr/share/games/colobot/textures
while read -r name package file op; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  if [[ ! -f "$file" ]]; then
    echo "synth_exemplars: missing $file (apt-get install $package)" >&2
    exit 1
  fi
  oiiotool "$file" --ch R,G,B $op -o "$out/$name.png"
done <<LIST
brick        neverball-data           $nb/brick.jpg                    --resize 128x128
planks       neverball-data           $nb/plank-small-light.jpg        --resize 128x128
wood         neverball-data           $nb/wood-glossy.jpg              --resize 128x128
marble       neverball-data           $nb/marble-brown-polished.jpg    --resize 128x128
grass        extremetuxracer-data     $etr/grass02.png                 --cut 128x128+0+0
pave         extremetuxracer-data     $etr/pave01.png                  --cut 128x128+0+0
pebbles      extremetuxracer-data     $etr/pebbles04.png               --cut 128x128+0+0
rock         extremetuxracer-data     $etr/rock02.png                  --cut 128x128+0+0
dirt         colobot-common-textures  $cb/dirty01.png                  --resize 128x128
lava         colobot-common-textures  $cb/lava04.png                   --resize 128x128
LIST
echo "synth_exemplars: wrote $(ls "$out"/*.png | wc -l) exemplars to $out"
