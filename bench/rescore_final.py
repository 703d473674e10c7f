#!/usr/bin/env python3
"""Re-score `proctex match`'s final choice offline, on stored batch results of labelled photos.

    proctex match tune.txt --db CAT --out-dir tune-run          # one JSON per photo (starts included)
    python3 bench/rescore_final.py --labels bench/realset/labels.json --fit tune-run --apply report-run

Replays the final choice of search/match.cpp (log S + lambda log P over the finalists, the
outclassed rule) from each result's `starts`, checks that the replay picks the shader the matcher
picked, then tries alternatives fitted on the --fit runs only and scores them on --apply:
  - lambda (the selection's weight);
  - a per-shader look-alike bias: how similar the shader's race lanes get on photos of other
    materials (flexible shaders reach a high S on everything, so their S is weaker evidence).
Prints category accuracy for each, then tries to calibrate a "right material" probability from
what the matcher knows of its answer (logistic, leave-one-out) and the threshold that would give
95% precision. Nothing here changes the matcher; docs/match-evaluation.md (session 12) has the
results (neither the bias nor the calibration beat the matcher as it is).
"""
import argparse
import collections
import glob
import json
import math
import os


def load_runs(folder, labels):
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        if os.path.basename(path).startswith("index"):
            continue
        d = json.load(open(path))
        # A batch result ({"match": ...}) or bench_match_eval --pictures' per-photo JSON (the match).
        m = d.get("match", d)
        if "starts" not in m:
            continue
        pid = os.path.basename(path)[:-len(".json")].split("__")[-1].replace(".png", "")
        if pid not in labels:
            continue
        rows.append({"id": pid, "accepted": set(labels[pid]), "match": m})
    return rows


def candidates(m):
    """The final candidates as the matcher scored them: (shader, S, P, polished)."""
    out = []
    for s in m["starts"]:
        if not s.get("finalist"):
            continue
        if "refined_similarity" in s:
            out.append((s["shader"], s["refined_similarity"], s["selection_probability"], s.get("shape_distance", 0.0)))
        if "polished_similarity" in s:
            out.append((s["shader"], s["polished_similarity"], s["selection_probability"], 0.0))
    return out


def choose(cands, lam, bias, ratio=2.25, gamma=0.0):
    def score(c):
        return (math.log(max(c[1], 1e-9)) - bias.get(c[0], 0.0) + lam * math.log(max(c[2], 1e-9))
                - gamma * c[3])
    best = max(cands, key=score)
    most = max(cands, key=lambda c: c[1])
    if best[1] * ratio < most[1]:
        best = most
    return best[0]


def lane_bias(rows, exclude=None):
    """Per shader: mean log S of its best race lane on photos it is wrong for, minus the mean
    over all shaders (so only differences between shaders count)."""
    per = collections.defaultdict(list)
    for r in rows:
        if r["id"] == exclude:
            continue
        best = {}
        for s in r["match"]["starts"]:
            v = s.get("refined_similarity_coarse", 0)
            best[s["shader"]] = max(best.get(s["shader"], 0), v)
        for sh, v in best.items():
            if sh not in r["accepted"] and v > 0:
                per[sh].append(math.log(v))
    means = {k: sum(v) / len(v) for k, v in per.items() if len(v) >= 3}
    if not means:
        return {}
    centre = sum(means.values()) / len(means)
    return {k: v - centre for k, v in means.items()}


def accuracy(rows, lam, beta, bias_of):
    right = 0
    for r in rows:
        c = candidates(r["match"])
        if not c or r["match"].get("pattern"):
            sh = r["match"]["spec"]["shader"]
        else:
            b = {k: beta * v for k, v in bias_of(r).items()}
            sh = choose(c, lam, b)
        right += sh in r["accepted"]
    return right


FEATURES = ["log_probability", "log_similarity", "decision_margin", "similarity_margin", "probability_lead"]


def verdict_features(m, lam=1.0):
    """What the matcher knows about its own answer, for a calibrated "is it the right material"
    (session 12: this calibration did not beat the selection probability itself, so the matcher
    does not compute it):
      log P and log S of the answer; its decision (log S + lambda log P) minus the best other
      shader's among the final candidates; its S minus the best other shader's S there; log P
      minus the log of the highest selection probability of another screened shader."""
    cands = candidates(m)
    chosen = m["spec"]["shader"]
    p = max(m.get("selection_probability", 0.0), 1e-4)
    s = max(m["similarity"], 1e-4)
    mine = math.log(s) + lam * math.log(p)
    others = [c for c in cands if c[0] != chosen]
    other = max((math.log(max(c[1], 1e-4)) + lam * math.log(max(c[2], 1e-4)) for c in others), default=mine - 3.0)
    best_other_s = max((c[1] for c in others), default=0.0)
    p_other = max((c["selection_probability"] for c in m["candidates"] if c["shader"] != chosen), default=1e-4)
    return [math.log(p), math.log(s), mine - other, s - best_other_s, math.log(p) - math.log(max(p_other, 1e-4))]


def calibrate(fit, rep, target_precision=0.95, use=None, C=1.0):
    import numpy as np
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import LeaveOneOut, cross_val_predict
    use = use or FEATURES
    mask = np.array([f in use for f in FEATURES], dtype=float)
    print("features:", ", ".join(use), "C", C)
    X = np.array([verdict_features(r["match"]) for r in fit]) * mask
    y = np.array([r["match"]["spec"]["shader"] in r["accepted"] for r in fit])
    model = LogisticRegression(C=C, max_iter=1000)
    oof = cross_val_predict(model, X, y, cv=LeaveOneOut(), method="predict_proba")[:, 1]
    order = np.argsort(-oof)
    print("tune, out-of-fold: threshold / called good / right among them")
    threshold = 1.01
    for k in range(1, len(order) + 1):
        t = oof[order[k - 1]]
        prec = y[order[:k]].mean()
        if k in (5, 10, 15, 20, 25, 30, 40, 50, 60) or k == len(order):
            print(f"  top {k:3d}: p >= {t:.3f}  precision {prec:.3f}")
        if prec >= target_precision:
            threshold = t
    print(f"threshold for {target_precision:.0%} out-of-fold precision: {threshold:.3f}")

    def reliability(p, y, title):
        edges = [0, 0.2, 0.35, 0.5, 0.65, 0.8, 1.0001]
        cells = []
        for lo, hi in zip(edges, edges[1:]):
            sel = (p >= lo) & (p < hi)
            if sel.any():
                cells.append(f"[{lo:.2f},{min(hi, 1):.2f}) {sel.sum()} photos, mean p {p[sel].mean():.2f}, right {y[sel].mean():.2f}")
        brier = float(np.mean((p - y) ** 2))
        print(f"  {title}: Brier {brier:.3f}; " + "; ".join(cells))
    raw = np.array([r["match"]["selection_probability"] for r in fit])
    reliability(raw, y, "tune, the selection probability as it is")
    reliability(oof, y, "tune, material probability out-of-fold")
    model.fit(X, y)
    print("coefficients:", np.round(model.coef_[0], 3), "intercept", round(float(model.intercept_[0]), 3))
    if rep:
        Xr = np.array([verdict_features(r["match"]) for r in rep]) * mask
        yr = np.array([r["match"]["spec"]["shader"] in r["accepted"] for r in rep])
        pr = model.predict_proba(Xr)[:, 1]
        reliability(np.array([r["match"]["selection_probability"] for r in rep]), yr, "report, the selection probability")
        reliability(pr, yr, "report, material probability")
        for t in (threshold, 0.8, 0.7, 0.6):
            good = pr >= t
            print(f"report: p >= {t:.3f}: {good.sum()} called good, {yr[good].sum()} right"
                  f" (wrong-but-good {(good & ~yr).sum()} of {(~yr).sum()} wrong)")


def shape_weights(rows, title, gammas=(0, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0)):
    """Category accuracy of the final choice log S + log P - gamma x shape distance (the finalists'
    `shape_distance`, recorded since session 12)."""
    rows = [r for r in rows if any("shape_distance" in s for s in r["match"]["starts"])]
    out = []
    for g in gammas:
        right = 0
        for r in rows:
            c = candidates(r["match"])
            sh = r["match"]["spec"]["shader"] if not c or r["match"].get("pattern") else choose(c, 1.0, {}, gamma=g)
            right += sh in r["accepted"]
        out.append((g, right))
    print(f"{title} ({len(rows)} photos with shape distances): " + ", ".join(f"gamma {g:g}: {n}" for g, n in out))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", required=True)
    ap.add_argument("--fit", required=True, help="batch out-dir of the tune photos")
    ap.add_argument("--apply", help="batch out-dir of the report photos")
    ap.add_argument("--features", default="", help="comma-separated subset of " + ",".join(FEATURES))
    ap.add_argument("--C", type=float, default=1.0, help="inverse L2 strength of the logistic fit")
    ap.add_argument("--shape", action="store_true", help="only the shape distance's weight in the final choice")
    ap.add_argument("--calibrate-only", action="store_true", help="skip the final-choice alternatives")
    a = ap.parse_args()
    labels = {i["id"]: i["accepted"] for i in json.load(open(a.labels))["images"]}
    fit = load_runs(a.fit, labels)
    print(f"fit: {len(fit)} photos")
    replay_ok = sum(choose(candidates(r["match"]), 1.0, {}) == r["match"]["spec"]["shader"]
                    for r in fit if candidates(r["match"]) and not r["match"].get("pattern"))
    print(f"replay agrees with the matcher on {replay_ok} of {sum(1 for r in fit if candidates(r['match']) and not r['match'].get('pattern'))}")
    actual = sum(r["match"]["spec"]["shader"] in r["accepted"] for r in fit)
    print(f"matcher as run: {actual}/{len(fit)}")
    if a.shape:
        shape_weights(fit, "fit")
        if a.apply:
            shape_weights(load_runs(a.apply, labels), "apply")
        return
    if not a.calibrate_only:
        top = []
        for lam in (0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0):
            for beta in (0.0, 0.25, 0.5, 0.75, 1.0, 1.5):
                n = accuracy(fit, lam, beta, lambda r: lane_bias(fit, exclude=r["id"]))
                # ties go to the setting nearest the matcher's (lambda 1, no bias)
                top.append((n, -abs(lam - 1.0) - beta, lam, beta))
        top.sort(reverse=True)
        for n, _, lam, beta in top[:8]:
            print(f"fit  lambda {lam:4.2f} beta {beta:4.2f}: {n}/{len(fit)} (bias left out for each photo)")
        bias = lane_bias(fit)
        print("look-alike bias (log S above the mean on wrong photos):",
              ", ".join(f"{k} {v:+.2f}" for k, v in sorted(bias.items(), key=lambda kv: -kv[1])[:12]))
        if a.apply:
            rep = load_runs(a.apply, labels)
            actual = sum(r["match"]["spec"]["shader"] in r["accepted"] for r in rep)
            print(f"apply: {len(rep)} photos, matcher as run {actual}")
            for lam, beta in ((top[0][2], top[0][3]), (1.0, 0.0)):
                m = accuracy(rep, lam, beta, lambda r: bias)
                print(f"apply lambda {lam:4.2f} beta {beta:4.2f}: {m}/{len(rep)}")
    calibrate(fit, load_runs(a.apply, labels) if a.apply else [],
              use=a.features.split(",") if a.features else None, C=a.C)


if __name__ == "__main__":
    main()
