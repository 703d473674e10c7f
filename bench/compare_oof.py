#!/usr/bin/env python3
"""Compares the shader selection's grouped out-of-fold answers of two or more fits on the same photos.

    /usr/bin/python3 bench/compare_oof.py A.json B.json ... [--labels bench/realset/labels.json]
        [--batches 0,2,3] [--kinds sand,endgrain,...]

Each JSON is bench/fit_selection.py --oof-json output ({photo id: {shader: p}}). Scored on the photos
present in every file, restricted to --batches (0 = the first 86 photos' tune half) when given:
top-1 and top-3 (a right shader = one of the photo's accepted shaders), per kind for --kinds, and
the most frequent wrong top-1 shaders. See docs/match-evaluation.md ("Session 13").
"""
import argparse
import collections
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("oof", nargs="+")
    ap.add_argument("--labels", default=os.path.join(HERE, "realset", "labels.json"))
    ap.add_argument("--batches", default="", help="comma-separated batches to score (0: no batch); default all")
    ap.add_argument("--kinds", default="sand,endgrain,cracked_earth,leaves,marble,fabric,flagstones,parquet,"
                                       "concrete,rock,bark,gravel,grass")
    args = ap.parse_args()
    labels = {i["id"]: i for i in json.load(open(args.labels))["images"]}
    runs = [json.load(open(f)) for f in args.oof]
    ids = set(runs[0])
    for r in runs[1:]:
        ids &= set(r)
    if args.batches:
        want = {int(b) for b in args.batches.split(",")}
        ids = {i for i in ids if labels[i].get("batch", 0) in want}
    ids = sorted(ids)
    kinds = args.kinds.split(",")
    print("%d photos" % len(ids))
    for f, r in zip(args.oof, runs):
        top1 = top3 = 0
        per = collections.defaultdict(lambda: [0, 0])
        wrong = collections.Counter()
        for i in ids:
            order = sorted(r[i], key=lambda s: -r[i][s])
            acc = set(labels[i]["accepted"])
            ok1 = order[0] in acc
            top1 += ok1
            top3 += bool(acc & set(order[:3]))
            per[labels[i]["kind"]][0] += ok1
            per[labels[i]["kind"]][1] += 1
            if not ok1:
                wrong[order[0]] += 1
        print("%s: top-1 %d/%d (%.3f), top-3 %d (%.3f)" % (f, top1, len(ids), top1 / len(ids), top3, top3 / len(ids)))
        print("  per kind: " + ", ".join("%s %d/%d" % (k, per[k][0], per[k][1]) for k in kinds if per[k][1]))
        print("  wrong top-1: " + ", ".join("%s %d" % kv for kv in wrong.most_common(6)))


if __name__ == "__main__":
    main()
