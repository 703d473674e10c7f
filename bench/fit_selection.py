#!/usr/bin/python3
"""Fits the shader selection of `proctex match` (issue 12): which material is this photo?

    build/bench/bench_select_dump --db CAT --list LIST.tsv --out DIR
    /usr/bin/python3 bench/fit_selection.py DIR --db CAT [--write search/selection_model.h]

A multinomial logistic regression from the default metric's structural features (spectrum,
pyramid and structure; colour left out: a catalogue sample's colours are random until fitted) to
the library's shaders, trained on
  - every catalogue sample, labelled with its shader (what each shader can look like), and
  - the photos of the tune split, every view of each (search::target_views: the whole photo and
    closer crops), labelled with the set of shaders a person accepts for it: the loss is
    -log sum_{accepted} P(shader), so any accepted shader is right (weight --photo-weight);
  - with `bench_select_dump --augment N`, N photo-like renders of every sample (zoom, lighting
    gradient, blur, noise), labelled with its shader,
with an L2 penalty (--l2). Features are standardised with the catalogue's mean and deviation.
At match time a photo's score for a shader is the largest logit over its views plus
alpha * log(best structural similarity of the shader's catalogue samples to the photo) - the
catalogue's nearest-sample evidence, which recognises clean renders the classifier has not seen;
probabilities are the softmax of those scores. alpha is chosen on out-of-fold scores of the tune
photos and on renders of another catalogue (bench_select_dump --synthetic, split "synthetic"),
each counting half. The report split is never used for fitting: it is only scored.

Calibration of "good" (search/match.h): the model is refitted on each half of the tune split
(stratified by kind) and scores the other half; p_good is the smallest probability such that at
least --precision of those out-of-fold top-1 choices with P >= p_good are right.
"""
import argparse
import json
import os
import sqlite3
import sys

import numpy as np

# Feature layout of the default metric (composite v106): spectrum 30, pyramid 160, colour 36,
# structure 191. Colour [190, 226) is left out.
STRUCTURAL = [(0, 190), (226, 417)]


def softmax(L):
    L = L - L.max(axis=1, keepdims=True)
    P = np.exp(L)
    return P / P.sum(axis=1, keepdims=True)


class Data:
    def __init__(self, folder, db):
        con = sqlite3.connect(db)
        meta = con.execute("select distinct metric, metric_version, resolution from shaders").fetchall()
        if len(meta) != 1:
            sys.exit("catalogue mixes metric versions: %s" % meta)
        self.metric, self.metric_version, self.resolution = meta[0]
        rows = con.execute("select s.name, f.vector from features f join shaders s on s.id = f.shader_id "
                           "order by s.name, f.idx").fetchall()
        self.names = sorted({r[0] for r in rows})
        X = np.array([np.frombuffer(r[1], dtype="<f4") for r in rows], dtype=np.float64)
        self.y = np.array([self.names.index(r[0]) for r in rows])
        index = json.load(open(os.path.join(folder, "evidence.json")))
        F = index["feature_size"]
        if X.shape[1] != F:
            sys.exit("catalogue features have %d values, the dump %d" % (X.shape[1], F))
        self.use = np.zeros(F, dtype=bool)
        for a, b in STRUCTURAL:
            self.use[a:b] = True
        T = np.fromfile(os.path.join(folder, "targets.f32"), dtype="<f4").reshape(-1, F).astype(np.float64)
        Xs = X[:, self.use]
        self.mean = Xs.mean(axis=0)
        self.scale = Xs.std(axis=0) + 1e-6
        self.Z = (Xs - self.mean) / self.scale
        self.TZ = (T[:, self.use] - self.mean) / self.scale
        # --augment rows of bench_select_dump: photo-like renders of the samples, labelled by shader.
        aug_path = os.path.join(folder, "augmented.f32")
        if os.path.exists(aug_path) and index.get("augmented"):
            XA = np.fromfile(aug_path, dtype="<f4").reshape(-1, F).astype(np.float64)
            self.Z = np.vstack([self.Z, (XA[:, self.use] - self.mean) / self.scale])
            self.y = np.concatenate([self.y, np.array(index["augmented"])])
            print("training rows: %d catalogue samples + %d augmented renders" % (len(X), len(XA)))
        self.photos = index["photos"]
        self.views = []
        at = 0
        for p in self.photos:
            self.views.append(list(range(at, at + p["scales"])))
            at += p["scales"]
        self.S = np.fromfile(os.path.join(folder, "structural.f32"), dtype="<f4").reshape(
            len(self.photos), len(self.names)).astype(np.float64)
        self.alpha = 0.0
        self.balance = False
        self.A = np.zeros((len(self.photos), len(self.names)))
        for i, p in enumerate(self.photos):
            for s in p["accepted"].split(","):
                if s in self.names:
                    self.A[i, self.names.index(s)] = 1

    def ids(self, split):
        return sorted([i for i, p in enumerate(self.photos) if p["split"] == split],
                      key=lambda i: (self.photos[i]["kind"], self.photos[i]["path"]))

    def train(self, photo_ids, l2, photo_weight, iterations=600, rate=0.5):
        n, d = self.Z.shape
        K = len(self.names)
        Y = np.eye(K)[self.y]
        PR = np.array([self.TZ[v] for i in photo_ids for v in self.views[i]]).reshape(-1, d)
        PA = np.array([self.A[i] for i in photo_ids for v in self.views[i]]).reshape(-1, K)
        # --balance: every kind weighs the same in total (a photo weighs 1 / its kind's photo count,
        # scaled to a mean of 1), so kinds with many photos do not dominate the photo term.
        PW = np.ones(len(PR))
        if self.balance and len(PR):
            count = {}
            for i in photo_ids:
                count[self.photos[i]["kind"]] = count.get(self.photos[i]["kind"], 0) + 1
            PW = np.array([1.0 / count[self.photos[i]["kind"]] for i in photo_ids for v in self.views[i]])
            PW *= len(PW) / PW.sum()
        W = np.zeros((d, K))
        b = np.zeros(K)
        for _ in range(iterations):
            G = (softmax(self.Z @ W + b) - Y) / n
            gW, gb = self.Z.T @ G, G.sum(axis=0)
            if len(PR) and photo_weight > 0:
                Q = softmax(PR @ W + b)
                target = Q * PA
                target /= target.sum(axis=1, keepdims=True) + 1e-12
                Gp = (Q - target) * (photo_weight * PW[:, None]) / len(PR)
                gW += PR.T @ Gp
                gb += Gp.sum(axis=0)
            W -= rate * (gW + l2 * W)
            b -= rate * gb
        return W, b

    def probabilities(self, W, b, i):
        scores = (self.TZ[self.views[i]] @ W + b).max(axis=0) + self.alpha * np.log(np.maximum(self.S[i], 1e-6))
        return softmax(scores[None, :])[0]


def score(data, W, b, ids):
    top1 = top3 = 0
    for i in ids:
        order = np.argsort(-data.probabilities(W, b, i))
        top1 += data.A[i, order[0]] > 0
        top3 += data.A[i, order[:3]].any()
    n = max(1, len(ids))
    return top1 / n, top3 / n


def out_of_fold(data, ids, l2, photo_weight):
    """Models fitted on each half of `ids` (alternate items by kind), each with the other half."""
    folds = []
    for fold in (0, 1):
        train = [i for k, i in enumerate(ids) if k % 2 != fold]
        test = [i for k, i in enumerate(ids) if k % 2 == fold]
        folds.append((data.train(train, l2, photo_weight), test))
    return folds


def choose_alpha(data, folds, synthetic_model, synthetic):
    best = None
    for alpha in [0, 0.5, 1, 2, 3, 4, 6, 8, 12]:
        data.alpha = alpha
        photo = np.mean([data.A[i, int(np.argmax(data.probabilities(W, b, i)))] > 0 for (W, b), test in folds for i in test])
        W, b = synthetic_model
        synth = np.mean([data.A[i, int(np.argmax(data.probabilities(W, b, i)))] > 0 for i in synthetic]) if synthetic else 0
        print("alpha %-4g out-of-fold tune top-1 %.3f, synthetic top-1 %.3f" % (alpha, photo, synth))
        if best is None or 0.5 * (photo + synth) > best[0] + 1e-9:
            best = (0.5 * (photo + synth), alpha)
    data.alpha = best[1]
    return best[1]


def calibrate(data, folds, precision):
    """p_good from the out-of-fold top-1 probabilities and rightness."""
    out = []
    for (W, b), test in folds:
        for i in test:
            p = data.probabilities(W, b, i)
            k = int(np.argmax(p))
            out.append((p[k], data.A[i, k] > 0))
    out.sort(reverse=True)
    p_good = 1.0
    for p, _ in sorted(out):
        kept = [ok for q, ok in out if q >= p]
        if kept and sum(kept) / len(kept) >= precision:
            p_good = p
            break
    kept = [ok for q, ok in out if q >= p_good]
    return p_good, out, (sum(kept), len(kept))


def write_header(path, data, W, b, version, p_good, argv, report):
    def array(values, per_line=8):
        vals = ["%.7g" % v for v in values]
        return ",\n".join("    " + ", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line))

    ranges = ", ".join("{%d, %d}" % r for r in STRUCTURAL)
    lines = [
        "#pragma once",
        "// Written by bench/fit_selection.py - do not edit by hand. The shader selection model of",
        "// search/selection.h: a multinomial logistic regression from the default metric's structural",
        "// features to the library's shaders, fitted on the catalogue's samples and the tune split of",
        "// the labelled real photos (bench/realset). " + report,
        "// Command: fit_selection.py " + " ".join(argv[1:]),
        "#include <cstddef>",
        "",
        "namespace proctex::search::selection_model {",
        "",
        "inline constexpr int kVersion = %d;" % version,
        'inline constexpr const char* kMetric = "%s";' % data.metric,
        "inline constexpr int kMetricVersion = %d;" % data.metric_version,
        "inline constexpr int kResolution = %d;" % data.resolution,
        "// Feature index ranges [begin, end) used, in order.",
        "inline constexpr std::size_t kRanges[][2] = {%s};" % ranges,
        "inline constexpr std::size_t kFeatures = %d;" % W.shape[0],
        "inline constexpr std::size_t kShaders = %d;" % W.shape[1],
        "inline constexpr const char* kShaderNames[kShaders] = {",
        "    " + ", ".join('"%s"' % n for n in data.names) + "};",
        "// Standardisation: z = (x - kMean) / kScale.",
        "inline constexpr float kMean[kFeatures] = {", array(data.mean), "};",
        "inline constexpr float kScale[kFeatures] = {", array(data.scale), "};",
        "// Logit of shader k = sum_f z_f kWeights[f * kShaders + k] + kBias[k].",
        "inline constexpr float kWeights[kFeatures * kShaders] = {", array(W.reshape(-1)), "};",
        "inline constexpr float kBias[kShaders] = {", array(b), "};",
        "// Score of shader k = its largest logit over the views + kStructuralWeight * log(best",
        "// structural similarity of its catalogue samples to the whole photo).",
        "inline constexpr double kStructuralWeight = %g;" % data.alpha,
        "// \"good\" needs the matched shader's selection probability to reach this (out-of-fold",
        "// calibration on the tune split for the precision given to the fit).",
        "inline constexpr double kGoodProbability = %.4f;" % p_good,
        "",
        "}  // namespace proctex::search::selection_model",
        "",
    ]
    open(path, "w").write("\n".join(lines))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", help="bench_select_dump output")
    ap.add_argument("--db", required=True, help="the catalogue the dump was made with")
    ap.add_argument("--l2", type=float, default=0.05)
    ap.add_argument("--photo-weight", type=float, default=0.5)
    ap.add_argument("--balance", action="store_true", help="class-balanced photo weights (each kind weighs the same)")
    ap.add_argument("--precision", type=float, default=0.95, help="wanted precision of 'good'")
    ap.add_argument("--version", type=int, default=1)
    ap.add_argument("--alpha", type=float, default=None, help="structural weight (default: chosen, see above)")
    ap.add_argument("--write", default="", help="write the model as a C++ header")
    args = ap.parse_args()
    data = Data(args.folder, args.db)
    data.balance = args.balance
    tune, report, synthetic = data.ids("tune"), data.ids("report"), data.ids("synthetic")
    W, b = data.train(tune, args.l2, args.photo_weight)
    folds = out_of_fold(data, tune, args.l2, args.photo_weight)
    alpha = choose_alpha(data, folds, (W, b), synthetic) if args.alpha is None else args.alpha
    data.alpha = alpha
    print("chosen alpha", alpha)
    t1, t3 = score(data, W, b, tune)
    r1, r3 = score(data, W, b, report)
    print("tune   (%d photos, fitted on): top-1 %.3f top-3 %.3f" % (len(tune), t1, t3))
    print("report (%d photos, held out) : top-1 %.3f top-3 %.3f" % (len(report), r1, r3))
    p_good, oof, (right, kept) = calibrate(data, folds, args.precision)
    if synthetic:
        print("synthetic (%d renders of another catalogue): top-1 %.3f top-3 %.3f" % ((len(synthetic),) + score(data, W, b, synthetic)))
    print("out-of-fold on tune: top-1 %.3f; p_good %.3f keeps %d of %d, %d right" % (
        np.mean([ok for _, ok in oof]), p_good, kept, len(oof), right))
    good = [(data.probabilities(W, b, i), i) for i in report]
    called = [(p, i) for p, i in good if p.max() >= p_good]
    print("report: top-1 with P >= p_good: %d, right %d" % (
        len(called), sum(data.A[i, int(np.argmax(p))] > 0 for p, i in called)))
    for i in tune + report + synthetic[::4]:
        p = data.probabilities(W, b, i)
        order = np.argsort(-p)[:3]
        print("%-3s %-6s %-14s %-42s %s" % ("ok" if data.A[i, order[0]] else "BAD", data.photos[i]["split"],
              data.photos[i]["kind"], os.path.basename(data.photos[i]["path"]),
              " ".join("%s %.2f" % (data.names[k], p[k]) for k in order)))
    if args.write:
        report_line = "Report split: top-1 %.3f, top-3 %.3f (%d photos); tune top-1 %.3f." % (r1, r3, len(report), t1)
        data.report_alpha = alpha
        write_header(args.write, data, W, b, args.version, p_good, sys.argv, report_line)
        print("wrote", args.write)


if __name__ == "__main__":
    main()
