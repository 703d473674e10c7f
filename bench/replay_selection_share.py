#!/usr/bin/python3
"""Replay of the final choice's selection share on clean patterns (search/match.cpp
kPatternSelectionShare, session 20) on per-target match JSONs (bench_match_eval --pictures DIR, real
photos with --real or synthetic targets with --targets): for each target the spectrum calls a clean
pattern, the finalists' 256 px S, selection P and whether they are deterministic (polish.deterministic)
are re-scored under several rules, and the picks are checked against the labels (real photos:
bench/realset/labels.json accepted shaders; synthetic targets: the shader in the file name).
Approximate: certain matches (S >= 0.75) win outright, pixel-exact and looks-the-same tiers and the
polishes' own candidates are left out; the rule that was run should be reproduced (column of the code
that wrote the JSONs).
Usage: bench/replay_selection_share.py DIR [DIR...]"""
import glob
import json
import math
import os
import sys

LABELS = os.path.join(os.path.dirname(__file__), "realset", "labels.json")
labels = {i["id"]: set(i["accepted"]) for i in json.load(open(LABELS))["images"]}


def log(x):
    return math.log(max(x, 1e-9))


def finalists(match):
    return [(s["shader"], s["refined_similarity"], s["selection_probability"],
             s.get("polish", {}).get("deterministic", False))
            for s in match["starts"] if s.get("finalist")]


# Each rule: the share of the selection's weight for a candidate, given all finalists.
RULES = {
    "0.25 for all (session 10)": lambda c, all_: 0.25,
    "0.25 for deterministic candidates": lambda c, all_: 0.25 if c[3] else 1.0,
    "0.25 if the most similar is deterministic (session 20)": lambda c, all_: 0.25 if max(all_, key=lambda x: x[1])[3] else 1.0,
    "1 for all": lambda c, all_: 1.0,
}


def pick(cands, rule):
    def score(c):
        return 1e6 + c[1] if c[1] >= 0.75 else log(c[1]) + rule(c, cands) * log(c[2])
    return max(cands, key=score)[0]


for folder in sys.argv[1:]:
    right = {name: 0 for name in RULES}
    n = 0
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        name = os.path.basename(path)[:-len(".json")]
        m = json.load(open(path))
        m = m.get("match", m)
        if not m.get("pattern") or "starts" not in m:
            continue
        accepted = labels.get(name) or ({name.split("-", 1)[1]} if name[:2].isdigit() else None)
        if not accepted:
            continue
        n += 1
        cands = finalists(m)
        picks = {rule: pick(cands, f) for rule, f in RULES.items()}
        for rule in RULES:
            right[rule] += picks[rule] in accepted
        if len(set(picks.values())) > 1:
            print(f"  {name}: matcher {m['spec']['shader']}; " + ", ".join(f"{r.split(' (')[0]}: {p}" for r, p in picks.items()))
    print(f"{folder}: {n} clean-pattern targets")
    for rule in RULES:
        print(f"  {right[rule]:3d}/{n} right  {rule}")
