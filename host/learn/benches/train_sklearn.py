"""`et train --data` beside scikit-learn doing the same work on the same data set, wall clock,
load included (docs/measurements.md, "Training end to end").

The work: read the data set; referenced features (each row minus its visit's untouched
frame); standardise; fit QDA on every row; stratified 10-fold cross-validation and
leave-one-visit-out cross-validation of that model. With --auto, first choose the shrinkage
(regularisation) among et's six candidates by leave-one-visit-out cross-validation.

Make the data set (the method's procedure, 49 classes x 2 400 observations x 96 features) and
run on the same machine, nothing else running:

    cargo build --release -p et-host --bin et
    target/release/et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --out /tmp/big.npz
    target/release/et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --out /tmp/big.csv
    python host/learn/benches/train_sklearn.py target/release/et /tmp/big

Prints one line per (tool, file format, shrinkage) with the wall time, the best of --repeat
runs. scikit-learn's QDA shrinks toward the identity of the standardised features
(`reg_param`), et's toward the pooled covariance: the same amount of work per candidate.
scikit-learn runs its cross-validation on all cores (`n_jobs=-1`), as et does.
"""
import json
import os
import subprocess
import sys
import time

import numpy as np
from sklearn.discriminant_analysis import QuadraticDiscriminantAnalysis
from sklearn.model_selection import LeaveOneGroupOut, StratifiedKFold, cross_val_score
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

CANDIDATES = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0]


def load_npz(path):
    d = np.load(path)
    return d["x"], d["label"], d["visit"], d["untouched"]


def load_csv(path):
    # et's CSV: '#' provenance lines (the untouched frames among them), a header, then rows.
    untouched = []
    with open(path) as f:
        for line in f:
            if not line.startswith("#"):
                header = line.strip().split(",")
                break
            if line.startswith("# untouched:"):
                for frame in line.split(":", 1)[1].split(";"):
                    if frame.strip():
                        untouched.append([float(v) for v in frame.split()])
        table = np.loadtxt(f, delimiter=",")
    features = [i for i, h in enumerate(header) if h.startswith("f")]
    x = table[:, features]
    return x, table[:, header.index("label")].astype(int), table[:, header.index("visit")].astype(int), np.array(untouched)


def sklearn_train(path, auto):
    x, y, visit, untouched = (load_npz if path.endswith(".npz") else load_csv)(path)
    x = x - untouched[visit]
    groups = LeaveOneGroupOut()
    # tol: scikit-learn's rank test refuses a class whose covariance has an eigenvalue below
    # 1e-4 of the standardised scale; on the calibrated sheet a class's quiet channels vary
    # 2 % of the feature's spread over all classes (eigenvalues down to 1e-6), full rank all
    # the same. A tolerance near machine precision lets it fit what et fits.
    model = lambda r: make_pipeline(StandardScaler(), QuadraticDiscriminantAnalysis(reg_param=r, tol=1e-12))
    shrinkage = 0.0
    if auto:
        scores = [cross_val_score(model(r), x, y, groups=visit, cv=groups, n_jobs=-1).mean() for r in CANDIDATES]
        shrinkage = CANDIDATES[int(np.argmax(scores))]
    fitted = model(shrinkage).fit(x, y)
    kfold = cross_val_score(model(shrinkage), x, y, cv=StratifiedKFold(10, shuffle=True, random_state=1), n_jobs=-1).mean()
    lovo = cross_val_score(model(shrinkage), x, y, groups=visit, cv=groups, n_jobs=-1).mean()
    return fitted, shrinkage, kfold, lovo


def et_train(et, path, auto):
    args = [et, "train", "--data", path, "--folds", "10", "--out", "/tmp/et-train-bench.json", "--force", "--json"]
    if not auto:
        args += ["--shrinkage", "0"]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    s = json.loads(out)
    return s["shrinkage"], s["cv_accuracy"], s["leave_one_visit_out_accuracy"]


def best_of(repeat, f):
    times, result = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - t)
    return min(times), result


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    repeat = int(next((a.split("=")[1] for a in sys.argv if a.startswith("--repeat=")), "3"))
    et, base = args
    print(f"machine: {os.cpu_count()} cores; best of {repeat}")
    print("tool | file | shrinkage | wall s | 10-fold CV | leave-one-visit-out")
    for ext in ["npz", "csv"]:
        path = f"{base}.{ext}"
        if not os.path.exists(path):
            continue
        for auto in [False, True]:
            t, (l, cv, lovo) = best_of(repeat, lambda: et_train(et, path, auto))
            print(f"et | {ext} | {'auto: ' if auto else ''}{l} | {t:.2f} | {cv:.4f} | {lovo:.4f}", flush=True)
            t, (_, l, cv, lovo) = best_of(1 if ext == "csv" else repeat, lambda: sklearn_train(path, auto))
            print(f"scikit-learn | {ext} | {'auto: ' if auto else ''}{l} | {t:.2f} | {cv:.4f} | {lovo:.4f}", flush=True)


if __name__ == "__main__":
    main()
