#!/usr/bin/python3
"""Replay of the race skip rule (search/match.cpp kUnracedMargin / kUnracedReach, session 16) on
per-target match JSONs written with every lane raced (bench_match_eval --pictures DIR, code before
session 16 or --race-every-lane 1): how many lanes of the targets that are not clean patterns it
would race, and their race renders. Approximate: the leader is taken from the stored race
similarities; the answers themselves are checked by running the matcher (compare_match_answers.py).
Usage: bench/replay_race_skip.py MARGIN REACH DIR [DIR...]   (the product: 0.5 1.85)"""
import glob
import json
import math
import sys

margin, reach = float(sys.argv[1]), float(sys.argv[2])
OUTCLASSED_RATIO, WAVE = 2.25, 2
lanes = raced = renders = saved = targets = 0
for folder in sys.argv[3:]:
    for path in sorted(glob.glob(folder + "/*.json")):
        m = json.load(open(path))
        m = m.get("match", m)
        if "starts" not in m or m.get("pattern"):
            continue
        starts = m["starts"]
        if any(not s.get("raced", True) for s in starts):
            sys.exit(f"{path}: written by the lazy race; replay runs of every lane raced")
        order = sorted(starts, key=lambda s: -s["selection_probability"])
        leader, leader_s, i = -math.inf, 0.0, 0
        while i < len(order) and (i == 0 or math.log(max(order[i]["selection_probability"], 1e-9)) > leader - margin):
            for s in order[i:i + WAVE]:
                score = math.log(max(s["race_similarity_coarse"], 1e-9)) + math.log(max(s["selection_probability"], 1e-9))
                if score > leader:
                    leader, leader_s = score, s["race_similarity_coarse"]
            i += WAVE
        i = min(i, len(order))
        skipped = [s for s in order[i:] if s["screened_similarity"] * reach <= OUTCLASSED_RATIO * leader_s]
        targets += 1
        lanes += len(order)
        raced += len(order) - len(skipped)
        renders += m["evaluations"]
        # A skipped lane's race renders (a lane's first 1/5 of the evaluations and its colour fit;
        # the rest of a finalist's refinement is not counted).
        saved += sum(min(s["evaluations"], 60) for s in skipped)
print(f"{targets} targets that are not clean patterns: {raced} of {lanes} lanes raced; "
      f"about {saved} of {renders} renders saved")
