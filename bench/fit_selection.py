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

Colour (--colour): a second, linear term over the photo's colour statistics (search::colour_statistics:
CIELAB mean, deviation and quantiles of L*, a*, b*, chroma, and the hue direction; bench_select_dump
writes them to colour.f32), added to every shader's logit of a photo. Its weights are fitted on the
photo rows only (catalogue samples have random colours), jointly with the structural weights, with
their own L2 penalty (--colour-l2); the colour statistics are standardised with the tune photos'
mean and deviation. A greyscale photo (mean chroma < 0.5) gets no colour term (search/selection.h).
At match time a photo's score for a shader is the largest logit over its views plus
alpha * log(best structural similarity of the shader's catalogue samples to the photo) - the
catalogue's nearest-sample evidence, which recognises clean renders the classifier has not seen;
probabilities are the softmax of those scores. alpha is chosen on out-of-fold scores of the tune
photos and on renders of another catalogue (bench_select_dump --synthetic, split "synthetic"),
each counting half. The report split is never used for fitting: it is only scored.

Out-of-fold scores (every choice of options and alpha, and the calibration, use only these):
the tune photos are cut into --folds folds GROUPED by texture series, so that two crops or
recolours of one texture never sit on both sides: group = package + series stem, the stem being
the first alphabetic word of the file name (lowercased; the prefixes "stktex" and "generic" of
supertuxkart skipped): ufoai's wall003 ... wall_bricks006 are one group "ufoai-textures/wall",
nexuiz's bark and bark2 one group, etr's rock01/06/07 one group. Groups are dealt to the folds
largest first, each to the fold with the fewest photos (deterministic). --ungrouped gives the old
2 folds (alternate photos by kind), for comparison only.

Shape statistics (--shape): search::shape_statistics of every view and catalogue sample (orientation
coherence, orientation concentration, Hessian ridge / blob / polarity at four pyramid levels;
bench_select_dump writes them to shape.f32 and catalog_shape.f32), appended to the structural
features: what a greyscale lawn has and gravel has not (long thin upright blades).

Greyscale copies (bench_select_dump --grey, --grey-weight W): every photo also as its greyscale copy
(the structural features are computed from luminance, so the copy differs only by having no colour
term), trained on with weight W per copy and scored out of fold separately: the structural term
must stand alone for greyscale photos.

Calibration (--calibrate): temperatures of the structural and the colour logits and alpha, fitted
on the out-of-fold NLL (-log sum_{accepted} P) of the tune photos and their grey copies
(--calibrate-synthetic: and the renders of another catalogue, half the weight); written to the
header as kStructuralTemperature / kColourTemperature (search/selection.cpp divides by them).
--match-json DIR re-scores the final choice of bench_match_eval runs (see rescore_matches).

Calibration of "good" (search/match.h): p_good is the smallest probability such that at least
--precision of the out-of-fold top-1 choices with P >= p_good are right, and they are at least
--min-kept photos (default 20; otherwise p_good is 1: the selection never says "good").
"""
import argparse
import json
import os
import re
import sqlite3
import sys

import numpy as np

# Feature layout of the default metric (composite v106): spectrum 30, pyramid 160, colour 36,
# structure 191. Colour [190, 226) is left out.
STRUCTURAL = [(0, 190), (226, 417)]
# search::kGreyscaleChroma: below this mean chroma a photo is greyscale and its colour term is left out.
GREYSCALE_CHROMA = 0.5


def softmax(L):
    L = L - L.max(axis=1, keepdims=True)
    P = np.exp(L)
    return P / P.sum(axis=1, keepdims=True)


def series_group(photo, labels):
    """package + series stem of a photo (see above); project photos are their own group."""
    item = labels.get(os.path.splitext(os.path.basename(photo["path"]))[0])
    if item is None:
        return "other/" + os.path.basename(photo["path"])
    words = [w for w in re.findall("[a-z]+", os.path.basename(item["path"].split("!")[-1]).lower())
             if w not in ("stktex", "generic")]
    return item["package"] + "/" + (words[0] if words else "")


class Data:
    def __init__(self, folder, db, shape=False, train_dump=None, micro=False):
        # train_dump (--train-dump): the catalogue rows (what each shader can look like) come from
        # another dump's catalogue - e.g. more samples per shader - while the photos, the synthetic
        # rows and the nearest-sample evidence stay those of `folder` and `db` (the catalogue a
        # match runs with).
        train_db = json.load(open(os.path.join(train_dump, "evidence.json")))["db"] if train_dump else db
        con = sqlite3.connect(train_db)
        meta = con.execute("select distinct metric, metric_version, resolution from shaders").fetchall()
        if len(meta) != 1:
            sys.exit("catalogue mixes metric versions: %s" % meta)
        self.metric, self.metric_version, self.resolution = meta[0]
        rows = con.execute("select s.name, f.vector from features f join shaders s on s.id = f.shader_id "
                           "order by s.name, f.idx").fetchall()
        self.names = sorted({r[0] for r in rows})
        if train_dump:
            own = sorted({r[0] for r in sqlite3.connect(db).execute("select name from shaders").fetchall()})
            if own != self.names:
                sys.exit("--train-dump's catalogue has other shaders than --db")
            print("catalogue rows from %s (%d samples)" % (train_db, len(rows)))
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
        self.shape_features = 0
        self.micro_features = 0
        if shape:
            # --shape: search::shape_statistics of every sample (catalog_shape.f32, shader-name order =
            # the rows above) and of every view (shape.f32, the rows of targets.f32), appended to the
            # structural features and standardised with the catalogue's mean and deviation like them.
            K = index.get("shape_size", 0)
            if not K or index.get("shape_shaders") != self.names:
                sys.exit("the dump has no shape statistics for this catalogue (bench_select_dump of session 11 or later)")
            shape_index = json.load(open(os.path.join(train_dump, "evidence.json"))) if train_dump else index
            if shape_index.get("shape_shaders") != self.names:
                sys.exit("--train-dump has no shape statistics for its catalogue")
            XS = np.fromfile(os.path.join(train_dump or folder, "catalog_shape.f32"), dtype="<f4").reshape(-1, K).astype(np.float64)
            TS = np.fromfile(os.path.join(folder, "shape.f32"), dtype="<f4").reshape(-1, K).astype(np.float64)
            if len(XS) != len(X) or len(TS) != len(T):
                sys.exit("shape statistics rows (%d, %d) do not match the features (%d, %d)" % (len(XS), len(TS), len(X), len(T)))
            # bench_select_dump --micro: the last micro_size columns are search::micro_statistics
            # (local binary patterns); used with --micro, dropped without (the same rows as before).
            M = index.get("micro_size", 0)
            if micro and (not M or shape_index.get("micro_size", 0) != M):
                sys.exit("--micro needs bench_select_dump --micro dumps (and --train-dump with them)")
            if not micro and shape_index.get("micro_size", 0):
                XS = XS[:, :K - shape_index["micro_size"]]
            if not micro and M:
                TS = TS[:, :K - M]
            self.micro_features = M if micro else 0
            smean, sscale = XS.mean(axis=0), XS.std(axis=0) + 1e-6
            self.Z = np.hstack([self.Z, (XS - smean) / sscale])
            self.TZ = np.hstack([self.TZ, (TS - smean) / sscale])
            self.mean, self.scale = np.concatenate([self.mean, smean]), np.concatenate([self.scale, sscale])
            self.shape_features = XS.shape[1] - self.micro_features
        # --augment rows of bench_select_dump: photo-like renders of the samples, labelled by shader.
        aug_path = os.path.join(folder, "augmented.f32")
        if os.path.exists(aug_path) and index.get("augmented"):
            if shape:
                sys.exit("--shape with --augment rows is not supported (no shape statistics for them)")
            XA = np.fromfile(aug_path, dtype="<f4").reshape(-1, F).astype(np.float64)
            self.Z = np.vstack([self.Z, (XA[:, self.use] - self.mean) / self.scale])
            self.y = np.concatenate([self.y, np.array(index["augmented"])])
            print("training rows: %d catalogue samples + %d augmented renders" % (len(X), len(XA)))
        self.photos = index["photos"]
        # bench_select_dump --grey: a greyscale copy after each photo ("grey", "source": its photo's row)
        self.grey = np.array([bool(p.get("grey", False)) for p in self.photos])
        self.grey_of = {p["source"]: i for i, p in enumerate(self.photos) if p.get("grey")}
        self.grey_weight = 0.0  # --grey-weight: the grey copies of the training photos as training rows
        self.temperature = (1.0, 1.0)  # structural, colour: logits divided by these (calibration)
        self.views = []
        at = 0
        for p in self.photos:
            self.views.append(list(range(at, at + p["scales"])))
            at += p["scales"]
        self.S = np.fromfile(os.path.join(folder, "structural.f32"), dtype="<f4").reshape(
            len(self.photos), len(self.names)).astype(np.float64)
        # Colour statistics per photo (NaN for synthetic rows: no image).
        C = index.get("colour_size", 0)
        self.C = (np.fromfile(os.path.join(folder, "colour.f32"), dtype="<f4").reshape(len(self.photos), C)
                  .astype(np.float64) if C else np.zeros((len(self.photos), 0)))
        tune = [i for i, p in enumerate(self.photos) if p["split"] == "tune" and not p.get("grey")]
        self.cmean = self.C[tune].mean(axis=0) if C else np.zeros(0)
        self.cscale = (self.C[tune].std(axis=0) + 1e-6) if C else np.zeros(0)
        self.CZ = np.nan_to_num((self.C - self.cmean) / np.where(self.cscale > 0, self.cscale, 1), nan=0.0)
        # Greyscale photos (mean chroma [6] below search::kGreyscaleChroma = 0.5) get no colour term.
        self.has_colour = np.zeros(len(self.photos), dtype=bool)
        if C:
            self.has_colour = np.nan_to_num(self.C[:, 6], nan=0.0) >= GREYSCALE_CHROMA
            self.CZ[~self.has_colour] = 0.0
        self.colour = False
        self.colour_l2 = 0.05
        self.precondition = True
        self.alpha = 0.0
        self.balance = False
        self.A = np.zeros((len(self.photos), len(self.names)))
        for i, p in enumerate(self.photos):
            for s in p["accepted"].split(","):
                if s in self.names:
                    self.A[i, self.names.index(s)] = 1

    def ids(self, split):
        return sorted([i for i, p in enumerate(self.photos) if p["split"] == split and not p.get("grey")],
                      key=lambda i: (self.photos[i]["kind"], self.photos[i]["path"]))

    def train(self, photo_ids, l2, photo_weight, iterations=600, rate=0.5):
        """(W, b, V): structural weights and bias, colour weights (zeros without --colour)."""
        # Preconditioning: gradient descent runs on whitened features Z M, M = V diag(1/sqrt(e + 1)) V'
        # (e, V: eigen-decomposition of the catalogue's feature covariance), and the weights are
        # mapped back (W_features = M W), so the model and the header are unchanged in form.
        # Without it the largest eigenvalue (82) makes the step of 0.5 unstable in the top
        # directions (it needs < 2 / (0.5 * 82)): the weights oscillate, and the same fit in float32
        # and float64 gave grouped out-of-fold top-1 0.32 and 0.21 (session 7).
        if self.grey_weight > 0:
            photo_ids = list(photo_ids) + [self.grey_of[i] for i in photo_ids if i in self.grey_of]
        M = self.whitening().astype(np.float32) if self.precondition else np.eye(self.Z.shape[1], dtype=np.float32)
        # float32 arithmetic (twice as fast as float64; the weights are written as float anyway)
        Z = self.Z.astype(np.float32) @ M
        n, d = Z.shape
        K = len(self.names)
        Y = np.eye(K, dtype=np.float32)[self.y]
        PR = np.array([self.TZ[v] for i in photo_ids for v in self.views[i]], dtype=np.float32).reshape(-1, d) @ M
        c = self.CZ.shape[1]
        # the colour statistics are strongly correlated too (means and quantiles): whitened the same way
        Mc = self.colour_whitening().astype(np.float32) if self.precondition else np.eye(c, dtype=np.float32)
        PC = np.array([self.CZ[i] for i in photo_ids for v in self.views[i]], dtype=np.float32).reshape(-1, c) @ Mc
        V = np.zeros((c, K), dtype=np.float32)
        PA = np.array([self.A[i] for i in photo_ids for v in self.views[i]], dtype=np.float32).reshape(-1, K)
        # --balance: every kind weighs the same in total (a photo weighs 1 / its kind's photo count,
        # scaled to a mean of 1), so kinds with many photos do not dominate the photo term.
        PW = np.ones(len(PR), dtype=np.float32)
        if self.balance and len(PR):
            count = {}
            for i in photo_ids:
                count[self.photos[i]["kind"]] = count.get(self.photos[i]["kind"], 0) + 1
            PW = np.array([1.0 / count[self.photos[i]["kind"]] for i in photo_ids for v in self.views[i]], dtype=np.float32)
            PW *= len(PW) / PW.sum()
        if self.grey_weight > 0 and len(PR):
            # each grey copy weighs grey_weight x its photo (then the mean weight is 1 again)
            PW *= np.array([self.grey_weight if self.grey[i] else 1.0 for i in photo_ids for v in self.views[i]],
                           dtype=np.float32)
            PW *= len(PW) / PW.sum()
        W = np.zeros((d, K), dtype=np.float32)
        b = np.zeros(K, dtype=np.float32)
        rate, l2, photo_weight = np.float32(rate), np.float32(l2), np.float32(photo_weight)
        colour_l2 = np.float32(self.colour_l2)
        for _ in range(iterations):
            G = (softmax(Z @ W + b) - Y) / np.float32(n)
            gW, gb = Z.T @ G, G.sum(axis=0)
            gV = None
            if len(PR) and photo_weight > 0:
                Q = softmax(PR @ W + b + PC @ V)
                target = Q * PA
                target /= target.sum(axis=1, keepdims=True) + 1e-12
                Gp = (Q - target) * (photo_weight * PW[:, None]) / np.float32(len(PR))
                gW += PR.T @ Gp
                gb += Gp.sum(axis=0)
                gV = PC.T @ Gp
            W -= rate * (gW + l2 * W)
            b -= rate * gb
            if self.colour and gV is not None:
                V -= rate * (gV + colour_l2 * V)
        return (M @ W).astype(np.float64), b.astype(np.float64), (Mc @ V).astype(np.float64)

    def colour_whitening(self):
        if getattr(self, "_colour_whitening", None) is None:
            tune = [i for i, p in enumerate(self.photos) if p["split"] == "tune" and not p.get("grey")]
            C = self.CZ[tune]
            e, U = np.linalg.eigh(C.T @ C / max(1, len(C)))
            self._colour_whitening = (U / np.sqrt(np.maximum(e, 0) + 1.0)) @ U.T
        return self._colour_whitening

    def whitening(self):
        if getattr(self, "_whitening", None) is None:
            e, U = np.linalg.eigh(self.Z.T @ self.Z / len(self.Z))
            self._whitening = (U / np.sqrt(np.maximum(e, 0) + 1.0)) @ U.T
        return self._whitening

    def parts(self, model, i):
        """The three parts of photo i's scores: structural logits (largest over the views, bias
        included), colour logits, log of the best structural similarity per shader."""
        W, b, V = model
        if isinstance(V, tuple):  # a header's colour weights with their offset (load_header)
            colour = self.CZ[i] @ V[0] + (V[1] if self.has_colour[i] else 0.0)
        else:
            colour = self.CZ[i] @ V
        return ((self.TZ[self.views[i]] @ W + b).max(axis=0), colour,
                np.log(np.maximum(self.S[i], 1e-6)))

    def probabilities(self, model, i):
        s, c, n = self.parts(model, i)
        ts, tc = self.temperature
        return softmax((s / ts + c / tc + self.alpha * n)[None, :])[0]


def score(data, model, ids):
    top1 = top3 = 0
    for i in ids:
        order = np.argsort(-data.probabilities(model, i))
        top1 += data.A[i, order[0]] > 0
        top3 += data.A[i, order[:3]].any()
    n = max(1, len(ids))
    return top1 / n, top3 / n


def fold_ids(data, ids, k, grouped, labels):
    """The test photos of each fold: grouped by series (see above), or alternate items by kind."""
    if not grouped:
        return [[i for n, i in enumerate(ids) if n % 2 == fold] for fold in (0, 1)]
    groups = {}
    for i in ids:
        groups.setdefault(series_group(data.photos[i], labels), []).append(i)
    folds = [[] for _ in range(k)]
    for name in sorted(groups, key=lambda g: (-len(groups[g]), g)):
        min(folds, key=len).extend(groups[name])
    return folds


def out_of_fold(data, ids, l2, photo_weight, tests, extra=()):
    """Models fitted without each fold's photos, each with its test photos; `extra` photos are
    always trained on (e.g. the project photos with --train-project)."""
    folds = []
    for test in tests:
        train = [i for i in ids if i not in set(test)] + list(extra)
        folds.append((data.train(train, l2, photo_weight), test))
    return folds


def choose_alpha(data, folds, synthetic_model, synthetic):
    best = None
    for alpha in [0, 0.5, 1, 2, 3, 4, 6, 8, 12]:
        data.alpha = alpha
        photo = np.mean([data.A[i, int(np.argmax(data.probabilities(m, i)))] > 0 for m, test in folds for i in test])
        synth = np.mean([data.A[i, int(np.argmax(data.probabilities(synthetic_model, i)))] > 0
                         for i in synthetic]) if synthetic else 0
        print("alpha %-4g out-of-fold tune top-1 %.3f, synthetic top-1 %.3f" % (alpha, photo, synth))
        if best is None or 0.5 * (photo + synth) > best[0] + 1e-9:
            best = (0.5 * (photo + synth), alpha)
    data.alpha = best[1]
    return best[1]


def calibrate(data, folds, precision, min_kept=20):
    """p_good from the out-of-fold top-1 probabilities and rightness: the smallest P whose kept
    choices reach `precision`, counted only when at least `min_kept` photos are kept (4 of 4 right
    says little about 95 %: session 14's first v7 fit set p_good 0.807 on 4 photos)."""
    out = []
    for m, test in folds:
        for i in test:
            p = data.probabilities(m, i)
            k = int(np.argmax(p))
            out.append((p[k], data.A[i, k] > 0))
    out.sort(reverse=True)
    p_good = 1.0
    for p, _ in sorted(out):
        kept = [ok for q, ok in out if q >= p]
        if len(kept) >= min_kept and sum(kept) / len(kept) >= precision:
            p_good = p
            break
    kept = [ok for q, ok in out if q >= p_good]
    return p_good, out, (sum(kept), len(kept))


def pairs_of(data, folds, grey=False):
    """(model, row) of the out-of-fold test photos, or of their greyscale copies."""
    if not grey:
        return [(m, i) for m, test in folds for i in test]
    return [(m, data.grey_of[i]) for m, test in folds for i in test if i in data.grey_of]


def top_k(data, pairs):
    if not pairs:
        return float("nan"), float("nan")
    t1 = np.mean([data.A[i, int(np.argmax(data.probabilities(m, i)))] > 0 for m, i in pairs])
    t3 = np.mean([data.A[i, np.argsort(-data.probabilities(m, i))[:3]].any() for m, i in pairs])
    return t1, t3


def nll(data, pairs):
    """Mean negative log-likelihood of the set-valued label: -log sum_{accepted} P."""
    if not pairs:
        return float("nan")
    return float(np.mean([-np.log(max(1e-12, (data.probabilities(m, i) * data.A[i]).sum())) for m, i in pairs]))


def reliability(data, pairs, edges=(0, 0.2, 0.4, 0.6, 0.8, 0.9, 1.0001)):
    """Table rows (bin, count, mean top-1 P, share right) of the top-1 probability."""
    out = []
    top = [(data.probabilities(m, i).max(), data.A[i, int(np.argmax(data.probabilities(m, i)))] > 0) for m, i in pairs]
    for lo, hi in zip(edges[:-1], edges[1:]):
        b = [(p, ok) for p, ok in top if lo <= p < hi]
        if b:
            out.append("[%.1f,%.1f) n %3d  mean P %.3f  right %.3f" % (lo, min(hi, 1), len(b), np.mean([p for p, _ in b]),
                                                                       np.mean([ok for _, ok in b])))
    return out


def fit_temperature(data, pairs, fit_alpha=True, weights=None):
    """Temperatures (structural, colour) and alpha minimising the out-of-fold NLL of `pairs`:
    scores = s / Ts + c / Tc + alpha n. Coordinate search on a log grid, refined 4 times."""
    parts = [data.parts(m, i) for m, i in pairs]
    S = np.array([p[0] for p in parts]); C = np.array([p[1] for p in parts]); N = np.array([p[2] for p in parts])
    A = np.array([data.A[i] for _, i in pairs])
    w = np.ones(len(pairs)) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()

    def loss(ks, kc, a):
        L = ks * S + kc * C + a * N
        L = L - L.max(axis=1, keepdims=True)
        E = np.exp(L)
        return float(np.sum(w * (np.log(E.sum(axis=1)) - np.log((E * A).sum(axis=1) + 1e-300))))

    x = [1.0 / data.temperature[0], 1.0 / data.temperature[1], data.alpha]
    step = [0.5, 0.5, 1.0]
    best = loss(*x)
    for _ in range(40):
        improved = False
        for k in range(3 if fit_alpha else 2):
            for d in (-1, 1):
                y = list(x)
                y[k] = max(1e-3, y[k] * np.exp(d * step[k])) if k < 2 else max(0.0, y[k] + d * step[k])
                v = loss(*y)
                if v < best - 1e-7:
                    best, x, improved = v, y, True
        if not improved:
            step = [t / 2 for t in step]
            if max(step) < 1e-3:
                break
    return 1.0 / x[0], 1.0 / x[1], x[2], best


def load_header(path, data):
    """A written model header as (W, b, V) on this dump's standardisation, and its alpha and
    temperatures (for comparing a committed model on the same rows)."""
    text = open(path).read()

    def arr(name):
        m = re.search(r"%s\[[^\]]*\] = \{([^}]*)\}" % name, text)
        return np.array([float(v) for v in m.group(1).replace("\n", " ").split(",") if v.strip()])

    mean, scale, W, b = arr("kMean"), arr("kScale"), arr("kWeights"), arr("kBias")
    cmean, cscale, V = arr("kColourMean"), arr("kColourScale"), arr("kColourWeights")
    K = len(b)
    W = W.reshape(-1, K)
    # header z = (x - mean) / scale; the dump's z' = (x - m') / s'  ->  x = z' s' + m'
    # logit = ((z' s' + m' - mean) / scale) W + b = z' (s'/scale) W + ((m' - mean)/scale) W + b
    # (a header without shape statistics against a dump with them: zero weights for those)
    nh = len(mean)
    if nh > len(data.mean):
        sys.exit("%s uses %d features, the dump has %d (add --shape)" % (path, nh, len(data.mean)))
    W2 = np.zeros((len(data.mean), K))
    W2[:nh] = (data.scale[:nh] / scale)[:, None] * W
    b2 = b + ((data.mean[:nh] - mean) / scale) @ W
    if len(V) == 0 or not V.any():
        V2 = np.zeros((data.CZ.shape[1], K))
    else:
        V = V.reshape(-1, K)
        V2 = (data.cscale / cscale)[:, None] * V
        b_c = ((data.cmean - cmean) / cscale) @ V  # colour offset (only where the colour term applies)
        V2 = (V2, b_c)
    def num(name, default):
        m = re.search(r"%s = ([0-9.eE+-]+);" % name, text)
        return float(m.group(1)) if m else default
    return (W2, b2, V2), num("kStructuralWeight", 1.0), (num("kStructuralTemperature", 1.0), num("kColourTemperature", 1.0))


def rescore_matches(data, model, folder, weights=(0, 0.25, 0.5, 1, 1.5, 2, 3)):
    """The final choice of bench_match_eval --pictures JSONs (split "match" rows), re-scored with this
    model's P: among each target's finalists (refined and polished similarity S) the one maximising
    log S + share w log P (share 0.25 on clean patterns, where S >= 0.75 wins outright, as
    search/match.cpp). The finalists were
    chosen with the model of the run, so this is an estimate."""
    rows = [i for i, p in enumerate(data.photos) if p["split"] == "match"]
    out = {}
    for w in weights:
        ident = repro = same = 0
        for i in rows:
            r = json.load(open(os.path.join(folder, data.photos[i]["file"])))
            P = data.probabilities(model, i)
            share = 0.25 if r.get("pattern") else 1.0
            cands = []
            for st in r["starts"]:
                if not st.get("finalist"):
                    continue
                for key in ("refined_similarity", "polished_similarity"):
                    if key in st:
                        cands.append((st["shader"], st[key], st["selection_probability"]))
            if not cands:
                continue
            k = {n: j for j, n in enumerate(data.names)}
            # as search/match.cpp: on a clean pattern S >= 0.75 (kCertainMatch) wins outright
            best = max(cands, key=lambda c: 1e6 + c[1] if share < 1 and c[1] >= 0.75 else
                       np.log(max(c[1], 1e-9)) + share * w * np.log(max(P[k[c[0]]], 1e-9)))
            target = r["target"]["spec"]["shader"]
            ident += best[0] == target
            repro += best[0] == target or best[1] >= 0.95 * r["target"]["ceiling"]
            same += best[0] == r["spec"]["shader"]
        out[w] = (ident, repro, len(rows))
        print("  match JSONs, w %-4g: identified %d/%d, reproduced %d/%d (same shader as the run: %d)" % (
            w, ident, len(rows), repro, len(rows), same))
    return out


def write_header(path, data, model, version, p_good, argv, report):
    W, b, V = model
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
        "// After the metric's features: kShapeFeatures search::shape_statistics of the view, then",
        "// kMicroFeatures search::micro_statistics (none before v9).",
        "inline constexpr std::size_t kShapeFeatures = %d;" % data.shape_features,
        "inline constexpr std::size_t kMicroFeatures = %d;" % data.micro_features,
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
        "// Colour term (search::colour_statistics, fitted on the tune photos): logit of shader k +=",
        "// sum_c ((s_c - kColourMean[c]) / kColourScale[c]) kColourWeights[c * kShaders + k].",
        "inline constexpr std::size_t kColourFeatures = %d;" % V.shape[0],
        "inline constexpr float kColourMean[kColourFeatures] = {", array(data.cmean), "};",
        "inline constexpr float kColourScale[kColourFeatures] = {", array(data.cscale), "};",
        "inline constexpr float kColourWeights[kColourFeatures * kShaders] = {", array(V.reshape(-1)), "};",
        "// Score of shader k = its largest logit over the views + kStructuralWeight * log(best",
        "// structural similarity of its catalogue samples to the whole photo).",
        "inline constexpr double kStructuralWeight = %.6g;" % data.alpha,
        "// Calibration (fitted on the grouped out-of-fold NLL of the tune photos and their greyscale",
        "// copies): the structural logits (largest over the views, bias included) are divided by",
        "// kStructuralTemperature and the colour logits by kColourTemperature before the softmax.",
        "inline constexpr double kStructuralTemperature = %.6g;" % data.temperature[0],
        "inline constexpr double kColourTemperature = %.6g;" % data.temperature[1],
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
    ap.add_argument("--labels", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "realset", "labels.json"),
                    help="labels of the photos (packages and paths, for the series groups)")
    ap.add_argument("--train-dump", default="",
                    help="take the catalogue rows (features + shape statistics) from this bench_select_dump output's "
                         "catalogue instead of --db's (e.g. a catalogue with more samples per shader)")
    ap.add_argument("--l2", type=float, default=0.05)
    ap.add_argument("--photo-weight", type=float, default=0.5)
    ap.add_argument("--balance", action="store_true", help="class-balanced photo weights (each kind weighs the same)")
    ap.add_argument("--shape", action="store_true",
                    help="add the orientation and elongation statistics (search::shape_statistics) to the structural features")
    ap.add_argument("--micro", action="store_true",
                    help="with --shape: add the local binary pattern statistics (search::micro_statistics; "
                         "bench_select_dump --micro dumps)")
    ap.add_argument("--colour", action="store_true", help="fit the colour term (see above)")
    ap.add_argument("--colour-l2", type=float, default=0.05, help="L2 penalty of the colour weights")
    ap.add_argument("--grey-weight", type=float, default=0.0,
                    help="train on the greyscale copies of the photos too (bench_select_dump --grey), each "
                         "weighing this much of its photo (0: not)")
    ap.add_argument("--calibrate", action="store_true",
                    help="fit the temperatures (structural, colour) and alpha on the out-of-fold NLL of the tune "
                         "photos and their grey copies, written to the header")
    ap.add_argument("--calibrate-synthetic", action="store_true",
                    help="calibrate on the synthetic renders too (half the weight; their colours are random)")
    ap.add_argument("--folds", type=int, default=5, help="grouped out-of-fold folds")
    ap.add_argument("--no-precondition", action="store_true", help="plain gradient descent (before session 7; unstable)")
    ap.add_argument("--ungrouped", action="store_true", help="the old 2 ungrouped folds (comparison only)")
    ap.add_argument("--train-project", action="store_true",
                    help="train on the photos of split 'project' too (default: they are only scored)")
    ap.add_argument("--score-report", action="store_true",
                    help="also score the report split (the final check only: never choose options on it)")
    ap.add_argument("--match-json", default="",
                    help="folder of the bench_match_eval JSONs the dump's split 'match' rows come from "
                         "(bench_select_dump --match-json): re-score their final choice with this model")
    ap.add_argument("--compare", default="", help="a model header to score on the same rows (project, synthetic, match)")
    ap.add_argument("--compare-only", action="store_true", help="stop after --compare")
    ap.add_argument("--precision", type=float, default=0.95, help="wanted precision of 'good'")
    ap.add_argument("--min-kept", type=int, default=20,
                    help="p_good must keep at least this many out-of-fold photos (else 1: no 'good' on P)")
    ap.add_argument("--version", type=int, default=1)
    ap.add_argument("--alpha", type=float, default=None, help="structural weight (default: chosen, see above)")
    ap.add_argument("--write", default="", help="write the model as a C++ header")
    ap.add_argument("--oof-json", default="",
                    help="write each tune photo's out-of-fold probabilities ({id: {shader: p}}): what the "
                         "matcher's selection would say of a photo it was not trained on (bench_match_eval "
                         "--selection-override)")
    args = ap.parse_args()
    data = Data(args.folder, args.db, shape=args.shape, train_dump=args.train_dump or None, micro=args.micro)
    data.balance = args.balance
    data.colour = args.colour
    data.colour_l2 = args.colour_l2
    data.grey_weight = args.grey_weight
    data.precondition = not args.no_precondition
    labels = {i["id"]: i for i in json.load(open(args.labels))["images"]}
    tune, report, synthetic = data.ids("tune"), data.ids("report"), data.ids("synthetic")
    project = data.ids("project")
    extra = project if args.train_project else []
    if args.compare:
        cmp_model, cmp_alpha, cmp_t = load_header(args.compare, data)
        saved = (data.alpha, data.temperature)
        data.alpha, data.temperature = cmp_alpha, cmp_t
        print("compare %s (alpha %g, temperatures %g %g):" % (args.compare, cmp_alpha, cmp_t[0], cmp_t[1]))
        pairs = [(cmp_model, i) for i in synthetic]
        print("  synthetic top-1 %.3f top-3 %.3f NLL %.3f" % (top_k(data, pairs) + (nll(data, pairs),)))
        for i in project:
            for r in [i] + ([data.grey_of[i]] if i in data.grey_of else []):
                p = data.probabilities(cmp_model, r)
                o = np.argsort(-p)[:3]
                print("  project%s %-28s %s" % (" grey" if data.grey[r] else "     ", os.path.basename(data.photos[r]["path"]),
                                                " ".join("%s %.2f" % (data.names[k], p[k]) for k in o)))
        if args.match_json:
            rescore_matches(data, cmp_model, args.match_json)
        data.alpha, data.temperature = saved
        if args.compare_only:
            return
    model = data.train(tune + extra, args.l2, args.photo_weight)
    tests = fold_ids(data, tune, args.folds, not args.ungrouped, labels)
    print("folds (%s): %s photos" % ("ungrouped 2" if args.ungrouped else "grouped by series",
                                     " ".join(str(len(t)) for t in tests)))
    folds = out_of_fold(data, tune, args.l2, args.photo_weight, tests, extra)
    alpha = choose_alpha(data, folds, model, synthetic) if args.alpha is None else args.alpha
    data.alpha = alpha
    print("chosen alpha", alpha)

    def summary(title):
        colour_pairs, grey_pairs = pairs_of(data, folds), pairs_of(data, folds, grey=True)
        synth_pairs = [(model, i) for i in synthetic]
        print("%s (alpha %g, temperatures structural %.3f colour %.3f):" % (title, data.alpha, *data.temperature))
        print("  OUT-OF-FOLD tune, photos:      top-1 %.3f top-3 %.3f NLL %.3f (%d)" % (
            top_k(data, colour_pairs) + (nll(data, colour_pairs), len(colour_pairs))))
        if grey_pairs:
            print("  OUT-OF-FOLD tune, grey copies: top-1 %.3f top-3 %.3f NLL %.3f (%d)" % (
                top_k(data, grey_pairs) + (nll(data, grey_pairs), len(grey_pairs))))
        if synth_pairs:
            print("  synthetic (%d renders of another catalogue): top-1 %.3f top-3 %.3f NLL %.3f" % (
                (len(synth_pairs),) + top_k(data, synth_pairs) + (nll(data, synth_pairs),)))
        for name, pairs in (("out-of-fold photos + grey copies", colour_pairs + grey_pairs), ("synthetic", synth_pairs)):
            if pairs:
                print("  reliability of the top-1 probability, %s:" % name)
                for line in reliability(data, pairs):
                    print("    " + line)
        for i in project:
            for r in [i] + ([data.grey_of[i]] if i in data.grey_of else []):
                p = data.probabilities(model, r)
                o = np.argsort(-p)[:3]
                print("  project%s %-28s %s" % (" grey" if data.grey[r] else "     ", os.path.basename(data.photos[r]["path"]),
                                                " ".join("%s %.2f" % (data.names[k], p[k]) for k in o)))
        if args.match_json:
            rescore_matches(data, model, args.match_json)

    summary("uncalibrated")
    if args.calibrate:
        pairs = pairs_of(data, folds) + pairs_of(data, folds, grey=True)
        weights = [1.0] * len(pairs)
        if args.calibrate_synthetic and synthetic:
            # the renders of another catalogue (the full model: they are held out from it) weigh as
            # much in total as the out-of-fold photos: the matcher sees both kinds of target
            weights += [len(pairs) / len(synthetic)] * len(synthetic)
            pairs = pairs + [(model, i) for i in synthetic]
        ts, tc, a, loss = fit_temperature(data, pairs, weights=weights)
        data.temperature, data.alpha = (ts, tc), a
        print("calibrated on %d rows: structural temperature %.3f, colour temperature %.3f, alpha %.3f, NLL %.3f"
              % (len(pairs), ts, tc, a, loss))
        summary("calibrated")
    t1, t3 = score(data, model, tune)
    print("tune   (%d photos, fitted on): top-1 %.3f top-3 %.3f" % (len(tune), t1, t3))
    p_good, oof, (right, kept) = calibrate(data, folds, args.precision, args.min_kept)
    print("OUT-OF-FOLD tune: top-1 %.3f; p_good %.3f keeps %d of %d, %d right" % (
        np.mean([ok for _, ok in oof]), p_good, kept, len(oof), right))
    kinds = sorted({data.photos[i]["kind"] for i in tune})
    per_kind = {k: [0, 0, 0] for k in kinds}
    for m, test in folds:
        for i in test:
            per_kind[data.photos[i]["kind"]][2] += 1
            per_kind[data.photos[i]["kind"]][0] += data.A[i, int(np.argmax(data.probabilities(m, i)))] > 0
            if i in data.grey_of:
                g = data.grey_of[i]
                per_kind[data.photos[i]["kind"]][1] += data.A[g, int(np.argmax(data.probabilities(m, g)))] > 0
    print("out-of-fold per kind (photo, grey copy): " + ", ".join("%s %d/%d/%d" % (k, v[0], v[1], v[2]) for k, v in per_kind.items()))
    shown = [(i, m) for m, test in folds for i in sorted(test)]
    shown += [(i, model) for i in synthetic[::8]]
    if args.score_report:
        r1, r3 = score(data, model, report)
        print("report (%d photos, held out) : top-1 %.3f top-3 %.3f" % (len(report), r1, r3))
        good = [(data.probabilities(model, i), i) for i in report]
        called = [(p, i) for p, i in good if p.max() >= p_good]
        print("report: top-1 with P >= p_good: %d, right %d" % (
            len(called), sum(data.A[i, int(np.argmax(p))] > 0 for p, i in called)))
        shown += [(i, model) for i in report]
    for i, m in shown:
        p = data.probabilities(m, i)
        order = np.argsort(-p)[:3]
        split = data.photos[i]["split"] + ("-oof" if data.photos[i]["split"] == "tune" else "")
        print("%-3s %-9s %-14s %-42s %s" % ("ok" if data.A[i, order[0]] else "BAD", split,
              data.photos[i]["kind"], os.path.basename(data.photos[i]["path"]),
              " ".join("%s %.2f" % (data.names[k], p[k]) for k in order)))
    if args.oof_json:
        oof_probabilities = {}
        for m, test in folds:
            for i in test:
                pid = os.path.splitext(os.path.basename(data.photos[i]["path"]))[0]
                p = data.probabilities(m, i)
                oof_probabilities[pid] = {data.names[k]: float(p[k]) for k in range(len(data.names))}
        with open(args.oof_json, "w") as f:
            json.dump(oof_probabilities, f)
        print("wrote", args.oof_json, "(%d photos)" % len(oof_probabilities))
    if args.write:
        report_line = "Grouped out-of-fold tune top-1 %.3f (%d photos); tune top-1 %.3f." % (
            np.mean([ok for _, ok in oof]), len(oof), t1)
        write_header(args.write, data, model, args.version, p_good, sys.argv, report_line)
        print("wrote", args.write)


if __name__ == "__main__":
    main()
