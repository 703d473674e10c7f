#!/usr/bin/env python3
"""Baseline: can photos alone tell the material kind? (issue 12, session 14; an experiment, not the product)

    /usr/bin/python3 bench/photo_kind_baseline.py --images build/realset/images [--features F.json]

Hand-made photo descriptors (numpy/scipy only): Lab colour moments; rotation-invariant uniform LBP
histograms (P,R = 8,1 and 16,2 at scales 1, 1/2, 1/4); a log radial power spectrum with orientation
anisotropy; gradient and structure-tensor coherence statistics. Classifiers (sklearn) predict each
labelled photo's kind, trained on the other tune photos: grouped out-of-fold over the tune split (the
folds of bench/fit_selection.py: series groups dealt largest first), and tune -> report.
The kinds' accepted shader sets are disjoint-per-kind in labels.json, so a right kind is a right
category. Result in docs/match-evaluation.md, "Session 14 (lead)".
"""
import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))

def load(path):
    # use oiiotool-free path: PNG via matplotlib? use PIL if present
    with tempfile.TemporaryDirectory() as d:
        tmp = os.path.join(d, "a.ppm")
        subprocess.run(["oiiotool", path, "--ch", "R,G,B", "-d", "uint8", "-o", tmp], check=True, capture_output=True)
        data = open(tmp, "rb").read()
    parts = data.split(maxsplit=4)
    w, h = int(parts[1]), int(parts[2])
    px = np.frombuffer(data[-w * h * 3:], dtype=np.uint8).reshape(h, w, 3)
    return px.astype(np.float64) / 255.0

def lbp_riu2(g, P, R):
    h, w = g.shape
    ang = 2 * np.pi * np.arange(P) / P
    yy, xx = np.mgrid[R:h - R, R:w - R]
    c = g[R:h - R, R:w - R]
    bits = np.zeros((P,) + c.shape, dtype=bool)
    for p in range(P):
        y = yy - R * np.sin(ang[p]); x = xx + R * np.cos(ang[p])
        v = ndimage.map_coordinates(g, [y.ravel(), x.ravel()], order=1).reshape(c.shape)
        bits[p] = v >= c + 1e-3
    trans = np.sum(bits != np.roll(bits, 1, axis=0), axis=0)
    ones = bits.sum(axis=0)
    code = np.where(trans <= 2, ones, P + 1)
    hist = np.bincount(code.ravel(), minlength=P + 2).astype(float)
    return hist / hist.sum()

def radial_spectrum(g, nb=12):
    g = g - g.mean()
    n = min(g.shape)
    g = g[:n, :n] * np.outer(np.hanning(n), np.hanning(n))
    F = np.abs(np.fft.fftshift(np.fft.fft2(g))) ** 2
    y, x = np.indices(F.shape) - n // 2
    r = np.hypot(x, y) / (n / 2)
    th = np.arctan2(y, x) % np.pi
    edges = np.geomspace(2.0 / n, 1.0, nb + 1)
    out = []
    tot = F[(r > edges[0]) & (r <= 1)].sum() + 1e-12
    for a, b in zip(edges[:-1], edges[1:]):
        m = (r > a) & (r <= b)
        out.append(np.log(F[m].sum() / tot + 1e-9))
    # orientation anisotropy per octave-ish band
    aniso = []
    for a, b in [(0.02, 0.1), (0.1, 0.3), (0.3, 1.0)]:
        m = (r > a) & (r <= b)
        ob = np.array([F[m & (th >= k * np.pi / 8) & (th < (k + 1) * np.pi / 8)].sum() for k in range(8)])
        ob = ob / (ob.sum() + 1e-12)
        aniso += [ob.max() / (ob.mean() + 1e-12), np.abs(np.sum(ob * np.exp(2j * np.arange(8) * np.pi / 8)))]
    return out + aniso

def lab(rgb):
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    M = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = lin @ M.T / np.array([0.9505, 1.0, 1.089])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    L = 116 * f[..., 1] - 16; a = 500 * (f[..., 0] - f[..., 1]); b = 200 * (f[..., 1] - f[..., 2])
    return L, a, b

def grad_stats(g):
    gx = ndimage.sobel(g, 1); gy = ndimage.sobel(g, 0)
    m = np.hypot(gx, gy)
    th = np.arctan2(gy, gx)
    # orientation coherence (structure tensor)
    Jxx = ndimage.gaussian_filter(gx * gx, 3); Jyy = ndimage.gaussian_filter(gy * gy, 3); Jxy = ndimage.gaussian_filter(gx * gy, 3)
    coh = np.sqrt((Jxx - Jyy) ** 2 + 4 * Jxy ** 2) / (Jxx + Jyy + 1e-9)
    q = np.quantile(m, [0.5, 0.9, 0.99]) / (m.mean() + 1e-9)
    return [np.log(m.mean() + 1e-6), *q, coh.mean(), np.quantile(coh, 0.9)]

def features(path):
    rgb = load(path)
    L, a, b = lab(rgb)
    g = L / 100.0
    f = {}
    f["colour"] = [L.mean() / 100, L.std() / 100, a.mean() / 50, b.mean() / 50, a.std() / 50, b.std() / 50,
                   np.corrcoef(L.ravel(), b.ravel())[0, 1] if L.std() > 0 and b.std() > 0 else 0]
    gn = (g - g.mean()) / (g.std() + 1e-6)
    lb = []
    for s in (1, 2, 4):
        gs = gn if s == 1 else ndimage.zoom(ndimage.gaussian_filter(gn, 0.5 * s), 1.0 / s, order=1)
        for P, R in ((8, 1), (16, 2)):
            lb += list(lbp_riu2(gs, P, R))
    f["lbp"] = lb
    f["spec"] = radial_spectrum(gn)
    f["grad"] = grad_stats(gn) + [float(((gn - 0) ** 3).mean()), float((gn ** 4).mean())]
    return f



def folds_of(ids, labels, k=5):
    sys.path.insert(0, HERE)
    from fit_selection import series_group
    by_stem = {it["id"]: it for it in labels}
    groups = collections.defaultdict(list)
    for n, i in enumerate(ids):
        groups[series_group({"path": i + ".png"}, by_stem)].append(n)
    folds = [[] for _ in range(k)]
    for name in sorted(groups, key=lambda g: (-len(groups[g]), g)):
        min(folds, key=len).extend(groups[name])
    return folds


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", default=os.path.join(HERE, "realset", "labels.json"))
    ap.add_argument("--images", default="build/realset/images", help="all 238 images (bench/realset/build.py)")
    ap.add_argument("--features", default="", help="cache file of the descriptors (JSON; computed when absent)")
    args = ap.parse_args()
    from sklearn.ensemble import ExtraTreesClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC
    labels = json.load(open(args.labels))["images"]
    feats = json.load(open(args.features)) if args.features and os.path.exists(args.features) else {}
    for it in labels:
        if it["id"] not in feats:
            p = os.path.join(args.images, it["id"] + ".png")
            if not os.path.exists(p):
                sys.exit("photo_kind_baseline: error: %s is missing (build the set: bench/realset/build.py)" % p)
            feats[it["id"]] = features(p)
    if args.features:
        json.dump(feats, open(args.features, "w"))
    models = {
        "logistic C=1": lambda: make_pipeline(StandardScaler(), LogisticRegression(C=1.0, max_iter=3000)),
        "logistic C=0.1": lambda: make_pipeline(StandardScaler(), LogisticRegression(C=0.1, max_iter=3000)),
        "SVM rbf C=10": lambda: make_pipeline(StandardScaler(), SVC(C=10, gamma="scale")),
        "extra trees": lambda: ExtraTreesClassifier(n_estimators=500, random_state=1),
    }
    tune = [it for it in labels if it["split"] == "tune"]
    report = [it for it in labels if it["split"] == "report"]
    folds = folds_of([it["id"] for it in tune], labels)
    for groups in (["colour", "lbp", "spec", "grad"], ["colour"], ["lbp"], ["spec", "grad"]):
        X = np.array([np.concatenate([feats[it["id"]][g] for g in groups]) for it in tune])
        y = np.array([it["kind"] for it in tune])
        Xr = np.array([np.concatenate([feats[it["id"]][g] for g in groups]) for it in report])
        yr = np.array([it["kind"] for it in report])
        for name, make in models.items():
            pred = np.empty(len(y), dtype=object)
            for f in folds:
                train = np.setdiff1d(np.arange(len(y)), f)
                pred[f] = make().fit(X[train], y[train]).predict(X[f])
            rep = make().fit(X, y).predict(Xr)
            print("%-28s %-15s tune out-of-fold %3d/%d (%.3f)   report %2d/%d (%.3f)" % (
                "+".join(groups), name, np.sum(pred == y), len(y), np.mean(pred == y), np.sum(rep == yr), len(yr),
                np.mean(rep == yr)))


if __name__ == "__main__":
    main()
