"""The Python peer's side of `cargo bench -p et-recon --bench peer`: pyeit 1.2.4 doing the
same work as et on a 16-electrode disc (point electrodes, adjacent drive and measurement, 208
values a frame) at each mesh size h0 given on the command line. Prints one JSON object a line:
the triangle count and each stage's seconds (median of the frame loops). Run it with one BLAS
thread (OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1) to compare one core with one core."""
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


for h0 in map(float, sys.argv[1:]):
    m, t_mesh = timed(lambda: mesh.create(16, h0=h0))
    p = protocol.create(16, dist_exc=1, step_meas=1, parser_meas="std")
    fwd = EITForward(m, p)
    v0, t_forward = timed(fwd.solve_eit)
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
