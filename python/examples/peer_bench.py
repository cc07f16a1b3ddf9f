"""et beside the Python peer (pyEIT), call for call, in one process: the table "Each frame,
call for call" in docs/python.md.

The peer's first example at three mesh sizes (a unit disc, 16 electrodes, the adjacent
protocol, a conductive anomaly of radius 0.1 at (0.5, 0.5), each side's frames made by its own
finite-element model): the set-up a user runs; one frame, pyEIT's `solve(v1, v0)` against et's
`r.image(v1)` with the reference set once (`r.set_reference(v0)`), its pixels read, and with
its objects read too; a batch of 1 000 frames, pyEIT's `solve` in a loop against et's
`r.images(V)`. et twice: its default (alpha chosen on each frame) and with the alpha that
chose fixed (one matrix for every frame, as pyEIT's lambda is). Medians of `--repeats` calls
after one warm call.

    python python/examples/peer_bench.py            # needs pyEIT (pip install pyeit)

Without pyEIT it says so and exits 0. Run it on a quiet machine, one BLAS thread
(`OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c 0` on Linux) for one core a side.
"""

import argparse
import time

import numpy as np

import et_touch as et
from peer_example import CENTRE, CONTRAST, RADIUS, peer_set_up

BATCH = 1000


def median_s(call, repeats):
    call()
    times = []
    for _ in range(repeats):
        clock = time.perf_counter()
        call()
        times.append(time.perf_counter() - clock)
    return float(np.median(times))


def batch_of(v0, v1):
    """1 000 frames: the anomaly's, each with its own 0.1 % noise of the change."""
    rng = np.random.default_rng(0)
    return v1 + 1e-3 * np.abs(v1 - v0).max() * rng.standard_normal((BATCH, len(v1)))


def peer(h0, repeats):
    mesh_obj, solver, set_up, v0, v1 = peer_set_up(h0)
    frame = median_s(lambda: solver.solve(v1, v0, normalize=True), repeats)
    frames = batch_of(v0, v1)
    clock = time.perf_counter()
    for v in frames:
        solver.solve(v, v0, normalize=True)
    batch = time.perf_counter() - clock
    return len(mesh_obj.element), set_up, frame, batch


def et_side(triangles, repeats, alpha="auto"):
    clock = time.perf_counter()
    sheet = et.disc(1.0, 16, sheet_resistance=1.0, model="point")
    r = et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=1.0), triangles=triangles,
                         alpha=alpha)
    set_up = time.perf_counter() - clock
    sigma = np.full(len(r.triangles), r.sigma0)
    centroids = r.nodes[r.triangles].mean(axis=1)
    inside = np.hypot(centroids[:, 0] - CENTRE[0], centroids[:, 1] - CENTRE[1]) < RADIUS
    v0, v1 = r.forward(sigma), r.forward(np.where(inside, CONTRAST * r.sigma0, sigma))
    r.set_reference(v0)
    frame = median_s(lambda: r.image(v1).pixels, repeats)
    with_objects = median_s(lambda: r.image(v1).objects, repeats)
    found = r.image(v1).objects[0]
    miss = np.hypot(found["x_m"] - CENTRE[0], found["y_m"] - CENTRE[1])
    frames = batch_of(v0, v1)
    r.images(frames[:2])
    clock = time.perf_counter()
    images = r.images(frames)
    batch = time.perf_counter() - clock
    assert images.pixels.shape[0] == BATCH
    return len(r.triangles), set_up, frame, with_objects, batch, miss, images.alpha[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=100, help="calls per median")
    parser.add_argument("--h0", type=float, nargs="+", default=[0.1, 0.05, 0.03],
                        help="pyEIT's mesh sizes (et meshes about as many triangles)")
    args = parser.parse_args()
    try:
        import pyeit  # noqa: F401
    except ImportError:
        print("pyEIT is not installed (pip install pyeit): nothing to compare")
        return
    print("| triangles (pyEIT / et) | set-up pyEIT / et | one frame: pyEIT `solve(v1, v0)` / "
          "et `r.image(v1)`, alpha chosen each frame (its objects read too) / alpha fixed | "
          "1 000 frames: pyEIT's loop / et `r.images(V)`, alpha chosen / fixed | et's object "
          "from the anomaly's centre |")
    print("| --- | --- | --- | --- | --- |")
    for h0 in args.h0:
        t_p, setup_p, frame_p, batch_p = peer(h0, args.repeats)
        t_e, setup_e, frame_e, objects_e, batch_e, miss, alpha = et_side(t_p, args.repeats)
        # The alpha the default chose, fixed: a matrix made once, as pyEIT's lambda is.
        fixed = et_side(t_p, args.repeats, alpha=repr(float(alpha)))
        print(f"| {t_p} / {t_e} | {setup_p * 1e3:.0f} / {setup_e * 1e3:.0f} ms | "
              f"{frame_p * 1e6:.0f} / {frame_e * 1e6:.0f} us ({objects_e * 1e6:.0f} us) / "
              f"{fixed[2] * 1e6:.0f} us | {batch_p * 1e3:.0f} / {batch_e * 1e3:.0f} / "
              f"{fixed[4] * 1e3:.0f} ms | {miss:.3f} |", flush=True)


if __name__ == "__main__":
    main()
