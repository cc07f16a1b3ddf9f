"""How `et train --kind auto` chooses, against every kind trained alone, on thirteen splits:
same-session and new-session stand-ins (milder and harsher drift, with and without
references) and scikit-learn's bundled regression sets. The table in docs/measurements.md
("Choosing with both figures in view") is this script's output.

Usage (from the repository's root, after `cargo build --release -p et-host --bin et`):

    python host/learn/benches/choice_study.py DATA_DIR [--et target/release/et] [-j 2]
        [--kinds auto,ridge,knn,kernel-ridge,mlp,gp]

DATA_DIR is made on first use: the stand-ins by `cargo run --release -p et-learn --example
standin` (seeds and drifts below) and, when scikit-learn is installed, diabetes and friedman1
shuffled by seed 0 and split 80/20 (the target as (t, 0) in m: the error is the mean absolute
error). Each split is trained through the CLI exactly as a user would (`et train --features F
--targets T --unit m --rows TRAIN --kind K`, no other flag but the split's own) and scored by
`et eval ... --rows TEST --json`. Prints one row per split: each kind's test error and auto's,
with auto's ratio to the best kind alone, and the worst ratio.
"""

import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

# name: (stand-in dir or bundled set, train rows, test rows, extra flags, what it is)
SPLITS = {
    "S3": ("s360", "0..300", "300..360", ["--folds", "3"], "3 sessions, last 60 presses"),
    "B": ("si", "0..400", "400..500", [], "same session"),
    "A": ("si", "0..2000", "2000..2500", [], "new session (electrodes moved)"),
    "S8": ("s800", "0..600", "600..800", ["--folds", "3"], "drifting, new session"),
    "C2": ("sd", "0..500", "500..1000", [], "drifting, one session to the next"),
    "C": ("sd", "0..500", "500..1000", ["ref"], "the same, ratio to the frame before"),
    "D2": ("sd", "0..2000", "2000..2500", [], "drifting, four sessions to the fifth"),
    "D": ("sd", "0..2000", "2000..2500", ["ref"], "the same, ratio to the frame before"),
    "H": ("sh", "0..500", "500..1000", [], "sessions far apart, one to the next"),
    "H2": ("sh", "0..500", "500..1000", ["ref"], "the same, ratio to the frame before"),
    "I": ("sh", "0..2000", "2000..2500", [], "sessions far apart, four to the fifth"),
    "G": ("diabetes", "0..353", "353..442", [], "scikit-learn's diabetes (MAE)"),
    "E": ("friedman1", "0..1600", "1600..2000", [], "scikit-learn's friedman1 (MAE)"),
}
# stand-in dir: example arguments (rows, sessions, seed, drift)
STANDINS = {
    "si": ["2500", "5", "1"],
    "sd": ["2500", "5", "1", "drifting"],
    "sh": ["2500", "5", "2", "drifting:0.3,1"],
    "s360": ["360", "3", "11"],
    "s800": ["800", "4", "7", "drifting"],
}


def make_data(data):
    for name, args in STANDINS.items():
        if not os.path.exists(os.path.join(data, name, "targets.csv")):
            subprocess.run(["cargo", "run", "--release", "-q", "-p", "et-learn", "--example",
                            "standin", "--", os.path.join(data, name), *args], check=True)
    for name in ("diabetes", "friedman1"):
        out = os.path.join(data, name)
        if os.path.exists(os.path.join(out, "targets.csv")):
            continue
        try:
            import numpy as np
            from sklearn.datasets import load_diabetes, make_friedman1
        except ImportError:
            print(f"(no scikit-learn: {name} skipped)", file=sys.stderr)
            continue
        x, t = (load_diabetes(return_X_y=True) if name == "diabetes"
                else make_friedman1(n_samples=2000, noise=1.0, random_state=0))
        order = np.random.default_rng(0).permutation(len(t))
        os.makedirs(out, exist_ok=True)
        np.savetxt(os.path.join(out, "features.csv"), x[order], delimiter=",")
        np.savetxt(os.path.join(out, "targets.csv"),
                   np.column_stack([t[order], np.zeros(len(t))]), delimiter=",")


def run(et, data, split, kind):
    where, train, test, extra, _ = SPLITS[split]
    d = os.path.join(data, where)
    if not os.path.exists(os.path.join(d, "targets.csv")):
        return None
    flags = [f for f in extra if f != "ref"]
    if "ref" in extra:
        files = ["--features", f"{d}/pressed.csv", "--reference-features", f"{d}/before.csv"]
    else:
        files = ["--features", f"{d}/features.csv"]
    files += ["--targets", f"{d}/targets.csv", "--unit", "m"]
    model = os.path.join(data, f"model.{split}.{kind}.json")
    subprocess.run([et, "train", *files, "--rows", train, "--kind", kind, *flags, "--out",
                    model, "--force"], check=True, capture_output=True)
    out = subprocess.run([et, "eval", "--model", model, *files, "--rows", test, "--json"],
                         check=True, capture_output=True, text=True).stdout
    chosen = json.load(open(model))["method"]
    return json.loads(out)["mean_error_mm"], chosen


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data")
    ap.add_argument("--et", default="target/release/et")
    ap.add_argument("-j", type=int, default=2)
    ap.add_argument("--kinds", default="auto,ridge,knn,kernel-ridge,mlp,gp")
    a = ap.parse_args()
    make_data(a.data)
    kinds = a.kinds.split(",")
    jobs = [(s, k) for s in SPLITS for k in kinds]
    with concurrent.futures.ThreadPoolExecutor(a.j) as pool:
        results = dict(zip(jobs, pool.map(lambda j: run(a.et, a.data, *j), jobs)))
    alone = [k for k in kinds if k != "auto"]
    print("| split | what | " + " | ".join(kinds) + " | auto / best kind |")
    print("|---|---|" + "---|" * (len(kinds) + 1))
    worst = 0.0
    for s, (_, _, _, _, what) in SPLITS.items():
        row = {k: results[(s, k)] for k in kinds}
        if any(v is None for v in row.values()):
            continue
        scale = 1e3 if s in ("G", "E") else 1.0  # bundled sets: the error in target units
        cells = [f"{row[k][0] / scale:.3g}" + (f" ({row[k][1]})" if k == "auto" else "")
                 for k in kinds]
        ratio = ""
        if "auto" in kinds and alone:
            best = min(row[k][0] for k in alone)
            r = row["auto"][0] / best
            worst = max(worst, r)
            ratio = f"{r:.2f}"
        print(f"| {s} | {what} | " + " | ".join(cells) + f" | {ratio} |")
    if worst:
        print(f"\nworst auto / best kind: {worst:.2f}")


if __name__ == "__main__":
    main()
