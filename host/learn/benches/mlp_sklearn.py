"""et's perceptron beside scikit-learn's MLPRegressor, call for call, on the same rows: the
table "The perceptron beside scikit-learn's" in docs/measurements.md.

Each side searches the same grid by 5-fold shuffled cross-validation inside the training rows
and fits the best on all of them: hidden layers 300, 50, 20; relu or tanh; L2 (alpha) 0.1 or
1; Adam at 1e-3 on batches of 200; early stopping on 10 % held out; inputs and targets
standardised. et: `et_touch.train(X, T, kind="mlp")` (the whole call a user makes);
scikit-learn: `GridSearchCV` over `StandardScaler` + `MLPRegressor(max_iter=2000,
early_stopping=True)` with its targets standardised (`TransformedTargetRegressor`).

Data sets: scikit-learn's bundled `load_diabetes` (442 x 10) and `make_friedman1` (2 000 x
10, noise 1), a shuffled 80/20 split drawn from each of three seeds (which also seed both
sides' folds and weights: a single seed's comparison is mostly which side drew the luckier
start); and, when a directory is given, the stand-in e-skin
(`cargo run --release -p et-learn --example standin -- DIR 2500`), train on rows 0..2000, test
on 2000..2500 (three seeds of the searches), its targets x, y, z in m, scored on x, y. A single target is given to et as the
position (t, 0).

Run on one core with one BLAS thread (after `maturin develop` of python/):

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c 0 \
        python host/learn/benches/mlp_sklearn.py [STANDIN_DIR]

With three targets scikit-learn is also fitted on x, y alone (its network otherwise spends
itself on z). `--candidates` instead fits each of scikit-learn's candidates alone on friedman1's seed-0 split
(three `random_state`s), beside et's `mlp_candidates` example. `--et-only` runs et's side
alone (scikit-learn's side does not change with et's commits).

Prints per data set and side (and et's candidates' cross-validated errors, as measured and
with the held-out channels drifted, in the error's unit): search + fit seconds and the test rows' mean error (absolute for
one target, the x, y distance for positions, in the targets' units; mm for the stand-in).
"""
import sys
import time

import numpy as np
import et_touch
from sklearn.compose import TransformedTargetRegressor
from sklearn.datasets import load_diabetes, make_friedman1
from sklearn.model_selection import GridSearchCV, KFold
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler


SEEDS = (0, 1, 2)


def shuffled_split(x, t, seed):
    order = np.random.default_rng(seed).permutation(len(t))
    cut = int(0.8 * len(t))
    return x[order[:cut]], t[order[:cut]], x[order[cut:]], t[order[cut:]]


def data_sets(standin):
    x, t = load_diabetes(return_X_y=True)
    for seed in SEEDS:
        yield "diabetes (442 x 10)", seed, 1.0, *shuffled_split(x, t[:, None], seed)
    x, t = make_friedman1(n_samples=2000, noise=1.0, random_state=0)
    for seed in SEEDS:
        yield "friedman1 (2 000 x 10, noise 1)", seed, 1.0, *shuffled_split(x, t[:, None], seed)
    if standin:
        load = lambda f: np.loadtxt(f"{standin}/{f}", delimiter=",", encoding="utf-8-sig", ndmin=2)
        x, t = load("features.csv"), load("targets.csv")
        for seed in SEEDS:
            yield ("stand-in skin (2 500 x 192; x, y, z)", seed, 1e3,
                   x[:2000], t[:2000], x[2000:], t[2000:])


def error(predicted, truth, unit):
    d = predicted[:, :2] - truth[:, :2] if truth.shape[1] > 1 else predicted[:, :1] - truth
    return unit * float(np.mean(np.hypot(d[:, 0], d[:, 1]) if d.shape[1] > 1 else np.abs(d[:, 0])))


def sklearn_side(x, t, seed):
    model = make_pipeline(
        StandardScaler(),
        TransformedTargetRegressor(
            MLPRegressor(hidden_layer_sizes=(300, 50, 20), max_iter=2000, early_stopping=True,
                         random_state=seed),
            transformer=StandardScaler()))
    grid = {"transformedtargetregressor__regressor__alpha": [0.1, 1.0],
            "transformedtargetregressor__regressor__activation": ["relu", "tanh"]}
    search = GridSearchCV(model, grid, cv=KFold(5, shuffle=True, random_state=seed),
                          scoring="neg_mean_squared_error")
    search.fit(x, t if t.shape[1] > 1 else t[:, 0])
    return lambda z: np.asarray(search.predict(z)).reshape(len(z), -1)


def sklearn_side_xy(x, t, seed):
    """scikit-learn fitted on x, y only (the position a user scores), where there are more."""
    predict = sklearn_side(x[:, :], t[:, :2], seed)
    return lambda z: np.c_[predict(z), np.zeros(len(z))]


SEARCHES = []


def et_side(x, t, seed):
    positions = t if t.shape[1] > 1 else np.c_[t, np.zeros_like(t)]
    model = et_touch.train(x, positions, kind="mlp", seed=seed + 1)
    SEARCHES.append([(c["hyperparameters"], c["cv_mean_error_mm"], c["cv_drifted_error_mm"])
                     for c in model.info.get("search", [])])
    return lambda z: np.asarray(model.predict(z))


def candidates():
    """Each candidate alone on friedman1's seed-0 split, `random_state` 0 to 2 (what et's
    `mlp_candidates` example does on its side), the test rows' mean absolute error."""
    x, t = make_friedman1(n_samples=2000, noise=1.0, random_state=0)
    xtr, ttr, xte, tte = shuffled_split(x, t, 0)
    mx, sx, mt, st = xtr.mean(0), xtr.std(0), ttr.mean(), ttr.std()
    for activation in ("relu", "tanh"):
        for alpha in (0.1, 1.0):
            errors = []
            for seed in range(3):
                m = MLPRegressor(hidden_layer_sizes=(300, 50, 20), alpha=alpha,
                                 activation=activation, max_iter=2000, early_stopping=True,
                                 random_state=seed).fit((xtr - mx) / sx, (ttr - mt) / st)
                p = m.predict((xte - mx) / sx) * st + mt
                errors.append(f"{np.mean(np.abs(p - tte)):.3f} ({m.n_iter_} passes)")
            print(f"{activation} alpha {alpha}: " + ", ".join(errors), flush=True)


def main():
    if "--candidates" in sys.argv:
        return candidates()
    et_only = "--et-only" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--et-only"]
    standin = args[0] if args else None
    print("| data set | seed | et mlp: search + fit | et error | scikit-learn: search + fit "
          "| scikit-learn error | scikit-learn on x, y only: search + fit | error |")
    print("|---|---|---|---|---|---|---|---|")
    totals = {}
    for name, seed, unit, xtr, ttr, xte, tte in data_sets(standin):
        row = [name, str(seed)]
        searched = None
        sides = (et_side,) if et_only else (
            (et_side, sklearn_side) + ((sklearn_side_xy,) if ttr.shape[1] > 2 else ()))
        for side in sides:
            start = time.perf_counter()
            predict = side(xtr, ttr, seed)
            seconds = time.perf_counter() - start
            e = error(predict(xte), tte, unit)
            totals.setdefault((name, side.__name__), []).append((seconds, e))
            if side is et_side:
                searched = SEARCHES[-1]
            row += [f"{seconds:.1f} s", f"{e:.3f}"]
        print("| " + " | ".join(row) + " |", flush=True)
        for h, plain, drifted in searched or []:
            said = ", ".join(f"{k}={v:g}" for k, v in h.items() if not k.startswith("hidden"))
            print(f"    et's candidate {said}: cross-validated {plain / 1e3 * unit:.3f}, "
                  f"drifted {drifted / 1e3 * unit:.3f}", flush=True)
    print("\nmeans over the seeds:")
    for (name, side), runs in totals.items():
        s, e = np.mean(runs, axis=0)
        print(f"  {name:40s} {side:13s} {s:6.1f} s  error {e:.3f}")


if __name__ == "__main__":
    main()
