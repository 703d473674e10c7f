#!/usr/bin/env python3
"""Writes the photo list of bench_select_dump (the shader selection's training and evaluation photos).

    python3 bench/realset/select_list.py [--labels bench/realset/labels.json] [--images build/realset/images] > LIST.tsv

One line per labelled image: "path<TAB>accepted shaders (comma-separated)<TAB>split<TAB>kind", in the
order of the labels. --project DIR appends the project's four CC0 photos (../shared/textures) as split
"project", with the shaders their tests accept (tests/search/photo_match_test.cpp): scored by
fit_selection.py, trained on with --train-project. Build the images first (bench/realset/build.py). See docs/search.md (shader selection).
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# The project photos and the shaders their tests accept (brick: the labelled set's bricks kind).
PROJECT_PHOTOS = [("brick.png", "bricks,pavers,stone_wall", "bricks"), ("grass.png", "grass", "grass"),
                  ("gravel.png", "gravel,stones", "gravel"), ("hubble_deep_field.jpg", "starfield", "starfield")]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", default=os.path.join(HERE, "labels.json"), help="labels file (JSON)")
    ap.add_argument("--images", default="build/realset/images", help="folder of the built images")
    ap.add_argument("--project", default="", help="folder of the project photos (../shared/textures) to append")
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
    if args.project:
        for name, accepted, kind in PROJECT_PHOTOS:
            path = os.path.join(args.project, name)
            if not os.path.exists(path):
                print(f"select_list: error: {path} missing (give --project ../shared/textures)", file=sys.stderr)
                sys.exit(1)
            print("\t".join([path, accepted, "project", kind]))


if __name__ == "__main__":
    main()
