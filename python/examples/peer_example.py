"""The Python peer's own first example, done with et: a unit disc with 16 electrodes, the
adjacent protocol, a conductive anomaly (radius 0.1 at (0.5, 0.5), 1000 times the background)
simulated by the finite-element model, imaged by one-step Gauss-Newton with the NOSER prior.
When the peer (pyEIT) is installed, its example runs beside it and both are timed.

    python python/examples/peer_example.py            # prints what it found and the times
    python python/examples/peer_example.py --plot anomaly.png   # and draws it (matplotlib)

Like the peer's example, the frames come from the same model that images them (a check of
the pipeline, not of the model: et's tests image the simulator's independent resistor network
for that).
"""

import argparse
import sys
import time

import numpy as np

import et_touch as et

CENTRE, RADIUS, CONTRAST = (0.5, 0.5), 0.1, 1000.0


def with_et(triangles):
    clock = time.perf_counter()
    # Point electrodes, as the peer's mesh puts its electrodes on nodes.
    sheet = et.disc(1.0, 16, sheet_resistance=1.0, model="point")
    r = et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=1.0), triangles=triangles)
    set_up = time.perf_counter() - clock
    sigma = np.full(len(r.triangles), r.sigma0)
    centroids = r.nodes[r.triangles].mean(axis=1)
    inside = np.hypot(centroids[:, 0] - CENTRE[0], centroids[:, 1] - CENTRE[1]) < RADIUS
    anomaly = np.where(inside, CONTRAST * r.sigma0, sigma)
    v0, v1 = r.forward(sigma), r.forward(anomaly)
    clock = time.perf_counter()
    image = r.image(v1, v0)
    first = time.perf_counter() - clock
    # Later frames as a user images a stream: the reference set once, each frame's pixels.
    r.set_reference(v0)
    r.image(v1)
    times = []
    for _ in range(100):
        clock = time.perf_counter()
        r.image(v1).pixels
        times.append(time.perf_counter() - clock)
    return r, image, set_up, first, float(np.median(times))


def peer_set_up(h0=0.05):
    """The peer's example (pyeit/examples/eit_dynamic_jac.py) up to its frames: its mesh
    (``h0``), protocol and solver, the set-up's seconds (mesh, protocol and solver, as a user
    makes them), and its model's frames v0, v1."""
    import pyeit.eit.jac as jac
    import pyeit.eit.protocol as protocol
    import pyeit.mesh as mesh
    from pyeit.eit.fem import EITForward
    from pyeit.mesh.wrapper import PyEITAnomaly_Circle

    clock = time.perf_counter()
    mesh_obj = mesh.create(16, h0=h0)
    proto = protocol.create(16, dist_exc=1, step_meas=1, parser_meas="std")
    solver = jac.JAC(mesh_obj, proto)
    solver.setup(p=0.5, lamb=0.01, method="kotre", perm=1, jac_normalized=True)
    set_up = time.perf_counter() - clock
    anomaly = PyEITAnomaly_Circle(center=list(CENTRE), r=RADIUS, perm=CONTRAST)
    mesh_new = mesh.set_perm(mesh_obj, anomaly=anomaly, background=1.0)
    fwd = EITForward(mesh_obj, proto)
    v0, v1 = fwd.solve_eit(), fwd.solve_eit(perm=mesh_new.perm)
    return mesh_obj, solver, set_up, v0, v1


def with_peer():
    """The peer's example, timed the same way."""
    mesh_obj, solver, set_up, v0, v1 = peer_set_up()
    clock = time.perf_counter()
    solver.solve(v1, v0, normalize=True)
    first = time.perf_counter() - clock
    times = []
    for _ in range(100):
        clock = time.perf_counter()
        solver.solve(v1, v0, normalize=True)
        times.append(time.perf_counter() - clock)
    return len(mesh_obj.element), set_up, first, float(np.median(times))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--triangles", type=int, default=2000, help="about how many triangles")
    parser.add_argument("--plot", help="draw the image into this PNG (needs matplotlib)")
    parser.add_argument("--check", action="store_true", help="exit 1 unless the anomaly is found")
    args = parser.parse_args()

    r, image, set_up, first, median = with_et(args.triangles)
    found = image.objects[0] if image.objects else None
    matrix = image.timings_s.get("matrix") or 0.0
    print(f"et: {len(r.triangles)} triangles, set-up {set_up * 1e3:.1f} ms; first frame "
          f"{first * 1e3:.1f} ms (alpha by GCV and its matrix {matrix * 1e3:.1f} ms), then "
          f"{median * 1e6:.0f} us a frame (median of 100)")
    if found:
        error = np.hypot(found["x_m"] - CENTRE[0], found["y_m"] - CENTRE[1])
        print(f"et: anomaly found at ({found['x_m']:.3f}, {found['y_m']:.3f}), {error:.3f} from "
              f"its centre, sign {found['sign']:+d}, {len(image.objects)} object(s)")
    else:
        print("et: no anomaly found")
    try:
        elements, p_set_up, p_first, p_median = with_peer()
        print(f"peer: {elements} triangles, set-up {p_set_up * 1e3:.1f} ms; first frame "
              f"{p_first * 1e3:.1f} ms, then {p_median * 1e6:.0f} us a frame (median of 100)")
    except ImportError:
        print("peer: pyEIT is not installed (pip install pyeit to time it beside et)")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 5))
        top = np.abs(image.values).max()
        shown = ax.tripcolor(r.nodes[:, 0], r.nodes[:, 1], r.triangles, image.values,
                             cmap="RdBu_r", vmin=-top, vmax=top)
        ax.add_patch(plt.Circle(CENTRE, RADIUS, fill=False, color="k"))
        ax.set_aspect("equal")
        ax.set_title("et, one-step Gauss-Newton: $\\Delta\\sigma / \\sigma_0$")
        fig.colorbar(shown)
        fig.savefig(args.plot, dpi=100)
        print(f"wrote {args.plot}")
    if args.check:
        ok = found is not None and found["sign"] == 1 and np.hypot(
            found["x_m"] - CENTRE[0], found["y_m"] - CENTRE[1]) < RADIUS
        sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
