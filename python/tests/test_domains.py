"""The Python module holds every value to the domain the command line's flags do (the
library checks them where the value is made), naming the value and what it must be."""

import json
import math
import re

import numpy as np
import pytest

import et_touch as et


@pytest.mark.parametrize(
    "options, named",
    [
        (dict(triangles=0), "triangles = 0: must be a whole number from 20 to 500000"),
        (dict(triangles=5_000_000), "triangles = 5000000"),
        (dict(threshold=-1.0), "threshold = -1: must be from 0 to 1"),
        (dict(threshold=2.0), "threshold = 2"),
        (dict(threshold=math.nan), "threshold = NaN"),
        (dict(iterations=0), "iterations = 0: must be a whole number from 1 to 100"),
        (dict(s=2.0), "s = 2: must be from 0 to 1"),
        (dict(pixels=2), "pixels = 2"),
        (dict(alpha="0"), "alpha = 0"),
        (dict(alpha="1e9"), "alpha = 1000000000"),
        (dict(method="greit", noise_figure=1e9), "noise figure = 1000000000"),
        (dict(method="greit", radius_m=-1.0), "radius, m = -1"),
    ],
)
def test_a_reconstruction_out_of_its_domain_is_refused_before_any_work(options, named):
    with pytest.raises(et.EtError, match=named.replace("(", r"\(")):
        et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), **options)


def test_timing_repeats_and_electrode_counts_are_checked():
    r = et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=300,
                         alpha=0.1)
    v0 = r.forward(r.sigma0)
    r.image(v0 * 1.001, v0)
    with pytest.raises(et.EtError, match="repeats = 1000000000"):
        r.frame_median(np.zeros_like(v0), 10**9)
    # A change of another length was timed as None, as an iterative method's is.
    with pytest.raises(et.EtError, match="dv: 20 values, where the protocol's frame has K = 208"):
        r.frame_median(np.zeros(20), 3)
    assert r.frame_median(np.zeros_like(v0), 3) > 0
    ex = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    meas = np.array([[2, 3, 0], [3, 0, 1], [0, 1, 2], [1, 2, 3]])
    with pytest.raises(et.EtError, match="electrodes = 4.5: electrode numbers and indices are whole"):
        et.Protocol.from_pyeit(ex, meas, electrodes=4.5)
    # A fraction among the rows is named by its place and value (it was "rows: electrode
    # numbers must be whole numbers", of no row).
    with pytest.raises(et.EtError, match=r"rows\[1, 2\] = 2.5: electrode numbers"):
        et.Protocol.from_rows([[0, 1, 2, 3], [0, 1, 2.5, 3]], 16)
    with pytest.raises(et.EtError, match=r"meas_mat\[0, 1\] = nan"):
        et.Protocol.from_pyeit(ex, np.where(meas == 3, np.nan, meas), electrodes=4)
    assert et.Protocol.from_pyeit(ex, meas, electrodes=4.0).electrodes == 4


def test_one_reconstructor_shared_by_threads_images_as_alone():
    # A call holds the native reconstruction with the GIL released; another thread's call
    # waits for it (before, it raised "Already borrowed").
    import threading

    r = et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=600)
    v0 = r.forward(r.sigma0)
    centroids = r.nodes[r.triangles].mean(axis=1)
    bump = np.hypot(centroids[:, 0] - 0.03, centroids[:, 1]) < 0.015
    v1 = r.forward(np.where(bump, 2 * r.sigma0, r.sigma0))
    r.set_reference(v0)
    alone = r.image(v1).objects
    assert alone
    errors = []

    def work():
        try:
            for _ in range(20):
                assert r.image(v1).objects == alone
                r.images(np.stack([v1, v1]))
        except Exception as e:  # noqa: BLE001 (any failure is the finding)
            errors.append(repr(e))

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


@pytest.mark.parametrize(
    "first, second",
    [(1, 2), ("1", "01"), (1.5, 2.5), (True, False), ("--1", "a"), ("x", "y"), (b"a", "é".encode())],
)
def test_labels_come_back_as_given(tmp_path, first, second):
    rng = np.random.default_rng(0)
    X = rng.standard_normal((120, 5))
    X[:60] += 2
    y = np.array([first] * 60 + [second] * 60)
    model = et.train(X, y, kind="lda")
    saved = tmp_path / "model.json"
    model.save(saved)
    for m in (model, et.Model.load(saved)):
        got = m.predict(X[[0, 119]])
        assert list(got) == [first, second]
        assert [type(v) for v in got.tolist()] == [type(first), type(second)]


def test_labels_of_two_kinds_are_refused_and_whole_numbers_beside_fractions_are_floats():
    # A list of text and numbers was made text by NumPy: 1 came back as "1".
    rng = np.random.default_rng(0)
    X = rng.standard_normal((60, 3)) + 3.0 * (np.arange(60) % 3)[:, None]
    for mixed, said in [(["a", 1, "b"], "'a' (str) and 1 (int)"), ([True, 1, 2], "True (bool)")]:
        with pytest.raises(et.EtError, match=re.escape(f"y mixes labels of two kinds, {said}")):
            et.train(X, mixed * 20, kind="lda")
    got = et.train(X, [1, 2.5, 3] * 20, kind="lda").predict(X[:3])
    assert got.tolist() == [1.0, 2.5, 3.0] and got.dtype == np.float64
    # A column of labels is read as positions of one coordinate: said with the fix.
    with pytest.raises(et.EtError, match=re.escape("a column of labels? give them as one row")):
        et.train(X, (np.arange(60) % 3)[:, None], kind="lda")


_Y = np.array([0, 1] * 20)
# Classes the features tell apart (random ones warn that the model guesses).
_X = np.random.default_rng(4).standard_normal((40, 3)) + 3.0 * _Y[:, None]


@pytest.mark.parametrize(
    "make, named",
    [
        (lambda: et.train(_X, _Y, cv=5), "cv = 5: 'shuffled' or 'blocks'; the number of folds is folds=5"),
        (lambda: et.train(_X, _Y, kind=None), "kind = None: 'auto', 'qda'"),
        (lambda: et.train(_X, _Y, grid=5), r"grid = 5: \(rows, cols\)"),
        (lambda: et.train(_X, _Y, budget_s="x"), "budget_s = 'x': a number"),
        (lambda: et.train(_X, _Y, groups=np.zeros((40, 2))), r"groups: shape \(40, 2\); give one group per row"),
        (lambda: et.train(_X, np.array([b"\xff"] * 40)), "y\\[0\\] = b'\\\\xff': bytes that are not UTF-8 text"),
        (lambda: et.protocol(5), "name = 5: 'adjacent'"),
        (lambda: et.disc("a"), "radius_m = 'a': a number"),
        (lambda: et.disc(0.1, contact_ohm=True), "contact_ohm = True: a number"),
        (lambda: et.Reconstructor(et.disc(0.1), et.protocol("adjacent"), method=None), "method = None: 'gn' or 'greit'"),
        (lambda: et.train(_X, _Y, kind="lda").export_blob(None), "precision = None: 'f16' or 'f32'"),
    ],
)
def test_a_parameter_of_the_wrong_kind_is_refused_by_its_name(make, named):
    # They raised "'int' object is not an instance of 'str'", "'int' object is not
    # subscriptable" or "could not convert string to float", naming no parameter.
    with pytest.raises(et.EtError, match=named):
        make()


def test_blocks_beside_groups_is_refused():
    rng = np.random.default_rng(1)
    X = rng.standard_normal((60, 4))
    y = np.array([0, 1] * 30)
    with pytest.raises(et.EtError, match="cv='blocks' with groups"):
        et.train(X, y, groups=[0, 1, 2] * 20, cv="blocks")


def test_a_sheet_with_a_nan_is_refused_by_the_numbers_name():
    with pytest.raises(et.EtError, match="sheet_resistance = nan"):
        et.Reconstructor(et.disc(0.1, 16, sheet_resistance=math.nan), et.protocol("adjacent", 16))
    with pytest.raises(et.EtError, match="electrodes.contact_ohm = inf"):
        et.Reconstructor(et.disc(0.1, 16, contact_ohm=math.inf), et.protocol("adjacent", 16))


def test_sheets_and_conductivities_past_single_precisions_frames_are_refused():
    # 1e-300 ohm/sq gave frames of zeros, 1e300 infinite ones, without a word.
    for r in (1e-300, 1e300):
        with pytest.raises(et.EtError, match="ohm per square is outside 1e-9 to 1e15"):
            et.disc(0.1, 16, sheet_resistance=r)
    # Past a million times the sheet resistance a contact changes nothing but round-off.
    with pytest.raises(et.EtError, match="give at most 1e6 ohm, which gives the same frames"):
        et.disc(0.1, 16, sheet_resistance=1.0, contact_ohm=1e9)
    r = et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=500)
    for sigma in (1e300, 1e-300):
        with pytest.raises(et.EtError, match="S per square: et models sheets of 1e-15 to 1e9"):
            r.forward(sigma)
    assert np.all(np.isfinite(r.forward(1e9))) and np.abs(r.forward(1e-15)).max() < 1e15
    # A reference 1e30 times a sheet's frame fitted a sheet of 3e34 ohm/sq, refused only when
    # the fitted sheet was first read.
    with pytest.raises(et.EtError, match="makes the sheet 3.000e34 ohm/sq, where sheets are"):
        r.fit_background(r.forward(r.sigma0) * 1e30)


def test_a_sheets_spec_takes_numpys_numbers_and_arrays():
    # They were "not JSON serializable"; a NaN among them is still refused by name.
    vertices = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]])
    sheet = et.Sheet({"shape": {"kind": "polygon", "vertices": vertices},
                      "sheet_resistance": np.float32(200.0), "electrodes": {"count": np.int64(8)}})
    r = et.Reconstructor(sheet, et.protocol("adjacent", 8), triangles=300)
    assert r.sheet.spec["sheet_resistance"] == 200.0 and r.sheet.electrodes == 8
    with pytest.raises(et.EtError, match="sheet_resistance = nan"):
        et.Sheet({"shape": {"kind": "disc", "radius": 0.1}, "sheet_resistance": np.float32("nan")})


@pytest.mark.parametrize(
    "field, value, said",
    [
        ("sheet_resistance", "30e3", '"30e3" is text, where a number belongs (write it without quotes)'),
        ("sheet_resistance", True, "True is a yes-or-no value, where a number belongs"),
        ("sheet_resistance", None, "an empty value (null), where a number belongs"),
        ("electrodes", 16, "16 is a whole number, where a table of fields belongs"),
        ("electrodes", {"count": 16.5}, "16.5 is a number with a fraction, where a whole number belongs"),
        ("electrodes", {"count": 16, "model": "cem"}, "unknown value `cem`: give one of `complete`"),
        ("shape", "disc", '"disc" is text, where a table of fields belongs'),
    ],
)
def test_a_sheets_spec_of_the_wrong_kind_is_said_in_pythons_words(field, value, said):
    # The parser said "invalid type: string "30e3", expected f64", "expected struct
    # ElectrodeSpec" and "expected Shape": the Rust types the spec is read into.
    spec = {"shape": {"kind": "disc", "radius": 0.1}, "electrodes": {"count": 16}, field: value}
    with pytest.raises(et.EtError) as refused:
        et.Sheet(spec)
    words = str(refused.value)
    assert said.replace("True", "true") in words and f"sheet: {field}" in words, words
    assert not any(internal in words for internal in ("f64", "struct", "enum", "Spec", "expected")), words


def test_outlines_the_mesher_cannot_mesh_are_refused_at_once():
    with pytest.raises(et.EtError, match="sliver"):
        et.Reconstructor(et.rectangle(0.2, 1e-6, 16), et.protocol("adjacent", 16))
    angles = np.linspace(0, 2 * np.pi, 1001, endpoint=False)
    many = np.column_stack([0.1 * np.cos(angles), 0.1 * np.sin(angles)])
    with pytest.raises(et.EtError, match="more than 1 000 vertices"):
        et.Reconstructor(et.polygon(many, 16), et.protocol("adjacent", 16))
    # A long strip is not a sliver.
    et.Reconstructor(et.rectangle(0.3, 0.01, 16), et.protocol("adjacent", 16), triangles=300)
    # Clockwise vertices placed and numbered the electrodes the other way round, silently.
    square = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]
    et.polygon(square, 8)
    with pytest.raises(et.EtError, match="vertices clockwise: give them counter-clockwise"):
        et.polygon(square[::-1], 8)
    # A sheet in millimetres images as one a thousand times larger, without a word.
    with pytest.raises(et.EtError, match="280.0 m across, past the 10 m .* in mm or cm"):
        et.disc(140, 16)


def test_currents_up_to_the_unit_current_of_simulated_frames():
    # pyEIT's frames are for 1 A: taken (the peer examples image them so); more is a slip of
    # units, refused by the row it is in, for built-in protocols and tables alike.
    sheet = et.disc(0.1, 16)
    et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=1.0), triangles=300)
    with pytest.raises(et.EtError, match="current 2 A is above 1 A"):
        et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=2.0), triangles=300)
    p = et.protocol("adjacent", 16)
    table = np.column_stack([p.rows, np.full(len(p.rows), 3.0)])
    with pytest.raises(et.EtError, match="above 1 A"):
        et.Reconstructor(sheet, et.Protocol.from_rows(table, 16), triangles=300)


def test_a_built_in_protocol_with_a_row_current_changed_keeps_it():
    # A named protocol was set up from its name and first current alone: a row's own
    # current was ignored without a word.
    sheet = et.disc(0.1, 16)
    p = et.protocol("adjacent", 16)
    currents = p.currents.copy()
    currents[5] *= 2.0
    changed = et.Protocol(p.electrodes, p.rows, currents, p.name)
    # A protocol is not changed once made: a row changed in place afterwards would be
    # ignored under its built-in name, so its arrays are read-only and its fields frozen.
    with pytest.raises(ValueError, match="read-only"):
        p.currents[5] = 1.0
    with pytest.raises(AttributeError):
        p.name = "opposite"
    # It is checked where it is made, as a Reconstructor would take it.
    zero = p.currents.copy()
    zero[3] = 0.0
    with pytest.raises(et.EtError, match="row 3: current 0 A"):
        et.Protocol(p.electrodes, p.rows, zero)
    r = et.Reconstructor(sheet, p, triangles=300)
    s = et.Reconstructor(sheet, changed, triangles=300)
    v, w = r.forward(r.sigma0), s.forward(s.sigma0)
    assert w[5] == pytest.approx(2.0 * v[5], rel=1e-9)
    assert np.allclose(np.delete(w, 5), np.delete(v, 5), rtol=1e-9)


@pytest.mark.parametrize(
    "make, named",
    [
        (lambda: et.disc(0.1, 2.5), "electrodes = 2.5: an even whole number from 4 to 32"),
        (lambda: et.disc(0.1, -3), "electrodes = -3: an even whole number from 4 to 32"),
        (lambda: et.disc(0.1, 2**64), "electrodes = 18446744073709551616: too large (at most 2"),
        (lambda: et.protocol("adjacent", 2**40), "electrodes = 1099511627776: an even whole number from 4 to 32"),
        # A negative count says the native side's bounds (it said "at least 0", then the
        # native side "20 to 500000").
        (
            lambda: et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=-1),
            "triangles = -1: a whole number from 20 to 500000",
        ),
        (lambda: et.protocol("adjacent", -16), "electrodes = -16: an even whole number from 4 to 32"),
        # A sheet is checked where it is made, not first where a Reconstructor uses it.
        (lambda: et.disc(-0.1), "radius = -0.1: must be a positive length"),
        (lambda: et.disc(0.1, 7), "electrodes.count: 7 must be even, 4 to 32"),
        (lambda: et.Sheet({"shape": {"kind": "disc", "radius": 0.1}, "sheet_resistance": -1.0}), "sheet_resistance"),
        (
            lambda: et.Reconstructor(et.disc(0.1, 300), et.Protocol.from_rows([[0, 1, 2, 3]], 300)),
            "electrodes.count: 300 must be even, 4 to 32",
        ),
        (lambda: et.protocol("adjacent", 16.5), "electrodes = 16.5"),
        (lambda: et.disc(0.1, 16, direction="up"), "direction 'up': 'ccw' or 'cw'"),
        (lambda: et.rectangle(0.1, 0.1, 16, model="x"), "model 'x'"),
        (lambda: et.Protocol.from_rows([[2, 3, 4, 5]], 16, base=2), "base = 2"),
        (lambda: et.Protocol.from_rows([[0, 1, 2, 3]], 16, base=-1), "base = -1"),
        (lambda: et.Protocol.from_rows([[0, 1, 2, 16]], 16), "give base=1"),
        (lambda: et.Protocol.from_rows([[0, 1, 2, -1]], 16), "electrodes are 0 to 15"),
        (lambda: et.Protocol.from_rows([[0, 1, 2, 3]], 0), "electrodes = 0: a whole number of at least 2"),
        # The arguments swapped: the number said as one ("rows: shape (1,)"); a built-in
        # protocol's current said by its name ("row 0: current 0 A").
        (lambda: et.Protocol.from_rows(16, [[0, 1, 2, 3]]), "rows = 16: a number; give the rows"),
        (lambda: et.protocol("adjacent", 16, 0.0), "current_a = 0.0: give the current driven, above 0 A"),
        (lambda: et.protocol("adjacent", 16, float("nan")), "current_a = nan"),
        (
            lambda: et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), iterations=1.5),
            "iterations = 1.5",
        ),
        (
            lambda: et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=300.7),
            "triangles = 300.7",
        ),
    ],
)
def test_counts_and_names_are_refused_where_they_are_made_not_truncated(make, named):
    # A fraction was truncated (2.5 electrodes made 2; 1.5 iterations made 1), a base of -1
    # shifted every electrode, and a direction or model was refused only later, as a JSON
    # parser's "unknown variant at line 1 column 156".
    with pytest.raises(et.EtError, match=named.replace("(", r"\(").replace(".", r"\.")):
        make()


def test_files_that_are_not_what_is_asked_are_said_so(tmp_path):
    frames = tmp_path / "frames.csv"
    frames.write_text("v0,v1\n1,2\n")
    with pytest.raises(et.EtError, match="not an et model file"):
        et.Model.load(frames)
    with pytest.raises(et.EtError, match="not an et recording"):
        et.read_recording(frames)
    with pytest.raises(et.EtError, match="k = 0: a whole number of at least 1"):
        et.read_frames(frames, 0)


@pytest.mark.parametrize(
    "options, named",
    [
        (dict(method="gn", noise_figure=0.3), "are GREIT's"),
        (dict(radius_m=0.01), "are GREIT's"),
        (dict(method="greit", s=0.2), "GREIT has no prior"),
        (dict(method="greit", iterations=3), "GREIT is one matrix"),
        (dict(method="greit", alpha=0.1, noise_figure=0.3), "under alpha='auto'"),
    ],
)
def test_one_methods_options_beside_the_other_are_refused_not_ignored(options, named):
    with pytest.raises(et.EtError, match=named):
        et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=300, **options)


@pytest.mark.parametrize("grid", [(1, 1), (0, 3), (10**6, 2)])
def test_a_grid_of_fewer_than_two_cells_or_past_its_bound_is_refused(grid):
    rng = np.random.default_rng(2)
    X = rng.standard_normal((40, 3))
    positions = rng.uniform(-0.05, 0.05, (40, 2))
    with pytest.raises(et.EtError, match=r"grid .*: a classifier tells at least two classes apart"):
        et.train(X, positions, kind="lda", grid=grid)


def test_what_a_call_cannot_use_is_refused_not_ignored():
    # v0 beside a table's model was ignored; a NaN frame was timed as None.
    rng = np.random.default_rng(3)
    labels = np.arange(60) % 3
    model = et.train(rng.standard_normal((60, 3)) + 3.0 * labels[:, None], labels, kind="lda")
    with pytest.raises(et.EtError, match="v0 is a board model's"):
        model.predict(rng.standard_normal((2, 3)), v0=np.zeros(3))
    r = et.Reconstructor(et.disc(0.1, 16), et.protocol("adjacent", 16), triangles=300)
    v0 = r.forward(r.sigma0)
    r.image(v0 * 1.001, v0)
    with pytest.raises(et.EtError, match=r"dv\[0\] = NaN"):
        r.frame_median(np.full(len(v0), np.nan), 3)
    # None as a frame is said as None (it was one NaN: "v[0] = nan"); a masked array's
    # masked values are missing, not the values under the mask (they were imaged as given).
    with pytest.raises(et.EtError, match="v = None: give an array of numbers"):
        r.image(None, v0)
    masked = np.ma.masked_array(v0 * 1.001, mask=np.arange(len(v0)) == 5)
    with pytest.raises(et.EtError, match=r"v\[5\] = nan"):
        r.image(masked, v0)
    r.image(np.ma.masked_array(v0 * 1.001), v0)


def test_training_arrays_are_checked_as_a_tables_cells_are():
    """What a table's reader refuses is refused from arrays too, by row and name: a feature
    not finite (an infinity was trained on), a missing label or group (None and NaN became
    classes of their own), complex targets, folds that are not a count (an OverflowError)."""
    rng = np.random.default_rng(5)
    x, y = rng.standard_normal((60, 4)), np.arange(60) % 3
    bad = x.copy()
    bad[19, 3] = np.inf
    with pytest.raises(et.EtError, match="row 19, feature 3: inf, where a finite number belongs"):
        et.train(bad, y, kind="lda")
    with pytest.raises(et.EtError, match=r"y\[2\] is nan: a missing label"):
        et.train(x, np.where(np.arange(60) == 2, np.nan, y.astype(float)), kind="lda")
    with pytest.raises(et.EtError, match=r"groups\[0\] is None: a missing group"):
        et.train(x, y, kind="lda", groups=[None] + [1] * 59)
    with pytest.raises(et.EtError, match="y: complex values"):
        et.train(x, rng.standard_normal((60, 2)) * (1 + 1j), kind="ridge")
    with pytest.raises(et.EtError, match="folds = -1: a whole number"):
        et.train(x, y, kind="lda", folds=-1)


def test_a_batch_whose_images_cannot_fit_in_memory_is_refused_with_the_run_that_fits():
    # A million frames of 512 x 512 pixels (2 TB of images) panicked inside NumPy's allocation
    # ("PyObject pointer is null"); the frames themselves are 32 MB.
    rows = et.protocol("adjacent", 8).rows[:4]
    r = et.Reconstructor(et.disc(0.1, 8), et.Protocol.from_rows(rows, 8), triangles=300, pixels=512)
    v0 = r.forward(r.sigma0)
    with pytest.raises(et.EtError, match=r"1048576 frames' images need .* GB .* image them in runs, r\.images\(V\[i:i \+ \d+\]\)"):
        r.images(np.broadcast_to(v0 * 1.01, (2**20, 4)), v0)


def test_positions_in_mm_where_m_are_taken_are_warned_of():
    rng = np.random.default_rng(5)
    positions = rng.uniform(-0.05, 0.05, (60, 2))
    X = np.hstack([positions, positions**2]) + rng.normal(0, 1e-3, (60, 4))
    with pytest.warns(et.EtWarning, match=r"more than any touch sheet \(10 m\): are they in mm\?"):
        et.train(X, positions * 1000, kind="ridge")


def test_labels_the_model_has_no_class_of_are_warned_of_in_evaluate():
    rng = np.random.default_rng(6)
    X = np.vstack([rng.normal(0, 1, (20, 3)), rng.normal(3, 1, (20, 3))])
    model = et.train(X, np.array(["a"] * 20 + ["b"] * 20), kind="lda")
    X = np.vstack([rng.normal(0, 1, (20, 3)), rng.normal(3, 1, (20, 3))])  # rows it has not seen
    with pytest.warns(et.EtWarning, match=r"1 label the model has no class of \(c\): 20 rows counted as missed"):
        scores = model.evaluate(X, np.array(["a"] * 20 + ["c"] * 20))
    assert scores["accuracy"] <= 0.5


def test_protocols_and_datasets_say_what_they_are_in_a_line(dataset):
    # A protocol printed its K x 4 rows and K currents (hundreds of lines), a reconstructor
    # and a dataset "<... object at 0x...>"; a name is kept as et spells it.
    assert repr(et.protocol("ADJACENT", 16)) == "Protocol('adjacent', 16 electrodes, K = 208, 0.001 A)"
    p = et.protocol("opposite", 16)
    mixed = et.Protocol(16, p.rows, np.linspace(1e-3, 2e-3, len(p.rows)))
    assert repr(mixed) == "Protocol(16 electrodes, K = 192, 192 currents from 0.001 to 0.002 A)"
    sheet = et.disc(radius_m=0.1, electrodes=16)
    r = et.Reconstructor(sheet, et.protocol("adjacent", 16), triangles=2000)
    assert repr(r) == (f"Reconstructor(gn, {len(r.triangles)} triangles, "
                       "Protocol('adjacent', 16 electrodes, K = 208, 0.001 A), 64 x 64 pixels)")
    data = et.read_dataset(dataset)
    assert repr(data) == (
        f"Dataset({len(data.y)} observations of {data.x.shape[1]} features, "
        f"{len(data.centres_m)} classes, {data.visit.max() + 1} visits; 16 electrodes, "
        f"{json.loads(data.config_json)['protocol'].lower()})"
    )
