#!/usr/bin/env bash
# Regenerates the pictures of docs/rgbn.md from the project's photos with `proctex rgbn` (and
# oiiotool, from openimageio-tools, to crop and lay out panels). Run from the repository root
# after building: docs/rgbn/make-pictures.sh [build/cli/proctex]
set -euo pipefail
P=${1:-build/cli/proctex}
T=../shared/textures
out=docs/rgbn
w=$(mktemp -d)
trap 'rm -rf "$w"' EXIT
q() { "$P" -q "$@"; }
panel() {  # panel OUT.jpg LABEL1 IMG1 LABEL2 IMG2 ...: a row of 256^2 tiles with captions
  local o=$1; shift
  local args=()
  while [[ $# -gt 1 ]]; do
    args+=("$2" --resize:filter=box 256x256 --text:x=6:y=20:size=16:color=1,1,0.2:font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf "$1")
    shift 2
  done
  oiiotool "${args[@]}" --mosaic:pad=4 "$(( ${#args[@]} / 5 ))x1" -d uint8 --quality 85 -o "$o"
}
# 256^2 crop of the brick photo as albedo and height.
oiiotool examples/brick.png --cut 256x256+128+128 -o "$w/brick.png"
q rgbn import --height "$w/brick.png" --scale -6 --albedo "$w/brick.png" -o "$w/b.exr"
L="135,40"
q rgbn light "$w/b.exr" --light $L -o "$w/b_lit.png"
q rgbn light "$w/b.exr" --light $L --model blinn --grey --exponent 24 --specular 0.4 -o "$w/b_blinn.png"
q rgbn view "$w/b.exr" --view albedo -o "$w/b_albedo.png"
q rgbn view "$w/b.exr" --view normals -o "$w/b_normals.png"
q rgbn view "$w/b.exr" --view needles --spacing 12 -o "$w/b_needles.png"
q rgbn view "$w/b.exr" --view base --base-sigma 3 -o "$w/b_base.png"
panel $out/views.jpg albedo "$w/b_albedo.png" "Lambert 135,40" "$w/b_lit.png" "Blinn-Phong (grey)" "$w/b_blinn.png" normals "$w/b_normals.png" "base normals (bilateral 3)" "$w/b_base.png" needles "$w/b_needles.png"

# Conventions.
q rgbn export "$w/b.exr" --convention gl -o "$w/gl.png"
q rgbn export "$w/b.exr" --convention dx -o "$w/dx.png"
q rgbn import "$w/dx.png" --convention gl -o "$w/wrong.exr"
q rgbn light "$w/wrong.exr" --light $L --grey -o "$w/wrong_lit.png"
q rgbn light "$w/b.exr" --light $L --grey -o "$w/b_grey.png"
panel $out/conventions.jpg "GL export" "$w/gl.png" "DX export" "$w/dx.png" "DX read as DX" "$w/b_grey.png" "DX read as GL (wrong)" "$w/wrong_lit.png"

# Filters (shaded grey from the upper left to show the relief).
f() { q rgbn filter "$w/b.exr" -o "$w/f_$1.exr" "${@:2}"; q rgbn light "$w/f_$1.exr" --light $L --grey -o "$w/f_$1.png"; }
f smooth --filter smooth --sigma 2
f sharpen --filter sharpen --sigma 2 --amount 2
f edge --filter edge --sigma 1 --sigma2 4 --amount 2
f detail --filter detail --sigma 1 --sigma2 4
f deepen --filter scale --amount 2.5
f flatten --filter scale --amount 0.4
f bilateral --filter bilateral --sigma 3 --sigma-n 0.15 --sigma-c 0.05
f brush --filter smooth --sigma 4 --brush 128,128,70,20
panel $out/filters1.jpg original "$w/b_grey.png" "smooth 2" "$w/f_smooth.png" "sharpen 2, x2" "$w/f_sharpen.png" "edge 1-4, x2" "$w/f_edge.png" "detail 1-4" "$w/f_detail.png"
panel $out/filters2.jpg "deepen x2.5" "$w/f_deepen.png" "flatten x0.4" "$w/f_flatten.png" "bilateral" "$w/f_bilateral.png" "smooth in a brush" "$w/f_brush.png"

# Curvature, segmentation, integration.
q rgbn curvature "$w/b.exr" --mean "$w/H.png" --gaussian "$w/K.png"
q rgbn segment "$w/b.exr" -o "$w/seg.png" --k 2 --min-size 200 --prefilter 2
q rgbn height "$w/b.exr" -o "$w/z.png"
panel $out/analysis.jpg "mean curvature H" "$w/H.png" "Gaussian curvature K" "$w/K.png" "segments (FH)" "$w/seg.png" "integrated height" "$w/z.png"

# Edits.
cat > "$w/ops.json" <<'JSON'
[{"op":"stamp","at":[70,70],"shape":"dome","radius":28,"height":10},
 {"op":"stamp","at":[190,70],"shape":"ring","radius":30,"height":5,"albedo":"keep"},
 {"op":"stamp","at":[70,190],"shape":"dimple","radius":24,"height":8},
 {"op":"pen","points":[[130,150],[170,230],[240,170]],"width":6,"depth":3,"profile":"vee","xi":10},
 {"op":"pen","points":[[10,250],[120,120]],"width":5,"depth":2,"profile":"groove"},
 {"op":"rotate","target":[-0.6,0.3,0.74],"amount":0.8,"mode":"blend","region":{"disc":[200,200,40]}},
 {"op":"paint","color":[0.5,0.08,0.05],"mode":"multiply","opacity":0.7,"region":{"disc":[70,70,28],"feather":6}}]
JSON
q rgbn edit "$w/ops.json" "$w/b.exr" -o "$w/e.exr"
q rgbn light "$w/e.exr" --light $L -o "$w/e_lit.png"
q rgbn light "$w/e.exr" --light 300,35 -o "$w/e_lit2.png"
q rgbn view "$w/e.exr" --view normals -o "$w/e_n.png"
panel $out/edits.jpg before "$w/b_lit.png" "after (light 135,40)" "$w/e_lit.png" "after (light 300,35)" "$w/e_lit2.png" "after: normals" "$w/e_n.png"

# Photometric stereo: the brick RGBN rendered under 4 lights (linear EXR), then recovered.
for a in 0 90 180 270; do
  q rgbn light "$w/b.exr" --light $a,45 --ambient 0 -o "$w/ps$a.exr"
  q rgbn light "$w/b.exr" --light $a,45 --ambient 0 -o "$w/ps$a.png"
done
q rgbn stereo "$w/ps0.exr" "$w/ps90.exr" "$w/ps180.exr" "$w/ps270.exr" --light 0,45 --light 90,45 --light 180,45 --light 270,45 -o "$w/ps.exr"
q rgbn light "$w/ps.exr" --light 300,35 -o "$w/ps_lit.png"
q rgbn light "$w/b.exr" --light 300,35 -o "$w/b_lit2.png"
panel $out/stereo.jpg "photo under 0,45" "$w/ps0.png" "photo under 180,45" "$w/ps180.png" "truth under 300,35" "$w/b_lit2.png" "recovered under 300,35" "$w/ps_lit.png"

# PTM: fit to 9 Blinn-Phong renders, render under an unseen light, synthesise 512^2.
lights=(0,30 90,30 180,30 270,30 45,60 135,60 225,60 315,60 0,90)
args=()
for l in "${lights[@]}"; do
  q rgbn light "$w/b.exr" --light "$l" --model blinn --exponent 8 --specular 0.2 -o "$w/ptm_${l/,/_}.exr"
  args+=("$w/ptm_${l/,/_}.exr" --light "$l")
done
q rgbn ptm fit "${args[@]}" -o "$w/b.ptm.exr"
q rgbn ptm render "$w/b.ptm.exr" --light 200,45 -o "$w/ptm_render.png"
q rgbn light "$w/b.exr" --light 200,45 --model blinn --exponent 8 --specular 0.2 -o "$w/ptm_truth.png"
q rgbn ptm synth "$w/b.ptm.exr" --width 512 --height 512 --patch 64 --seed 3 -o "$w/big.ptm.exr"
q rgbn ptm render "$w/big.ptm.exr" --light 200,45 -o "$w/ptm_big1.png"
q rgbn ptm render "$w/big.ptm.exr" --light 20,30 -o "$w/ptm_big2.png"
panel $out/ptm.jpg "Blinn truth 200,45" "$w/ptm_truth.png" "PTM under 200,45" "$w/ptm_render.png" "PTM synth 512^2, 200,45" "$w/ptm_big1.png" "same PTM, 20,30" "$w/ptm_big2.png"

# Normal-map MIP: the highlights of the footprint-8 level against the supersampled truth.
oiiotool examples/brick.png --cut 256x256+0+0 -o "$w/brick2.png"
q rgbn import --height "$w/brick2.png" --scale 12 -o "$w/m.exr"
q rgbn mip "$w/m.exr" -o "$w/mip" --footprints 8 --exponents 32 --shade-exponent 32 --light 120,55
panel $out/mip.jpg "truth (8x8 supersampled)" "$w/mip/truth_f8_spec.png" naive "$w/mip/naive_f8_spec.png" Toksvig "$w/mip/toksvig_f8_spec.png" "vMF, 4 lobes" "$w/mip/vmf_f8_spec.png" "SH order 6" "$w/mip/sh_f8_spec.png"

# Synthesis: grow gravel from a 128^2 example (synth/'s Lefebvre-Hoppe, the default, and jump
# maps), fill a hole in another gravel RGBN; everything shaded under the same light.
oiiotool $T/gravel.png --cut 128x128+0+0 -o "$w/gravel.png"
q rgbn import --height "$w/gravel.png" --scale 4 --albedo "$w/gravel.png" -o "$w/g.exr"
q rgbn synth "$w/g.exr" --width 384 --height 384 --seed 5 --no-cache -o "$w/g_big.exr"
q rgbn synth "$w/g.exr" --method jump --width 384 --height 384 --seed 5 -o "$w/g_big_j.exr"
q rgbn light "$w/g.exr" --light $L -o "$w/g_lit.png"
for f in g_big g_big_j; do
  q rgbn light "$w/$f.exr" --light $L -o "$w/${f}_lit.png"
  oiiotool "$w/${f}_lit.png" --cut 128x128+128+128 -o "$w/${f}_crop.png"
done
oiiotool "$w/g_big_lit.png" --resize 128x128 -o "$w/g_big_whole.png"
panel $out/synth.jpg "gravel example 128^2" "$w/g_lit.png" "synth 384^2 (128^2 crop)" "$w/g_big_crop.png" "jump maps (same crop)" "$w/g_big_j_crop.png" "synth 384^2, whole" "$w/g_big_lit.png"
oiiotool $T/gravel.png --cut 256x256+256+256 -o "$w/gravel2.png"
q rgbn import --height "$w/gravel2.png" --scale 4 --albedo "$w/gravel2.png" -o "$w/g2.exr"
oiiotool --create 256x256 3 --fill:color=1,1,1 64,64,192,192 -o "$w/hole.png"
q rgbn synth "$w/g.exr" --fill "$w/g2.exr" --mask "$w/hole.png" --compose --seed 2 -o "$w/filled.exr"
q rgbn synth "$w/g.exr" --method jump --fill "$w/g2.exr" --mask "$w/hole.png" --order hilbert --compose --seed 2 -o "$w/filled_j.exr"
for f in g2 filled filled_j; do q rgbn light "$w/$f.exr" --light $L -o "$w/${f}_lit.png"; done
q rgbn light "$w/filled.exr" --light 300,35 -o "$w/filled_lit2.png"
panel $out/synth-fill.jpg "gravel 256^2 (before)" "$w/g2_lit.png" "centre refilled: synth" "$w/filled_lit.png" "jump maps" "$w/filled_j_lit.png" "synth, light 300,35" "$w/filled_lit2.png"
echo "pictures in $out"
