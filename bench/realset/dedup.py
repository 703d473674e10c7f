#!/usr/bin/env python3
"""Looks for candidate photos that are the same texture as labelled photos (docs/realset.md, "No added
photo is a report photo").

    /usr/bin/python3 bench/realset/dedup.py CANDIDATE.png ... [--against report|tune|all]
        [--labels bench/realset/labels.json] [--images build/realset/images] [--top 3]

For each candidate: the peak of the phase correlation of its grey centre (128 px of a half-resolution
copy, Hann window, at 5 scales 0.5-2 of that copy) with each labelled photo of the chosen split at half
resolution, the best over the scales; prints the highest peaks, one line per candidate:
"candidate  peak  photo  scale ...". A photo compared with its own centre peaks near 1; unrelated
textures at about 0.01-0.05 (docs/realset.md gives this set's numbers); pairs above --threshold
(default 0.08) are marked "LOOK" and must be looked at side by side. Calibration on this set: a
photo's own centre and the known same-texture pairs (bricks-nexuiz-bricks01 / bricks-ufoai-wall043,
fabric-ufoai-couch_d / textil001) peak at about 0.25, unrelated photos at 0.03-0.05. Exact copies
are found separately, by the sha256 of the source files. Needs numpy, scipy, oiiotool.
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
SCALES = [0.5, 0.7071, 1.0, 1.4142, 2.0]
PATCH = 128


def load_grey(path):
    """8-bit image -> float grey (mean of R, G, B) in [0, 1], via oiiotool to a binary PPM."""
    fd, tmp = tempfile.mkstemp(suffix=".ppm")
    os.close(fd)
    try:
        r = subprocess.run(["oiiotool", path, "--ch", "R,G,B", "-d", "uint8", "-o", tmp], capture_output=True,
                           text=True)
        if r.returncode:
            sys.exit(f"dedup: error: cannot read {path}: {r.stderr.strip()[-300:]}")
        data = open(tmp, "rb").read()
    finally:
        os.remove(tmp)
    # header: P6 <ws> w <ws> h <ws> maxval <one ws>
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    pos += 1
    w, h = int(fields[1]), int(fields[2])
    img = np.frombuffer(data, dtype=np.uint8, count=w * h * 3, offset=pos).reshape(h, w, 3)
    return img.astype(np.float64).mean(axis=2) / 255.0


def half(g):
    h, w = (g.shape[0] // 2) * 2, (g.shape[1] // 2) * 2
    g = g[:h, :w]
    return 0.25 * (g[0::2, 0::2] + g[1::2, 0::2] + g[0::2, 1::2] + g[1::2, 1::2])


def centre_patches(g):
    """(scale, Hann-windowed zero-mean 128 px centre of the half-resolution copy zoomed by scale)."""
    hg = half(g)
    out = []
    win = np.outer(np.hanning(PATCH), np.hanning(PATCH))
    for s in SCALES:
        z = ndimage.zoom(hg, s, order=1) if s != 1.0 else hg
        if min(z.shape) < PATCH:
            continue
        y, x = (z.shape[0] - PATCH) // 2, (z.shape[1] - PATCH) // 2
        p = z[y:y + PATCH, x:x + PATCH]
        p = (p - p.mean()) * win
        out.append((s, p))
    return out


def phase_peak(photo_f, shape, patch):
    """Peak of the phase correlation of a patch (zero-padded) with a photo (its FFT given)."""
    pad = np.zeros(shape)
    pad[:PATCH, :PATCH] = patch
    cross = photo_f * np.conj(np.fft.rfft2(pad))
    cross /= np.abs(cross) + 1e-12
    return float(np.fft.irfft2(cross, s=shape).max())


def sha256(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("candidates", nargs="+", help="candidate images (built PNGs)")
    ap.add_argument("--labels", default=os.path.join(HERE, "labels.json"))
    ap.add_argument("--images", default="build/realset/images", help="folder of the built labelled photos")
    ap.add_argument("--against", default="report", help="split to compare with: report, tune or all")
    ap.add_argument("--top", type=int, default=3, help="peaks printed per candidate")
    ap.add_argument("--threshold", type=float, default=0.08, help="mark pairs above this peak")
    ap.add_argument("--exclude-self", action="store_true", help="skip a labelled photo with the candidate's file name")
    args = ap.parse_args()
    items = json.load(open(args.labels))["images"]
    photos = [i["id"] for i in items if args.against == "all" or i["split"] == args.against]
    ref = []
    for pid in photos:
        g = half(load_grey(os.path.join(args.images, pid + ".png")))
        g = g - g.mean()
        ref.append((pid, g.shape, np.fft.rfft2(g)))
    for cand in args.candidates:
        name = os.path.splitext(os.path.basename(cand))[0]
        patches = centre_patches(load_grey(cand))
        peaks = []
        for pid, shape, f in ref:
            if args.exclude_self and pid == name:
                continue
            best = max(((phase_peak(f, shape, p), s) for s, p in patches if shape[0] >= PATCH and shape[1] >= PATCH),
                       default=(0.0, 0.0))
            peaks.append((best[0], pid, best[1]))
        peaks.sort(reverse=True)
        mark = "LOOK" if peaks and peaks[0][0] > args.threshold else "ok"
        print(f"{name}\t{mark}\t" + "\t".join(f"{v:.3f} {pid} x{s:g}" for v, pid, s in peaks[:args.top]), flush=True)


if __name__ == "__main__":
    main()
