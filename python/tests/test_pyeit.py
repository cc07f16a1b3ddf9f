"""The Python peer's conventions taken as they come: its protocol object and arrays (pyEIT 1.2's
n_exc x n_meas x 2 `meas_mat`, and the older K x 3), and its electrodes' placement; against
pyEIT's own frames and image when it is installed."""

import warnings

import numpy as np
import pytest

import et_touch as et


def adjacent_like_pyeit(n_el=16):
    """pyEIT 1.2's `protocol.create(n_el, dist_exc=1, step_meas=1, parser_meas="std")` arrays,
    written out: excitation (i, i + 1); for each, the pairs [N, M] = [m + 1, m] not touching
    the drive electrodes, m from 0 up."""
    ex = np.array([[i, (i + 1) % n_el] for i in range(n_el)])
    meas = []
    for a, b in ex:
        pairs = [[(m + 1) % n_el, m] for m in range(n_el)
                 if len({m, (m + 1) % n_el} & {a, b}) == 0]
        meas.append(pairs)
    return ex, np.array(meas)


def test_pyeit_1_2_arrays_and_the_older_k_by_3_are_one_protocol():
    ex, meas = adjacent_like_pyeit()
    assert meas.shape == (16, 13, 2)
    p = et.Protocol.from_pyeit(ex, meas)
    assert p.electrodes == 16 and p.K == 208
    k3 = np.column_stack([meas.reshape(-1, 2), np.repeat(np.arange(16), 13)])
    q = et.Protocol.from_pyeit(ex, k3)
    np.testing.assert_array_equal(p.rows, q.rows)
    # Excitation by excitation: value k is u[N] - u[M] while (source, sink) drive.
    np.testing.assert_array_equal(p.rows[0], [0, 1, 3, 2])
    np.testing.assert_array_equal(p.rows[13], [1, 2, 4, 3])

    class PyEITProtocol:  # the fields pyEIT 1.2's object has
        ex_mat, meas_mat, n_el = ex, meas, 16

    np.testing.assert_array_equal(et.Protocol.from_pyeit(PyEITProtocol()).rows, p.rows)


def test_what_is_not_a_pyeit_protocol_is_refused():
    ex, meas = adjacent_like_pyeit()
    with pytest.raises(et.EtError, match="whole numbers"):
        et.Protocol.from_pyeit(ex + 0.5, meas)
    with pytest.raises(et.EtError, match="one block"):
        et.Protocol.from_pyeit(ex[:3], meas)
    with pytest.raises(et.EtError, match="outside"):
        et.Protocol.from_pyeit(ex, meas, electrodes=8)
    with pytest.raises(et.EtError, match="first_deg"):
        et.disc(1.0, 16, placement="pyeit", first_deg=0.0)
    with pytest.raises(et.EtError, match="placement"):
        et.disc(1.0, 16, placement="eidors")


def test_the_peers_own_frames_image_where_the_peer_images_them():
    pytest.importorskip("pyeit")
    import pyeit.eit.jac as jac
    import pyeit.eit.protocol as protocol
    import pyeit.mesh as mesh
    from pyeit.eit.fem import EITForward
    from pyeit.mesh.wrapper import PyEITAnomaly_Circle

    h0 = 0.05
    m = mesh.create(16, h0=h0)
    proto = protocol.create(16, dist_exc=1, step_meas=1, parser_meas="std")
    # Its object is the arrays written out above.
    np.testing.assert_array_equal(et.Protocol.from_pyeit(proto).rows,
                                  et.Protocol.from_pyeit(*adjacent_like_pyeit()).rows)
    anomaly = PyEITAnomaly_Circle(center=[0.5, 0.5], r=0.1, perm=1000.0)
    fwd = EITForward(m, proto)
    v0 = fwd.solve_eit()
    v1 = fwd.solve_eit(perm=mesh.set_perm(m, anomaly=anomaly, background=1.0).perm)
    solver = jac.JAC(m, proto)
    solver.setup(p=0.5, lamb=0.01, method="kotre", perm=1, jac_normalized=True)
    ds = np.real(solver.solve(v1, v0, normalize=True))
    centroids = m.node[m.element][:, :, :2].mean(axis=1)
    top = ds >= 0.5 * ds.max()
    theirs = (centroids[top] * ds[top, None]).sum(axis=0) / ds[top].sum()
    # The protocol object unchanged, the electrodes where pyEIT puts them, and its physics:
    # a unit current through a sheet of 1 ohm per square (et says when the frames are far
    # from its model's: they were 1 000 times them at 1 mA).
    found = {}
    for placement in ("pyeit", None):
        sheet = et.disc(1.0, 16, sheet_resistance=1.0, model="point", placement=placement)
        protocol = et.Protocol.from_pyeit(proto, current_a=1.0)
        with warnings.catch_warnings():
            warnings.simplefilter("error", et.EtWarning)
            r = et.Reconstructor(sheet, protocol, triangles=len(m.element))
            o = r.image(v1, v0).objects[0]
        found[placement] = (np.hypot(o["x_m"] - theirs[0], o["y_m"] - theirs[1]), o["sign"])
    assert found["pyeit"][1] == 1
    assert found["pyeit"][0] < h0, f"{found} (pyEIT's image at {theirs})"
    # et's own placement images the peer's frames elsewhere: the placement matters.
    assert found[None][0] > 0.3, found
