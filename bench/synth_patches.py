#!/usr/bin/env python3
"""Copied patches of a `proctex synth` output, read from its coordinate map (issue 13).

    proctex synth EX.png -o out.png --size 512 --coords c.exr
    bench/synth_patches.py c.exr EXEMPLAR_SIDE [patches.ppm]

A patch = a 4-connected region of output pixels with the same offset (exemplar position minus
output position, modulo the exemplar): a region copied verbatim from the exemplar. Prints the
number of patches, the three largest as a share of the exemplar's area (a plain tiling would be
one patch of the whole output: 16 for 512^2 from 128^2), how many cover at least a quarter of it,
the area-weighted mean patch and the share of pixels on a join (a right or lower neighbour from
another patch). Unlike bench_synth's "largest copied piece" (measured on the colours, after the
seam blend, on a 4 px grid) it sees the synthesis itself. With a third argument, writes a map with
one random colour per patch. Needs oiiotool (openimageio-tools).
"""
import random
import re
import subprocess
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path, side = sys.argv[1], int(sys.argv[2])
    out = sys.argv[3] if len(sys.argv) > 3 else None
    text = subprocess.run(['oiiotool', '--dumpdata', path], capture_output=True, text=True, check=True).stdout
    offset, width, height = {}, 0, 0
    for m in re.finditer(r'Pixel \((\d+), (\d+)\): ([-\d.]+) ([-\d.]+)', text):
        x, y = int(m.group(1)), int(m.group(2))
        offset[(x, y)] = ((int(float(m.group(3))) - x) % side, (int(float(m.group(4))) - y) % side)
        width, height = max(width, x + 1), max(height, y + 1)
    label, sizes = {}, []
    for p in offset:
        if p in label:
            continue
        k = len(sizes)
        label[p] = k
        stack, n = [p], 0
        while stack:
            c = stack.pop()
            n += 1
            x, y = c
            for q in ((x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)):
                if q in offset and q not in label and offset[q] == offset[c]:
                    label[q] = k
                    stack.append(q)
        sizes.append(n)
    area, total = side * side, width * height
    big = sorted(sizes, reverse=True)
    joins = sum(1 for (x, y) in offset if (x + 1 < width and offset[(x + 1, y)] != offset[(x, y)]) or
                (y + 1 < height and offset[(x, y + 1)] != offset[(x, y)]))
    print(f"{path}: {len(sizes)} patches, largest {' '.join(f'{s / area:.2f}' for s in big[:3])} of the exemplar, "
          f"{sum(1 for s in sizes if s >= area / 4)} of >= 1/4, area-weighted mean {sum(s * s for s in sizes) / total / area:.3f}, "
          f"join pixels {joins / total:.3f}")
    if out:
        random.seed(1)
        colour = [(random.randrange(256), random.randrange(256), random.randrange(256)) for _ in sizes]
        with open(out, 'wb') as f:
            f.write(b'P6 %d %d 255\n' % (width, height))
            f.write(bytes(v for y in range(height) for x in range(width) for v in colour[label[(x, y)]]))


if __name__ == '__main__':
    main()
