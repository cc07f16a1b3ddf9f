"""The Python peer's side of `cargo bench -p et-recon --bench peer`: pyeit 1.2.4 doing the
same work as et on a 16-electrode disc (point electrodes, adjacent drive and measurement, 208
values a frame) at each mesh size h0 given on the command line. Prints one JSON object a line:
the triangle count, the frame's error against the exact solution (point electrodes on the
unit disc, in closed form: the largest difference over the largest value, and the relative L2
error) and each stage's seconds (median of the frame loops). With `--accuracy` first, only
the mesh, the forward solve and the error. Run it with one BLAS thread (OMP_NUM_THREADS=1
OPENBLAS_NUM_THREADS=1) to compare one core with one core."""
import json
import statistics
import sys
import time

import numpy as np
import pyeit.eit.greit as greit
import pyeit.eit.jac as jac
import pyeit.eit.protocol as protocol
import pyeit.mesh as mesh
from pyeit.eit.fem import EITForward


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def per_call(f, n=200):
    times = []
    for _ in range(n):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def exact_frame(m, p):
    """The exact adjacent frame of point electrodes at pyeit's electrode nodes (unit disc,
    sigma = 1, 1 A): u(x) = ln(|x - sink| / |x - source|) / pi, as et's exact.rs."""
    at = m.node[m.el_pos, :2]
    u = lambda x, a, b: np.log(np.linalg.norm(x - at[b]) / np.linalg.norm(x - at[a])) / np.pi
    return np.array(
        [
            u(at[i], a, b) - u(at[j], a, b)
            for (a, b), pairs in zip(p.ex_mat, p.meas_mat)
            for i, j in pairs
        ]
    )


def errors(v, exact):
    d = v - exact
    return {
        "error_max": float(np.abs(d).max() / np.abs(exact).max()),
        "error_l2": float(np.linalg.norm(d) / np.linalg.norm(exact)),
    }


accuracy_only = sys.argv[1:2] == ["--accuracy"]
for h0 in map(float, sys.argv[2 if accuracy_only else 1 :]):
    m, t_mesh = timed(lambda: mesh.create(16, h0=h0))
    p = protocol.create(16, dist_exc=1, step_meas=1, parser_meas="std")
    fwd = EITForward(m, p)
    v0, t_forward = timed(fwd.solve_eit)
    err = errors(v0, exact_frame(m, p))
    if accuracy_only:
        print(json.dumps({"h0": h0, "triangles": int(m.element.shape[0]), **err}), flush=True)
        continue
    # A touch: the elements within 0.15 of (0.5, 0) ten times as conductive.
    c = m.elem_centers[:, :2]
    perm = np.where(np.hypot(c[:, 0] - 0.5, c[:, 1]) < 0.15, 10.0, 1.0)
    v1 = fwd.solve_eit(perm=perm)
    # One-step Gauss-Newton: the Jacobian and H = (J^T J + lamb diag(J^T J)^p)^-1 J^T.
    solver = jac.JAC(m, p)
    _, t_one_step = timed(
        lambda: solver.setup(p=0.5, lamb=0.01, method="kotre", perm=1.0, jac_normalized=False)
    )
    t_frame = per_call(lambda: solver.solve(v1, v0, normalize=False))
    # GREIT onto 64 x 64 pixels (its own Jacobian too).
    g = greit.GREIT(m, p)
    _, t_greit = timed(lambda: g.setup(p=0.5, lamb=0.01, n=64, perm=1.0, jac_normalized=False))
    t_greit_frame = per_call(lambda: g.solve(v1, v0, normalize=False))
    print(
        json.dumps(
            {
                "h0": h0,
                "triangles": int(m.element.shape[0]),
                "values": int(len(v0)),
                **err,
                "mesh": t_mesh,
                "forward": t_forward,
                "one_step_setup": t_one_step,
                "one_step_frame": t_frame,
                "greit_setup": t_greit,
                "greit_frame": t_greit_frame,
            }
        ),
        flush=True,
    )
