#!/usr/bin/env python3
"""Fits the shader-selection weights of `proctex match` (issue 12) on labelled real photos.

    build/bench/bench_select_dump --db CAT --list LIST.tsv --out DIR
    python3 bench/fit_selection.py DIR [--split tune] [--report report]

The selection distance of photo p to shader k is the smallest, over the photo's views v and the
shader's catalogue samples i, of sum_g w_g d_g(p, v, i) / m_g, where d_g are the default metric's
20 group distances and m_g their median over the data (so weight 1 gives each group the same say).
The weights are fitted on the tune split (coordinate descent over a grid of weights, objective:
mean log-loss of the accepted shaders under a softmax of -D / tau), the report split is only scored.
Prints the weights as a C++ table for search/selection_weights.h.
"""
import argparse
import json
import os
import sys

import numpy as np


def load(folder):
    index = json.load(open(os.path.join(folder, "evidence.json")))
    shaders = [s["name"] for s in index["shaders"]]
    counts = [s["samples"] for s in index["shaders"]]
    groups = index["groups"]
    photos = index["photos"]
    G, S = len(groups), sum(counts)
    raw = np.fromfile(os.path.join(folder, "distances.f32"), dtype="<f4")
    total_views = sum(p["scales"] for p in photos)
    assert raw.size == total_views * S * G, (raw.size, total_views, S, G)
    raw = raw.reshape(total_views, S, G)
    V = max(p["scales"] for p in photos)
    dist = np.full((len(photos), V, S, G), np.inf, dtype=np.float32)
    at = 0
    for i, p in enumerate(photos):
        dist[i, : p["scales"]] = raw[at : at + p["scales"]]
        at += p["scales"]
    owner = np.repeat(np.arange(len(shaders)), counts)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    return index, shaders, groups, photos, dist, owner, starts


def shader_distances(dist, w, starts, view_penalty):
    # (P, V, S) weighted distances, smallest over views (with a per-view penalty), then per shader.
    d = np.tensordot(dist, w, axes=([3], [0]))
    d = d + view_penalty[None, : d.shape[1], None]
    d = np.where(np.isfinite(d), d, np.inf).min(axis=1)
    return np.minimum.reduceat(d, starts, axis=1)  # (P, K)


def scores(D, accepted_mask, tau):
    logits = -D / tau
    logits -= logits.max(axis=1, keepdims=True)
    logp = logits - np.log(np.exp(logits).sum(axis=1, keepdims=True))
    acc_logp = np.log((np.exp(logp) * accepted_mask).sum(axis=1) + 1e-12)
    top1 = accepted_mask[np.arange(len(D)), D.argmin(axis=1)]
    order = np.argsort(D, axis=1)[:, :3]
    top3 = np.array([accepted_mask[i, order[i]].any() for i in range(len(D))])
    return -acc_logp.mean(), top1.mean(), top3.mean()


SELECTION_WEIGHT = 0.5
GOOD_PROBABILITY = 0.5


def write_header(path, version, groups, med, w, pen, tau, tune, rep, argv):
    lines = [
        "#pragma once",
        "// Written by bench/fit_selection.py (do not edit by hand): the shader-selection model of",
        "// search/selection.h, fitted on the tune split of the labelled real photos (bench/realset).",
        "// Command: " + " ".join(["fit_selection.py"] + argv[1:]),
        "// Tune split: log-loss %.3f, top-1 %.3f, top-3 %.3f." % tune,
    ]
    if rep is not None:
        lines.append("// Report split: log-loss %.3f, top-1 %.3f, top-3 %.3f." % rep)
    lines += [
        "namespace proctex::search::selection {",
        "",
        "inline constexpr int kVersion = %d;" % version,
        "struct Group {",
        "  const char* name;",
        "  double median;  // median distance of the group between a labelled photo and a catalogue sample",
        "  double weight;",
        "};",
        "inline constexpr Group kGroups[] = {",
    ]
    for g, name in enumerate(groups):
        lines.append('    {"%s", %.6g, %g},' % (name, med[g], w[g]))
    lines += ["};",
              "// Added to the distance of each view of search::target_views (whole, half, quarter).",
              "inline constexpr double kViewPenalty[] = {%s};" % ", ".join("%g" % p for p in pen),
              "inline constexpr double kTemperature = %g;" % tau,
              "// The match's final choice maximises log S + kSelectionWeight log P; \"good\" needs P >= kGoodProbability",
              "// (both calibrated on the tune split by bench/calibrate_verdict.py from match results).",
              "inline constexpr double kSelectionWeight = %g;" % SELECTION_WEIGHT,
              "inline constexpr double kGoodProbability = %g;" % GOOD_PROBABILITY,
              "",
              "}  // namespace proctex::search::selection", ""]
    open(path, "w").write("\n".join(lines))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("--split", default="tune")
    ap.add_argument("--report", default="report")
    ap.add_argument("--passes", type=int, default=6)
    ap.add_argument("--groups", default="", help="comma-separated group names allowed non-zero weights")
    ap.add_argument("--write", default="", help="write the fitted model as search/selection_weights.h")
    ap.add_argument("--version", type=int, default=1, help="model version written with --write")
    args = ap.parse_args()
    index, shaders, groups, photos, dist, owner, starts = load(args.folder)
    G = len(groups)
    finite = dist[np.isfinite(dist)].reshape(-1, G) if False else None
    med = np.array([np.median(dist[..., g][np.isfinite(dist[..., g])]) for g in range(G)])
    dist = dist / med[None, None, None, :]
    accepted = np.zeros((len(photos), len(shaders)), dtype=bool)
    for i, p in enumerate(photos):
        for name in p["accepted"].split(","):
            if name in shaders:
                accepted[i, shaders.index(name)] = True
    split = np.array([p["split"] for p in photos])
    tune = split == args.split
    rep = split == args.report
    allowed = [g for g in range(G) if not args.groups or groups[g] in args.groups.split(",")]
    w = np.zeros(G)
    for g in allowed:
        if not groups[g].startswith("colour"):
            w[g] = 1.0
    V = dist.shape[1]
    pen = np.zeros(V)
    tau = 1.0

    def objective(w, pen, tau, mask):
        D = shader_distances(dist[mask], w, starts, pen)
        return scores(D, accepted[mask], tau)

    base = objective(w, pen, tau, tune)
    print("start: tune loss %.3f top1 %.3f top3 %.3f" % base)
    grid = [0, 0.125, 0.25, 0.5, 1, 2, 4, 8]
    for it in range(args.passes):
        changed = False
        for g in allowed:
            best = (objective(w, pen, tau, tune)[0], w[g])
            for v in grid:
                w2 = w.copy()
                w2[g] = v
                if w2.sum() <= 0:
                    continue
                l = objective(w2, pen, tau, tune)[0]
                if l < best[0] - 1e-6:
                    best = (l, v)
            if best[1] != w[g]:
                w[g] = best[1]
                changed = True
        for v in range(1, V):
            for p in [0, 0.5, 1, 2, 4, 1e9]:
                pen2 = pen.copy()
                pen2[v] = p
                if objective(w, pen2, tau, tune)[0] < objective(w, pen, tau, tune)[0] - 1e-6:
                    pen = pen2
                    changed = True
        for t in [0.25, 0.5, 1, 2, 4, 8, 16]:
            if objective(w, pen, t, tune)[0] < objective(w, pen, tau, tune)[0] - 1e-6:
                tau = t
                changed = True
        r = objective(w, pen, tau, tune)
        print("pass %d: tune loss %.3f top1 %.3f top3 %.3f tau %g" % (it + 1, *r, tau))
        if not changed:
            break
    print("tune   : loss %.3f top1 %.3f top3 %.3f" % objective(w, pen, tau, tune))
    if rep.any():
        print("report : loss %.3f top1 %.3f top3 %.3f" % objective(w, pen, tau, rep))
    print("view penalties:", pen.tolist(), "tau", tau)
    for g in range(G):
        print('    {"%s", %.6g, %g},' % (groups[g], med[g], w[g]))
    if args.write:
        write_header(args.write, args.version, groups, med, w, pen, tau, objective(w, pen, tau, tune),
                     objective(w, pen, tau, rep) if rep.any() else None, sys.argv)
    D = shader_distances(dist, w, starts, pen)
    for i, p in enumerate(photos):
        order = np.argsort(D[i])[:3]
        mark = "ok " if accepted[i, order[0]] else "BAD"
        print(mark, p["split"], p["kind"], os.path.basename(p["path"]), [shaders[k] for k in order],
              "accepted:", p["accepted"])


if __name__ == "__main__":
    main()
