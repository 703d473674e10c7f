#!/usr/bin/python3
"""Is the selection's linear model the limit? Grouped out-of-fold top-1 of other classifiers on the
same evidence (issue 12, session 11; docs/match-evaluation.md "Session 11 (lead)").

    /usr/bin/python3 bench/select_classifiers.py DUMP --db CAT

DUMP: a bench_select_dump output with shape statistics (session 11 or later), CAT its catalogue.
Same rows and folds as bench/fit_selection.py --shape --train-project (5 folds grouped by texture
series; the project photos always trained on): extremely randomised trees and a random forest
(300 trees, leaves of at least 2, sklearn) on the catalogue renders plus the training photos'
views and grey copies (colour statistics appended, zero for renders and grey photos), a photo's
rows weighted --photo-weight each; and k-nearest tune photos (k 1 and 5) on the whole view's
features, colour statistics weighted 0, 1 or 3. A photo's score is the largest probability over its
views; right when the top shader is one a person accepts. Needs python3-sklearn
(scripts/install-deps.sh --with-bench).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_selection as fs  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--db", required=True)
    ap.add_argument("--labels", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "realset", "labels.json"))
    ap.add_argument("--photo-weight", type=float, nargs="+", default=[1.0, 20.0])
    args = ap.parse_args()
    from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier

    data = fs.Data(args.folder, args.db, shape=True)
    labels = {i["id"]: i for i in json.load(open(args.labels))["images"]}
    tune, project = data.ids("tune"), data.ids("project")
    tests = fs.fold_ids(data, tune, 5, True, labels)
    K = len(data.names)
    ncol = data.CZ.shape[1]
    catalogue = np.hstack([data.Z, np.zeros((len(data.Z), ncol))])  # renders: no colour term

    def rows_of(ids):
        X, y, w = [], [], []
        for i in ids:
            accepted = np.nonzero(data.A[i])[0]
            for r in [i] + ([data.grey_of[i]] if i in data.grey_of else []):
                for v in data.views[r]:
                    for a in accepted:  # a set-valued label: one row per accepted shader
                        X.append(np.concatenate([data.TZ[v], data.CZ[r]]))
                        y.append(a)
                        w.append(1.0 / len(accepted))
        return np.array(X), np.array(y), np.array(w)

    def predict(model, i):
        X = np.array([np.concatenate([data.TZ[v], data.CZ[i]]) for v in data.views[i]])
        P = np.zeros((len(X), K))
        P[:, model.classes_] = model.predict_proba(X)
        return P.max(axis=0)

    models = {"extra trees": ExtraTreesClassifier, "random forest": RandomForestClassifier}
    for name, cls in models.items():
        for photo_weight in args.photo_weight:
            start, top1, top3, grey1, wrong = time.time(), 0, 0, 0, {}
            for test in tests:
                train = [i for i in tune if i not in set(test)] + project
                Xp, yp, wp = rows_of(train)
                model = cls(n_estimators=300, min_samples_leaf=2, max_features="sqrt", n_jobs=1, random_state=1)
                model.fit(np.vstack([catalogue, Xp]), np.concatenate([data.y, yp]),
                          sample_weight=np.concatenate([np.ones(len(catalogue)), photo_weight * wp]))
                for i in test:
                    order = np.argsort(-predict(model, i))
                    top1 += data.A[i, order[0]] > 0
                    top3 += data.A[i, order[:3]].any()
                    if not data.A[i, order[0]]:
                        wrong[data.names[order[0]]] = wrong.get(data.names[order[0]], 0) + 1
                    if i in data.grey_of:
                        grey1 += data.A[i, int(np.argmax(predict(model, data.grey_of[i])))] > 0
            n = len(tune)
            print("%s, photo weight %g: out-of-fold photos top-1 %.3f top-3 %.3f, grey copies top-1 %.3f (%d photos, "
                  "%.0f s); most frequent wrong answers %s" % (name, photo_weight, top1 / n, top3 / n, grey1 / n, n,
                                                               time.time() - start,
                                                               sorted(wrong.items(), key=lambda x: -x[1])[:4]), flush=True)
    for colour in (0, 1, 3):
        for k in (1, 5):
            right = 0
            for test in tests:
                train = [i for i in tune if i not in set(test)]
                def feature(i):
                    whole = data.TZ[data.views[i][0]]
                    return np.concatenate([whole, colour * data.CZ[i]]) if colour else whole
                F = np.array([feature(i) for i in train])
                for i in test:
                    nearest = np.argsort(np.linalg.norm(F - feature(i), axis=1))[:k]
                    votes = data.A[[train[j] for j in nearest]].sum(axis=0)
                    right += data.A[i, int(np.argmax(votes))] > 0
            print("nearest tune photos, k %d, colour weight %g: out-of-fold top-1 %.3f" % (k, colour, right / len(tune)))


if __name__ == "__main__":
    main()
