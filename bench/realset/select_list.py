#!/usr/bin/env python3
"""Writes the photo list of bench_select_dump (the shader selection's training and evaluation photos).

    python3 bench/realset/select_list.py [--labels bench/realset/labels.json] [--images build/realset/images] > LIST.tsv

One line per labelled image: "path<TAB>accepted shaders (comma-separated)<TAB>split<TAB>kind", in the
order of the labels. Build the images first (bench/realset/build.py). See docs/search.md (shader selection).
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", default=os.path.join(HERE, "labels.json"), help="labels file (JSON)")
    ap.add_argument("--images", default="build/realset/images", help="folder of the built images")
    args = ap.parse_args()
    try:
        items = json.load(open(args.labels))["images"]
    except (OSError, ValueError, KeyError) as e:
        print(f"select_list: error: cannot read {args.labels}: {e} (give --labels bench/realset/labels.json)",
              file=sys.stderr)
        sys.exit(1)
    missing = [i["id"] for i in items if not os.path.exists(os.path.join(args.images, i["id"] + ".png"))]
    if missing:
        print(f"select_list: error: {len(missing)} images missing in {args.images}, e.g. {missing[0]} "
              "(run python3 bench/realset/build.py first)", file=sys.stderr)
        sys.exit(1)
    for i in items:
        print("\t".join([os.path.join(args.images, i["id"] + ".png"), ",".join(i["accepted"]), i["split"], i["kind"]]))


if __name__ == "__main__":
    main()
