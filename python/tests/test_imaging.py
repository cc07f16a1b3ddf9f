"""Imaging from Python against `et reconstruct` and `et forward` on the same input, and the
finite-element model against physics it must obey."""

import warnings

import numpy as np
import pytest

import et_touch as et

TRIANGLES = 2000


def cli_image(et_cli, work, scene, recording, *extra):
    """`et reconstruct`'s image (.npy) and JSON summary of the recording's last frame."""
    npy = work / f"image{'-'.join(map(str, extra))}.npy"
    summary = et_cli(
        "reconstruct", "--scene", scene, "--frames", recording, "--triangles", TRIANGLES,
        "--reference", 20, "--image-out", npy, "--out", work / f"image{len(extra)}.png",
        "--json", "--force", *extra,
    )
    return np.load(npy), summary


def python_image(scene, recording, fit, **options):
    sheet, protocol = et.scene(scene)
    r = et.Reconstructor(sheet, protocol, triangles=TRIANGLES, **options)
    v = et.read_recording(recording)["voltages"]
    if fit:
        r.fit_background(v[:20])
    return r, r.image(v[-1], v[:20])


@pytest.mark.parametrize(
    "cli_args, options, fit",
    [
        ((), {}, True),  # measured frames: et fits the background, as et reconstruct does
        (("--background", "scene"), {}, False),
        (("--method", "greit"), {"method": "greit"}, True),
    ],
)
def test_the_image_is_et_reconstructs(et_cli, work, scene, recording, cli_args, options, fit):
    pixels, summary = cli_image(et_cli, work, scene, recording, *cli_args)
    r, image = python_image(scene, recording, fit, **options)
    assert image.pixels.shape == pixels.shape == (64, 64)
    assert np.array_equal(np.isnan(image.pixels), np.isnan(pixels))
    peak = np.nanmax(np.abs(pixels))
    assert peak > 0
    # The same code on the same frames. The two builds may sum the set-up in other orders, and
    # the frame's large factor is rounded to 16 bits: an entry within 1e-16 of a rounding tie
    # can go either way, moving a pixel by up to a step (et's contract for a frame: within
    # 1e-4 of the peak). Nearly every pixel agrees far closer than that.
    np.testing.assert_allclose(image.pixels, pixels, rtol=0, atol=1e-4 * peak, equal_nan=True)
    inside = ~np.isnan(pixels)
    assert np.mean(np.abs(image.pixels - pixels)[inside] <= 1e-6 * peak) > 0.95
    assert image.alpha == pytest.approx(summary["alpha"], rel=1e-6)
    assert len(image.objects) == len(summary["objects"]) >= 1
    pixel = summary["image"]["pixel_m"]
    for mine, theirs in zip(image.objects, summary["objects"]):
        # A pixel at the threshold or at half the peak may fall the other way: one pixel.
        for key, within in (("x_m", pixel), ("y_m", pixel), ("area_m2", pixel * pixel)):
            assert mine[key] == pytest.approx(theirs[key], rel=1e-5, abs=within), key
        assert mine["peak"] == pytest.approx(theirs["peak"], rel=1e-4)
        assert mine["sign"] == theirs["sign"]
    assert image.noise == summary["noise"]
    grid = summary["image"]
    left, right, bottom, top = image.extent
    assert (left, bottom) == pytest.approx((grid["x0_m"], grid["y0_m"]))
    assert right - left == pytest.approx(grid["cols"] * grid["pixel_m"])


@pytest.mark.parametrize("method", ["gn", "greit"])
def test_a_reference_set_once_images_each_frame_as_with_it_given(scene, recording, method):
    sheet, protocol = et.scene(scene)
    r = et.Reconstructor(sheet, protocol, triangles=TRIANGLES, method=method)
    v = et.read_recording(recording)["voltages"]
    with pytest.raises(et.EtError, match="set_reference"):
        r.image(v[-1])
    # A reference of the other sign, or all zero, is refused with what to check.
    with pytest.raises(et.EtError, match="runs against the model.*direction"):
        r.set_reference(-v[:20])
    with pytest.raises(et.EtError, match="not measured"):
        r.set_reference(np.zeros_like(v[:20]))
    r.fit_background(v[:20])
    r.set_reference(v[:20])
    for frame in (v[-1], v[-2], v[-1]):
        given = r.image(frame, v[:20])
        made = r.image(frame)
        # The pixels at once (f32 from the second frame at an alpha: within 1e-4 of the peak),
        # the rest when read, from the same reference.
        assert made.alpha == given.alpha
        peak = np.nanmax(np.abs(given.pixels))
        np.testing.assert_allclose(made.pixels, given.pixels, rtol=0, atol=1e-4 * peak,
                                   equal_nan=True)
        np.testing.assert_array_equal(made.dv, given.dv)
        # The noise the same to f32's precision (from the factors at a matrix's first frame,
        # from its squared rows in f32 after).
        assert made.objects == [pytest.approx(o, rel=1e-5) for o in given.objects]
        assert made.noise == given.noise
        np.testing.assert_array_equal(made.segment(), given.segment())
        np.testing.assert_allclose(made.noise_sd, given.noise_sd, rtol=1e-5, equal_nan=True)


def test_a_batch_is_its_frames_imaged_one_by_one(scene, recording):
    sheet, protocol = et.scene(scene)
    r = et.Reconstructor(sheet, protocol, triangles=TRIANGLES)
    v = et.read_recording(recording)["voltages"]
    r.fit_background(v[:20])
    batch = r.images(v[20:], v[:20])
    assert len(batch) == len(v) - 20
    assert batch.pixels.shape == (len(batch), 64, 64)
    for i in (0, len(batch) // 2, len(batch) - 1):
        alone = r.image(v[20 + i], v[:20])
        assert batch.alpha[i] == alone.alpha
        peak = np.nanmax(np.abs(alone.pixels))
        np.testing.assert_allclose(batch.pixels[i], alone.pixels, rtol=0, atol=1e-4 * peak,
                                   equal_nan=True)
        assert batch[i].objects == [pytest.approx(o, rel=1e-5) for o in alone.objects]
        # Every frame's objects and touches at once (over every core), as each alone.
        assert batch.objects[i] == [pytest.approx(o, rel=1e-5) for o in alone.objects]
        # (A weak touch's peak and z to the f32 pixels' precision: 1e-4 of the image's peak.)
        assert batch.touches[i] == [pytest.approx(t, rel=1e-4, abs=1e-4 * peak)
                                    for t in alone.touches]
        assert batch[i].touches == batch.touches[i]
    assert len(batch.objects) == len(batch)
    # A slice is a batch of its frames (it raised a NumPy TypeError); an index past the end,
    # or not a whole number, is said as the batch's.
    part = batch[2:5]
    assert len(part) == 3 and part.objects == batch.objects[2:5]
    assert part[-1].alpha == batch[4].alpha
    with pytest.raises(IndexError, match=f"frame {len(batch)} of a batch of {len(batch)}"):
        batch[len(batch)]
    with pytest.raises(TypeError, match="a whole number or a slice"):
        batch[1.5]
    with pytest.raises(et.EtError, match="K"):
        r.images(v[20:, :-1])
    # No untouched frame: one is needed (it said "need at least 2", though one will do).
    with pytest.raises(et.EtError, match="0 frame\\(s\\): need at least 1"):
        r.set_reference(v[:0])


def test_the_press_is_found_where_it_was(scene, recording):
    _, image = python_image(scene, recording, fit=True)
    truth = et.read_recording(recording)["touches"][-1][0]
    best = image.touches[0]
    assert best["sign"] == 1
    assert np.hypot(best["x_m"] - truth["x"], best["y_m"] - truth["y"]) < 0.01
    # The values on the mesh are what the pixels are drawn from.
    r, _ = python_image(scene, recording, fit=True)
    assert image.values.shape == (len(r.triangles),)
    assert np.nanmax(image.pixels) == pytest.approx(image.values.max(), rel=1e-6)


def test_forward_is_et_forward_on_the_same_mesh(et_cli, work, scene):
    # A scene without touches: `et forward` meshes it as the Reconstructor does.
    untouched = work / "untouched.toml"
    text = scene.read_text()
    untouched.write_text(text[: text.index("[[touch]]")])
    cli = et_cli("forward", "--scene", untouched, "--triangles", TRIANGLES, "--json")
    sheet, protocol = et.scene(untouched)
    r = et.Reconstructor(sheet, protocol, triangles=TRIANGLES)
    assert len(r.triangles) == cli["triangles"]
    v0 = r.forward(r.sigma0)
    np.testing.assert_allclose(v0, cli["v0"], rtol=1e-12)
    np.testing.assert_allclose(r.electrodes, cli["electrodes_m"], rtol=1e-12)


@pytest.fixture(scope="module")
def disc():
    sheet = et.disc(0.065, 16)
    return et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=1e-3), triangles=1200)


def test_voltages_scale_inversely_with_conductivity():
    # Point electrodes: nothing but the sheet, so V is exactly proportional to 1 / sigma (a
    # contact resistance would not scale with it).
    sheet = et.disc(0.065, 16, model="point")
    r = et.Reconstructor(sheet, et.protocol("adjacent", 16), triangles=1200)
    v = r.forward(r.sigma0)
    np.testing.assert_allclose(r.forward(2 * r.sigma0), v / 2, rtol=1e-10)


def test_reciprocity_swapping_drive_and_measure_pairs(disc):
    rows = np.array([[0, 1, 5, 6], [5, 6, 0, 1], [2, 9, 4, 12], [4, 12, 2, 9]])
    p = et.Protocol.from_rows(rows, 16, current_a=1e-3)
    r = et.Reconstructor(et.disc(0.065, 16), p, triangles=1200)
    v = r.forward(r.sigma0)
    assert v[0] == pytest.approx(v[1], rel=1e-9)
    assert v[2] == pytest.approx(v[3], rel=1e-9)


def test_the_jacobian_is_the_forward_models_derivative(disc):
    j = disc.jacobian()
    t = len(disc.triangles)
    assert j.shape == (208, t)
    sigma = np.full(t, disc.sigma0)
    rng = np.random.default_rng(7)
    direction = rng.standard_normal(t) * disc.sigma0
    h = 1e-5
    fd = (disc.forward(sigma + h * direction) - disc.forward(sigma - h * direction)) / (2 * h)
    np.testing.assert_allclose(j @ direction, fd, rtol=1e-5, atol=1e-9 * np.abs(fd).max())


def test_the_peers_protocol_convention_gives_the_same_values(disc):
    # The Python peer's adjacent protocol: ex_mat (source, sink) and meas_mat (N, M, exc):
    # value = u[N] - u[M], measurements on drive electrodes left out.
    n = 16
    ex = np.array([[i, (i + 1) % n] for i in range(n)])
    meas = [
        [(m + 1) % n, m, k]
        for k, (a, b) in enumerate(ex)
        for m in range(n)
        if len({m, (m + 1) % n} & {a, b}) == 0
    ]
    p = et.Protocol.from_pyeit(ex, np.array(meas), electrodes=n)
    assert p.K == 208
    r = et.Reconstructor(et.disc(0.065, n), p, triangles=1200)
    mine = dict(zip(map(tuple, p.rows), r.forward(r.sigma0)))
    builtin = et.protocol("adjacent", n)
    theirs = dict(zip(map(tuple, builtin.rows), disc.forward(disc.sigma0)))
    for quad, value in mine.items():
        s, k, pos, neg = quad
        same = theirs.get(quad)
        flipped = theirs.get((s, k, neg, pos))
        assert same is not None or flipped is not None, quad
        expected = same if same is not None else -flipped
        assert value == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_the_mesh_is_ready_for_tripcolor(disc):
    nodes, tris = disc.nodes, disc.triangles
    assert nodes.shape[1] == 2 and tris.shape[1] == 3
    assert tris.min() == 0 and tris.max() == len(nodes) - 1
    # Counter-clockwise: every triangle's signed area is positive.
    a, b, c = (nodes[tris[:, i]] for i in range(3))
    area = 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    assert (area > 0).all()
    assert area.sum() == pytest.approx(np.pi * 0.065**2, rel=0.01)


def test_bad_input_is_refused_with_ets_message(disc):
    v = disc.forward(disc.sigma0)
    with pytest.raises(et.EtError, match="5 values for K = 208"):
        disc.image(v[:5], v)
    bad = v.copy()
    bad[3] = np.nan
    with pytest.raises(et.EtError, match="NaN|finite"):
        disc.image(bad, v)
    with pytest.raises(et.EtError, match="protocol 'zigzag'"):
        et.protocol("zigzag", 16)
    with pytest.raises(et.EtError, match="8 electrodes"):
        et.Reconstructor(et.disc(0.065, 16), et.protocol("adjacent", 8))
    with pytest.raises(et.EtError, match="radius"):
        et.Reconstructor(et.disc(-1.0, 16), et.protocol("adjacent", 16))
    with pytest.raises(et.EtError, match="row 0: source and sink"):
        et.Reconstructor(et.disc(0.065, 16), et.Protocol.from_rows([[0, 0, 2, 3]], 16))
    with pytest.raises(et.EtError, match="alpha 'much'"):
        et.Reconstructor(et.disc(0.065, 16), et.protocol("adjacent", 16), alpha="much")


def test_frames_that_are_not_volts_are_refused_or_said(disc):
    """A reference given with the frame is checked as one set once (an all-zero or negated
    one was imaged); frames that are not voltages in single precision, or complex, are refused
    by name; untouched frames far from the model's frame of the sheet are said, until the
    background is fitted to them."""
    v0 = disc.forward(disc.sigma0)
    v = v0 * 1.001
    with pytest.raises(et.EtError, match="is 0 in every entry"):
        disc.image(v, np.zeros_like(v0))
    with pytest.raises(et.EtError, match="runs against the model"):
        disc.image(v, -v0)
    with pytest.raises(et.EtError, match="v: complex values"):
        disc.image(v * (1 + 0j), v0)
    with pytest.raises(et.EtError, match="v0: not an array of numbers"):
        disc.image(v, [list(v0), list(v0[:-1])])
    # A port's raw bytes, said by their count (NumPy's words held every byte of them).
    with pytest.raises(et.EtError, match=r"v: 1664 bytes, not numbers .*np.frombuffer") as e:
        disc.image(v.tobytes(), v0)
    assert len(str(e.value)) < 200
    # A mask is not voltages (it was imaged as frames of 0 and 1 V), as a boolean .npy is not.
    with pytest.raises(et.EtError, match=r"v holds booleans \(True, False\), not voltages"):
        disc.image(v > v0, v0)
    with pytest.raises(et.EtError, match="V holds booleans"):
        disc.images(np.vstack([v, v]) > 0, v0)
    with pytest.raises(et.EtError, match="past single precision"):
        disc.image(v * 1e300, v0 * 1e300)
    with pytest.raises(et.EtError, match="below 1.2e-38"):
        disc.image(v * 1e-300, v0 * 1e-300)
    # Frames as columns (MATLAB's way, K x n) are refused with the fix (it was "frame 0
    # (0-based, of those given): ... frame: 3 values for K = 208").
    with pytest.raises(et.EtError, match=r"V is 208 x 3: its columns are the frames, K = 208"):
        disc.images(np.vstack([v, v, v]).T, v0)
    with pytest.raises(et.EtError, match=r"v0 is 208 x 2: .* \(v0.T, 2 x 208\)"):
        disc.set_reference(np.vstack([v0, v0]).T)
    with pytest.raises(et.EtError, match=r"one row or column\? give its values: v.ravel\(\)"):
        disc.image(v[:, None], v0)
    # K frames of K values as columns (scipy.io.loadmat of MATLAB's habit): refused with the fix
    # (they were imaged as K frames each holding one channel over time); as rows, imaged.
    square = v0 * (1 + 1e-3 * np.arange(208)[:, None])
    with pytest.raises(et.EtError, match=r"V is 208 x 208 and its columns are alike"):
        disc.images(square.T, v0)
    assert len(disc.images(square, v0)) == 208
    # Magnitudes without their sign (some systems write them), under a protocol whose values
    # change sign around the sheet: refused as that (imaged, they lost the touch).
    pp = et.Reconstructor(et.disc(0.065, 16), et.protocol("pp-pp", 16), triangles=1200)
    w0 = pp.forward(pp.sigma0)
    with pytest.raises(et.EtError, match="magnitudes without their sign"):
        pp.image(np.abs(w0 * 1.001), np.abs(w0))
    # A recording's NaN (a value the board did not send), named by its place (it was "a frame
    # value is NaN or infinite", of no frame or channel).
    gap = v.copy()
    gap[7] = np.nan
    with pytest.raises(et.EtError, match=r"v\[7\] = nan: frames are finite voltages"):
        disc.image(gap, v0)
    with pytest.raises(et.EtError, match=r"v0\[7\] = nan"):
        disc.image(v, gap)
    # Among frames, one with a value missing is not imaged, as `et reconstruct --all` skips
    # it, in its place (it refused the batch): said, NaN in the stacks, None as its image and
    # its objects; the others as imaged alone.
    with pytest.warns(et.EtWarning, match=r"V: 1 of 3 frames have values missing .*frames 1\)"):
        batch = disc.images(np.vstack([v, gap, v]), v0)
    assert list(batch.imaged) == [True, False, True] and len(batch) == 3
    # Every warning is said at the caller's line, however deep the call that says it (the
    # reference's, set by images(V, v0), was said at the module's own line).
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        disc.images(np.vstack([v, gap]), v0 * 1e3)
    assert len(said) >= 2 and {w.filename for w in said} == {__file__}, [
        (w.filename, str(w.message)[:40]) for w in said]
    assert np.isnan(batch.pixels[1]).all() and np.isnan(batch.dv[1]).all()
    assert np.isnan(batch.alpha[1]) and batch[1] is None and [b is None for b in batch] == [
        False, True, False]
    assert batch.objects[1] is None and batch.touches[1] is None
    alone = disc.images(v[None, :], v0)
    np.testing.assert_array_equal(batch.pixels[2], alone.pixels[0])
    assert batch.objects[0] == batch.objects[2] == alone.objects[0]
    assert batch[2].touches == alone[0].touches and "1 not imaged" in repr(batch)
    assert batch[1:].imaged.tolist() == [False, True] and batch[1:].objects[0] is None
    # What is said of the others names them by their numbers in V, past the one skipped.
    with pytest.warns(et.EtWarning, match=r"frame 2 is 1e\+03 times the reference V_0"), \
            pytest.warns(et.EtWarning, match="values missing"):
        disc.images(np.vstack([v, gap, v * 1e3]), v0)
    # Every frame missing values: nothing to image; an infinite value is refused by place.
    with pytest.raises(et.EtError, match="every frame has values missing"):
        disc.images(np.vstack([gap, gap]), v0)
    infinite = v.copy()
    infinite[5] = np.inf
    with pytest.raises(et.EtError, match=r"V\[2, 5\] = inf"):
        disc.images(np.vstack([v, gap, infinite]), v0)
    # Its own frames are 1 times its model's: nothing said. In mV they are 1 000 times: said,
    # with the image's values 1 000 times (what the warning says), until the fit.
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        in_v = disc.image(v, v0).pixels
    v0_past = "past the 100 V an EIT instrument reads"
    with pytest.warns(et.EtWarning, match=v0_past), \
            pytest.warns(et.EtWarning, match="1e\\+03 times the model's frame"):
        in_mv = disc.image(v * 1e3, v0 * 1e3).pixels
    np.testing.assert_allclose(np.nanmax(np.abs(in_mv)), 1e3 * np.nanmax(np.abs(in_v)), rtol=0.05)
    # Fitted to frames in mV, the unit goes into the sheet resistance (1 000 times): the
    # scale is no longer said, but V_0 past 100 V is (as `et reconstruct` notes it): no
    # instrument reads that, and the background and the values are in the wrong unit.
    r = et.Reconstructor(et.disc(0.065, 16), et.protocol("adjacent", 16), triangles=1200)
    most = f"{np.abs(v0).max() * 1e3:.0f}"
    unit = f"V_0 reaches {most} V, past the 100 V an EIT instrument reads: frames in millivolts"
    with pytest.warns(et.EtWarning, match=unit):
        r.fit_background(v0 * 1e3)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always", et.EtWarning)
        r.image(v * 1e3, v0 * 1e3)
    assert [str(w.message).startswith("the reference " + unit) for w in said] == [True]
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        et.Reconstructor(et.disc(0.065, 16), et.protocol("adjacent", 16),
                         triangles=1200).fit_background(v0)
    # Frames not alike their reference (one in mV, the other in V) are said, as et
    # reconstruct says them: given with the frame, set once, or in a batch.
    with pytest.warns(et.EtWarning, match=v0_past), \
            pytest.warns(et.EtWarning, match="the frame is 0.001 times the reference V_0"):
        r.image(v, v0 * 1e3)
    with pytest.warns(et.EtWarning, match=v0_past):
        r.set_reference(v0 * 1e3)
    with pytest.warns(et.EtWarning, match="the frame is 1e\\+03 times the reference V_0"):
        r.image(v * 1e6)
    with pytest.warns(et.EtWarning, match="frame 1 is 0.001 times .* 1 of 2 frames"):
        r.images(np.vstack([v * 1e3, v]))
    # A frame of zeros against a reference of negative values: 0 times, not "-0 times".
    with pytest.warns(et.EtWarning, match="the frame is 0 times the reference V_0"):
        r.image(np.where(v0 < 0, 0.0, v0), v0)
    # A frame of the other sign: said as that, not asked for its units.
    with pytest.warns(et.EtWarning, match=r"the frame is -1 times .*the other sign: were the"):
        r.image(-v0, v0)
    # Frames of another protocol of the same K (opposite's under pseudo-polar): imaged about
    # the wrong model without a word; now said as `et reconstruct` says it, fitted or not.
    opposite = et.Reconstructor(et.disc(0.065, 16), et.protocol("opposite", 16), triangles=1200)
    u0 = opposite.forward(opposite.sigma0)
    pseudo = et.Reconstructor(et.disc(0.065, 16), et.protocol("pseudo-polar", 16), triangles=1200)
    said = r"the homogeneous model leaves \d+ % of V_0 unexplained \(past 20 %\)"
    # (Another protocol's frame is not the model's in scale either: said too.)
    with pytest.warns(et.EtWarning, match="times the model's frame"):
        with pytest.warns(et.EtWarning, match=said):
            pseudo.set_reference(u0)
    with pytest.warns(et.EtWarning, match=said):
        pseudo.fit_background(u0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        opposite.set_reference(u0)
    # Untouched frames of which some were pressed (a bump there, each frame's own noise):
    # said; noise alone is not.
    rng = np.random.default_rng(4)
    sigma = np.full(len(opposite.triangles), opposite.sigma0)
    centres = opposite.nodes[opposite.triangles].mean(axis=1)
    sigma[np.hypot(centres[:, 0] - 0.02, centres[:, 1]) < 0.01] *= 2
    pressed = opposite.forward(sigma)
    noise = 1e-4 * np.abs(u0).max()
    still = u0 + noise * rng.standard_normal((20, len(u0)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        opposite.set_reference(still)
    touched = still + np.where(np.arange(20)[:, None] < 5, pressed - u0, 0)
    with pytest.warns(et.EtWarning, match="was the sheet touched, or drifting"):
        opposite.set_reference(touched)
    # Pressed from frame 12 on: the frame is named, with the rows to take alone.
    pressed = still + np.where(np.arange(20)[:, None] >= 12, pressed - u0, 0)
    with pytest.warns(et.EtWarning, match=r"frame 12 \(from 0\) is the first to differ.*"
                      r"the reference's first 12 rows, v0\[:12\]"):
        opposite.set_reference(pressed)
    # Frames of another built-in protocol's length are said as that (it named K alone).
    with pytest.raises(et.EtError, match=r"192 values for K = 208 \(of another protocol\? 192 "
                       r"values a frame are pseudo-polar at 16 electrodes, opposite at 16"):
        disc.image(u0 * 1.001, u0)


def test_a_reconstructor_pickles_as_it_was_made(scene, recording):
    """pickle, copy.deepcopy, multiprocessing and joblib take a reconstructor (they raised
    "cannot pickle"): made again from its arguments, its background fit and reference
    replayed, it images a frame as the original does."""
    import copy
    import pickle

    sheet, protocol = et.scene(scene)
    v = et.read_recording(recording)["voltages"]
    r = et.Reconstructor(sheet, protocol, triangles=1500, pixels=24)
    r.fit_background(v[:20])
    r.set_reference(v[:20])
    made = (pickle.loads(pickle.dumps(r)), copy.deepcopy(r))
    # (Each compared call for call: a frame imaged again against a set reference takes the
    # warm single-precision operator, which differs from the first call's within its rounding.)
    expected = [r.image(v[-1]).pixels, r.image(v[-1], v[:20]).pixels]
    for again in made:
        np.testing.assert_array_equal(again.image(v[-1]).pixels, expected[0])
        np.testing.assert_array_equal(again.image(v[-1], v[:20]).pixels, expected[1])
    # An image pickles whole (a worker's sent back): its objects and noise with it.
    image = r.image(v[-1], v[:20])
    back = pickle.loads(pickle.dumps(image))
    np.testing.assert_array_equal(back.pixels, image.pixels)
    np.testing.assert_array_equal(back.noise_sd, image.noise_sd)
    assert back.objects == image.objects and back.touches == image.touches


def test_arrays_of_any_layout_are_taken(disc):
    v0 = disc.forward(disc.sigma0)
    v = v0 * 1.001
    reference = np.asfortranarray(np.vstack([v0, v0]))
    a = disc.image(v, v0).pixels
    b = disc.image(list(v), reference).pixels
    c = disc.image(v.astype(np.float32), v0[None, :]).pixels
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)


def test_set_up_lets_other_python_threads_run():
    # Set-up runs without the GIL: the main thread keeps running while another sets up.
    import threading
    import time

    done = threading.Event()
    took = []

    def set_up():
        clock = time.perf_counter()
        et.Reconstructor(et.disc(0.065, 16), et.protocol("adjacent", 16), triangles=20000)
        took.append(time.perf_counter() - clock)
        done.set()

    worker = threading.Thread(target=set_up)
    last, longest = time.perf_counter(), 0.0
    worker.start()
    while not done.is_set():
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    worker.join()
    # Held, the GIL would stall this loop for the whole set-up.
    assert longest < 0.5 * took[0], (longest, took[0])


def test_ctrl_c_ends_a_set_up_or_a_batch_at_once(scene, recording):
    import _thread
    import threading
    import time

    def interrupted_at_a_tenth(work):
        """How long `work` ran when Ctrl-C (SIGINT, as a terminal or Jupyter's interrupt
        sends it) came a tenth of the way into it, against its whole time."""
        started = time.monotonic()
        work()
        whole = time.monotonic() - started
        timer = threading.Timer(whole / 10, _thread.interrupt_main)
        timer.start()
        started = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            work()
        timer.join()
        return time.monotonic() - started, whole

    # A set-up is one long call of et's: it ran to its end with the signal pending.
    disc = et.disc(radius_m=0.1, electrodes=32)
    took, whole = interrupted_at_a_tenth(
        lambda: et.Reconstructor(disc, et.protocol("adjacent", 32), triangles=TRIANGLES,
                                 method="greit"))
    assert took < whole / 2, (took, whole)
    # A batch takes it between its runs of frames.
    sheet, protocol = et.scene(scene)
    r = et.Reconstructor(sheet, protocol, triangles=TRIANGLES)
    v = et.read_recording(recording)["voltages"]
    frames = np.tile(v[20:], (600 // len(v[20:]) + 1, 1))
    took, whole = interrupted_at_a_tenth(lambda: r.images(frames, v[:20]))
    assert took < whole / 2, (took, whole)
    # What was set up and the reconstructor interrupted still work.
    assert len(r.images(v[20:], v[:20])) == len(v) - 20


def test_a_detached_electrode_is_said_and_left_out():
    """Electrode 5's values (those it drives or measures) of the untouched frame read as a
    floating input reads (noise of 0.5 V): set_reference names it and the way to leave it
    out; Protocol.without gives the protocol and the values kept, whose reconstructor
    images the press as the sound sheet's does, and says nothing."""
    protocol = et.protocol("adjacent", 16, current_a=1e-3)
    disc = et.Reconstructor(et.disc(0.065, 16), protocol, triangles=1200)
    v0 = disc.forward(disc.sigma0)
    rows = protocol.rows
    of5 = (rows == 5).any(axis=1)
    broken = v0.copy()
    broken[of5] = np.random.default_rng(3).normal(0.0, 0.5, of5.sum())
    with pytest.warns(et.EtWarning) as said:
        disc.set_reference(broken)
    first = str(said[0].message)
    assert first.startswith("electrode 5's 52 values") and "Protocol.without([5])" in first
    without, keep = protocol.without([5])
    assert without.K == 156 and len(keep) == 156 and not (without.rows == 5).any()
    assert np.array_equal(without.rows, rows[keep]) and without.name is None
    left_out = et.Reconstructor(et.disc(0.065, 16), without, triangles=1200)
    # A press: the sound sheet's frame under a conductive bump.
    sigma = np.full(len(disc.triangles), disc.sigma0)
    centres = disc.nodes[disc.triangles].mean(axis=1)
    sigma[np.hypot(centres[:, 0] - 0.02, centres[:, 1] - 0.01) < 0.01] *= 1.5
    pressed = disc.forward(sigma)
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        left_out.set_reference(broken[keep])
        found = left_out.image(pressed[keep]).objects
        whole = disc.image(pressed, v0).objects
    at = [[o["x_m"], o["y_m"]] for o in (found[0], whole[0])]
    assert np.hypot(*np.subtract(*at)) < 3e-3, (found, whole)
    # (A name is refused by the module's error: it was NumPy's ValueError.)
    for bad, match in ([16], "not one of this protocol's 0 to 15"), (range(9), "at most half"), \
            (["a"], "electrodes: not whole numbers"):
        with pytest.raises(et.EtError, match=match):
            protocol.without(bad)
    # Opposite's rows each touch electrodes half the sheet apart: without 0 to 7, none is left.
    with pytest.raises(et.EtError, match="every one of the 192 values involves one of the 8"):
        et.protocol("opposite", 16).without(range(8))
    # Sound in the reference, off in the frames to image from the third: said as come off
    # during the recording, as `et reconstruct` says it, and not as frames of another unit
    # (the railed values moved a least-squares scale past 2 times V_0: "same units?").
    railed = v0.copy()
    railed[of5] = 3.3  # (its input at the ADC's rail)
    frames = np.vstack([pressed, pressed, railed, railed])
    with pytest.warns(et.EtWarning) as said:
        disc.images(frames, v0)
    messages = [str(w.message) for w in said]
    assert any(m.startswith("electrode 5's values stand out in 2 of the 4 frames to image, from frame 2")
               and "Protocol.without([5]) leaves them out" in m for m in messages), messages
    assert not any("same units" in m for m in messages), messages
