#!/usr/bin/env python3
"""Calibrates the final choice and the verdict of `proctex match` (issue 12) on labelled photos.

    /usr/bin/python3 bench/calibrate_verdict.py LIST.tsv RESULTS_DIR [--split tune]

LIST.tsv: "path<TAB>accepted shaders<TAB>split<TAB>kind" (bench_select_dump's list); RESULTS_DIR
holds one match result per photo, named after the photo's file stem (<stem>.json, as written by
`proctex match PHOTO -o DIR/<stem>.json`).

1. The final choice among the finalists maximises log S + lambda log P (S: similarity at the full
   resolution, P: the selection probability of the shader). Each lambda of a grid is scored by the
   category accuracy it gives on the split (the finalists of the run stay what they were).
2. "good" needs S >= 0.5 and P >= p_good: the smallest p_good whose results called good are at
   least 95% right on the split (with the chosen lambda), reported with the count it keeps.
Prints both with the accuracy and the precision on every split present.
"""
import argparse
import json
import math
import os


def load(list_path, results):
    rows = []
    for line in open(list_path):
        if not line.strip() or line.startswith("#"):
            continue
        path, accepted, split, kind = (line.rstrip("\n").split("\t") + ["", "", ""])[:4]
        stem = os.path.splitext(os.path.basename(path))[0]
        f = os.path.join(results, stem + ".json")
        if not os.path.exists(f):
            continue
        r = json.load(open(f))
        finalists = [s for s in r["starts"] if s.get("finalist")]
        rows.append({"stem": stem, "kind": kind, "split": split, "accepted": set(accepted.split(",")),
                     "finalists": [(s["shader"], s.get("refined_similarity", s["refined_similarity_coarse"]),
                                    s.get("selection_probability", 1.0)) for s in finalists],
                     "result": r})
    return rows


def choose(row, lam):
    best = max(row["finalists"], key=lambda f: math.log(max(f[1], 1e-9)) + lam * math.log(max(f[2], 1e-9)))
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("list")
    ap.add_argument("results")
    ap.add_argument("--split", default="tune")
    ap.add_argument("--target", type=float, default=0.95)
    args = ap.parse_args()
    rows = load(args.list, args.results)
    splits = sorted({r["split"] for r in rows})
    tune = [r for r in rows if r["split"] == args.split]
    print("%d results (%s)" % (len(rows), ", ".join("%s %d" % (s, sum(r["split"] == s for r in rows)) for s in splits)))
    grid = [0, 0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8]
    scored = []
    for lam in grid:
        acc = sum(choose(r, lam)[0] in r["accepted"] for r in tune) / max(1, len(tune))
        scored.append((acc, -abs(lam - 1), lam))
        print("lambda %-5g tune accuracy %.3f" % (lam, acc))
    lam = max(scored)[2]
    print("chosen lambda", lam)
    chosen = [(choose(r, lam), r) for r in tune]
    thresholds = sorted({c[2] for c, _ in chosen} | {0.0})
    p_good = 1.01
    for p in thresholds:
        kept = [(c, r) for c, r in chosen if c[1] >= 0.5 and c[2] >= p]
        if kept and sum(c[0] in r["accepted"] for c, r in kept) / len(kept) >= args.target:
            p_good = p
            break
    print("p_good %.4f" % p_good)
    for s in splits:
        part = [r for r in rows if r["split"] == s]
        right = good = good_right = wrong_good = 0
        for r in part:
            c = choose(r, lam)
            ok = c[0] in r["accepted"]
            is_good = c[1] >= 0.5 and c[2] >= p_good
            right += ok
            good += is_good
            good_right += is_good and ok
            wrong_good += is_good and not ok
        n = max(1, len(part))
        wrong = max(1, len(part) - right)
        print("%-7s n %d  accuracy %.3f  good %d (precision %s)  wrong-but-good %d of %d wrong (%.3f)" % (
            s, len(part), right / n, good, "%.3f" % (good_right / good) if good else "-", wrong_good,
            len(part) - right, wrong_good / wrong))


if __name__ == "__main__":
    main()
