"""Learning from Python against `et train`, `et eval` and `et export` on the same input."""

import copy
import csv
import json
import pickle
import re
import warnings

import numpy as np
import pytest

import et_touch as et


def without_times(d):
    """A summary without the run's own timings (they differ between any two runs)."""
    return {k: v for k, v in d.items() if not k.endswith("_seconds")}


def test_a_board_model_is_et_trains(et_cli, work, dataset):
    cli_model = work / "cli-model.json"
    trained = et_cli("train", "--data", dataset, "--out", cli_model, "--json", "--force")
    model = et.train(et.read_dataset(dataset))
    assert model.is_board and model.kind == "qda"
    assert model.info["shrinkage"] == trained["shrinkage"]
    # Its repr says its size, not its tables.
    info = model.info
    size = f"{len(info['classes'])} classes, {len(info['feature_index'])} features"
    assert repr(model) == f"et_touch.Model(qda, board, {size})"
    # Its cross-validation's scores, as `et train --json` says them (its file keeps none).
    said = {k: v for k, v in trained.items() if k not in ("out", "learning_curve")}
    assert model.scores == said
    assert 0.5 < said["cv_accuracy"] <= 1 and said["leave_one_visit_out_accuracy"] is not None
    assert et.Model.load(cli_model).scores is None
    # The same model file, number for number.
    mine = work / "py-model.json"
    model.save(mine)
    assert json.loads(mine.read_text()) == json.loads(cli_model.read_text())
    # Scored as et eval scores it.
    # (Its training observations: both say so.)
    cli_eval = et_cli("eval", "--model", cli_model, "--data", dataset, "--json")
    assert "trained_note" in cli_eval
    with pytest.warns(et.EtWarning, match="those the model was trained on"):
        assert model.evaluate(dataset) == cli_eval
    # The board's blob, byte for byte.
    for precision in ("f16", "f32"):
        blob = work / f"cli-{precision}.etm"
        et_cli("export", "--model", cli_model, "--precision", precision, "--out", blob, "--force")
        assert model.export_blob(precision) == blob.read_bytes()


def test_a_board_model_no_better_than_guessing_is_said_so(work, dataset):
    # The dataset's frames know their classes: trained without a word.
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        et.train(dataset)
    # The same frames dealt to other rows of their visit (labels that do not belong to them,
    # as a sheet pressed other than labelled gives): `et train` notes it, and so does Python.
    with np.load(dataset) as z:
        arrays = {k: z[k] for k in z.files}
    rng = np.random.default_rng(3)
    for v in np.unique(arrays["visit"]):
        rows = np.flatnonzero(arrays["visit"] == v)
        arrays["x"][rows] = arrays["x"][rng.permutation(rows)]
    dealt = work / "dealt.npz"
    np.savez(dealt, **arrays)
    with pytest.warns(et.EtWarning, match="no better than always guessing the commonest class"):
        et.train(dealt)


def test_a_board_model_predicts_frames_minus_the_untouched_frame(dataset):
    data = et.read_dataset(dataset)
    model = et.train(data, kind="lda")
    assert model.kind == "lda"
    by_dataset = model.predict(data)
    assert by_dataset.shape == (len(data.y),)
    # Tested on its own training observations: said (the training's accuracy as the model's).
    with pytest.warns(et.EtWarning, match="hold about 100 % of those the model was trained on"):
        assert model.evaluate(data)["accuracy"] > 0.8
    assert (by_dataset == data.y).mean() > 0.8
    # One visit's frames minus its untouched frame, as the board classifies them.
    visit = data.visit == 0
    config = json.loads(data.config_json)
    k = et.protocol(config["protocol"].lower(), config["electrodes"]).K
    frames = np.full((int(visit.sum()), k), np.nan)
    frames[:, data.feature_index] = data.x[visit]
    v0 = np.zeros(k)
    v0[data.feature_index] = data.untouched[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(model.predict(frames, v0=v0), by_dataset[visit])
        # One pressed frame's changes, smaller than the training's on average, are no unit's
        # (it was said to be "1/13 of" them).
        model.predict(frames[:1], v0=v0)
    # Frames in mV where V was trained were classified without a word, and wrongly.
    with pytest.warns(et.EtWarning, match="times those the model was trained on") as said:
        model.predict(frames * 1000, v0=v0 * 1000)
    assert said[0].filename == __file__
    # A dataset in mV likewise (rewritten with numpy, as a user converting their own would).
    with np.load(dataset) as raw:
        arrays = {name: raw[name] for name in raw.files}
    arrays["x"], arrays["untouched"] = arrays["x"] * 1000, arrays["untouched"] * 1000
    in_mv = dataset.parent / "train-mV.npz"
    np.savez(in_mv, **arrays)
    with pytest.warns(et.EtWarning, match="1000 times those the model was trained on"):
        model.evaluate(et.read_dataset(in_mv))
    # A value it reads that is NaN was the last class; a dataset's own untouched frames,
    # classes and visits were used beside a v0, y or groups given, without a word.
    broken = frames[:1].copy()
    broken[0, data.feature_index[0]] = np.nan
    with pytest.raises(et.EtError, match=f"frame 0, value {data.feature_index[0]}: NaN"):
        model.predict(broken, v0=v0)
    with pytest.raises(et.EtError, match="predict\\(dataset\\) without v0"):
        model.predict(data, v0=v0)
    with pytest.raises(et.EtError, match="evaluate\\(dataset\\) without y"):
        model.evaluate(data, data.y)
    with pytest.raises(et.EtError, match="evaluate\\(dataset\\) without groups"):
        model.evaluate(data, groups=data.visit)
    positions = model.predict_positions(data)
    np.testing.assert_allclose(positions, data.centres_m[by_dataset], atol=1e-12)
    with pytest.raises(et.EtError, match="untouched frame"):
        model.predict(frames)
    # Frames of another length are another protocol's, though the values the model reads
    # fall inside them (they were classified).
    with pytest.raises(et.EtError, match=f"the model takes frames of K = {k} values"):
        model.predict(frames[:, :-1], v0=v0[:-1])
    # A dataset's features given for frames: said as that (it was "frames of 96 values and an
    # untouched frame of 0").
    with pytest.raises(et.EtError, match=r"without an untouched frame: .* the features the model reads"):
        model.predict(data.x[:3])
    # One fold tests on nothing (the command line refused it; Python trained with it).
    with pytest.raises(et.EtError, match="folds = 1: a cross-validation takes 2 to 1000 folds"):
        et.train(data, kind="lda", folds=1)


def write_table(path, X, header):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(X.tolist())


@pytest.fixture(scope="module")
def table(work, dataset):
    """The dataset as any sensor's table: features.csv and targets.csv (positions in m)."""
    data = et.read_dataset(dataset)
    features, targets = work / "features.csv", work / "targets.csv"
    write_table(features, data.x, [f"f{i}" for i in range(data.x.shape[1])])
    write_table(targets, data.positions_m, ["x", "y"])
    return data, features, targets


class Frame:
    """What et reads of a pandas DataFrame: its columns' names and its values."""

    def __init__(self, columns, values):
        self.columns, self._values = columns, values

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self._values, dtype=dtype)


def test_a_frames_columns_of_row_numbers_times_and_sessions_are_refused(table):
    """As `et train --features` leaves them out: a DataFrame's `id`, `time_s` or `session`
    column was trained on as a measurement. A DataFrame's columns are read by their names."""
    data, _, _ = table
    channels = [f"ch{i}" for i in range(data.x.shape[1])]
    model = et.train(Frame(channels, data.x), data.positions_m, kind="ridge")
    assert model.kind == "ridge"
    rows = np.arange(len(data.x), dtype=float)[:, None]
    for name in ("id", "time_s", "session"):
        with pytest.raises(et.EtError, match=f"X's columns '{name}' hold the rows' numbers"):
            et.train(Frame([name] + channels, np.hstack([rows, data.x])), data.positions_m)
    # Its columns are read by name: the same columns in another order predict as the
    # training's order does (they were taken by position, without a word).
    order = list(reversed(range(len(channels))))
    turned = Frame([channels[j] for j in order], data.x[:, order])
    np.testing.assert_array_equal(model.predict(turned), model.predict(data.x))
    scores = []
    for X in (turned, data.x):
        with pytest.warns(et.EtWarning, match="rows the model was trained on"):
            scores.append(without_times(model.evaluate(X, data.positions_m)))
    assert scores[0] == scores[1]
    with pytest.raises(et.EtError, match="X lacks 'ch0'; X has, the model never saw 'g0'"):
        model.predict(Frame(["g0"] + channels[1:], data.x))
    with pytest.raises(et.EtError, match="X's column 'ch1' twice"):
        et.train(Frame(["ch1"] + channels[1:], data.x), data.positions_m)


def test_models_pickle_and_copy_as_their_files(table, dataset):
    """pickle, copy.deepcopy, multiprocessing and joblib take a model and a dataset (they
    raised "cannot pickle 'et_touch._native.Model' object"): as their files, checked when
    made again."""
    data, _, _ = table
    names = np.array(["left", "right"])[(data.positions_m[:, 0] > 0).astype(int)]
    for model, X in [
        (et.train(data.x, data.positions_m, kind="ridge"), data.x),
        (et.train(data.x, names, kind="lda"), data.x),
        (et.train(data, kind="qda"), data),
    ]:
        for again in (pickle.loads(pickle.dumps(model)), copy.deepcopy(model)):
            assert again.kind == model.kind and again.info == model.info
            # (A board model's training scores, which its file keeps not, go with it.)
            assert model.scores is not None and again.scores == model.scores
            np.testing.assert_array_equal(again.predict(X), model.predict(X))
    damaged = pickle.dumps(model).replace(b'"qda"', b'"qdx"')
    with pytest.raises(et.EtError, match="the pickled model: kind: unknown value `qdx`"):
        pickle.loads(damaged)
    # A dataset likewise, as the .npz et collect writes.
    for again in (pickle.loads(pickle.dumps(data)), copy.deepcopy(data)):
        for name in ("x", "y", "positions_m", "centres_m", "visit", "feature_index", "untouched"):
            np.testing.assert_array_equal(getattr(again, name), getattr(data, name), err_msg=name)
        assert again.config_json == data.config_json


@pytest.mark.parametrize("kind", ["ridge", "knn"])
def test_a_regressor_predicts_as_et_eval_does(et_cli, work, table, kind):
    data, features, targets = table
    cli_model = work / f"cli-{kind}.json"
    common = ("--features", features, "--targets", targets, "--unit", "m")
    et_cli("train", *common, "--kind", kind, "--out", cli_model, "--json", "--force")
    predictions = work / f"predictions-{kind}.csv"
    cli_eval = et_cli(
        "eval", "--model", cli_model, *common, "--predictions", predictions, "--json", "--force"
    )
    model = et.train(data.x, data.positions_m, kind=kind)
    assert model.kind == kind
    assert model.info["hyperparameters"] == json.loads(cli_model.read_text())["hyperparameters"]
    # The chosen candidate's scores, as `et train --json` says them, here and from its file.
    scores = model.scores
    assert scores["cv_mean_error_mm"] in [c["cv_mean_error_mm"] for c in scores["candidates"]]
    assert scores == et.Model.load(cli_model).scores
    predicted = model.predict(data.x)
    written = np.loadtxt(predictions, delimiter=",", skiprows=1)
    np.testing.assert_allclose(predicted * 1e3, written[:, 1:3], atol=1e-4)
    # (Its training rows: both say so.)
    with pytest.warns(et.EtWarning, match="rows the model was trained on"):
        mine = model.evaluate(data.x, data.positions_m)
    assert "trained_note" in cli_eval
    assert without_times(mine) == pytest.approx(without_times(cli_eval))
    assert mine["mean_error_mm"] < mine["mean_predictor_error_mm"]
    # A model file et wrote predicts the same from Python.
    np.testing.assert_allclose(et.Model.load(cli_model).predict(data.x), predicted, atol=1e-12)


def test_a_classifier_returns_the_labels_it_was_given(table):
    data, _, _ = table
    names = np.array(["cell-%d" % c for c in data.y])
    model = et.train(data.x, names, kind="lda", groups=data.visit)
    assert set(model.predict(data.x[:20])) <= set(names)
    with pytest.warns(et.EtWarning, match="rows the model was trained on"):
        assert model.evaluate(data.x, names)["accuracy"] > 0.8
    by_number = et.train(data.x, data.y, kind="lda")
    assert by_number.predict(data.x[:5]).dtype.kind == "i"


def test_bad_training_input_is_refused(table):
    data, _, _ = table
    with pytest.raises(et.EtError, match="positions"):
        et.train(data.x, data.positions_m[:10])
    with pytest.raises(et.EtError, match="kind 'forest'"):
        et.train(data.x, data.positions_m, kind="forest")
    with pytest.raises(et.EtError, match="board"):
        et.train(data, kind="ridge")
    # The arrays' options are refused on a dataset, not ignored.
    for given in ({"groups": data.visit}, {"cv": "blocks"}, {"grid": (2, 2)}):
        with pytest.raises(et.EtError, match=f"{next(iter(given))}: for arrays"):
            et.train(data, **given)
    # A dataset's training estimates its time as an array's does, and keeps to the budget.
    # (Both were "under a second": the estimate and the budget said in figures.)
    with pytest.raises(et.EtError, match=r"would take about [0-9.]+ s, past the budget of 1\.0e-9 s"):
        et.train(data, budget_s=1e-9)
    # No limit is infinity (it was refused as "not above 0"); NaN limits nothing and is refused.
    assert et.train(data, budget_s=float("inf")).is_board
    with pytest.raises(et.EtError, match="budget_s = NaN: a number of seconds above 0"):
        et.train(data, budget_s=float("nan"))
    said = []
    et.train(data, progress=lambda what, done, total: said.append(what))
    first = [w for w in said if w.startswith("training: ") or w == "each fold's statistics"]
    assert first[0].startswith("training: "), said
    with pytest.raises(et.EtError, match="only a board model"):
        et.train(data.x, data.positions_m, kind="ridge").export_blob()


def test_what_training_finds_or_changes_is_a_warning():
    # A dead channel was said in Model.info["note"] alone (et train prints it); one group
    # only, which et train notes, was silent.
    rng = np.random.default_rng(0)
    x = rng.normal(size=(120, 4))
    x[:, 3] = 5.0
    y = (x[:, 0] > 0).astype(int)
    with pytest.warns(et.EtWarning, match="feature f3 is 5 in every row"):
        model = et.train(x, y, kind="lda")
    assert "f3 is 5" in model.info["note"]
    with pytest.warns(et.EtWarning, match="one group \\('a'\\) only"):
        et.train(x[:, :3], y, kind="lda", groups=["a"] * len(y))
    with warnings.catch_warnings():
        warnings.simplefilter("error", et.EtWarning)
        et.train(x[:, :3], y, kind="lda", groups=["a", "b"] * (len(y) // 2))


def test_training_tells_its_progress_and_estimate(table):
    """`progress` is called at each step, as `et train` shows it: the Gaussian process says
    its estimated time before its work (Python said nothing before a long training)."""
    data, _, _ = table
    calls = []
    et.train(data.x, data.positions_m, kind="gp", progress=lambda *a: calls.append(a))
    assert calls and all(0 <= done <= total or total == 0 for _, done, total in calls)
    assert re.search(r"cross-validating gp .*about [0-9.]+ (s|min)\)", calls[0][0]), calls[0]
    steps = []
    et.train(data, progress=lambda what, done, total: steps.append(what))
    assert any("choosing the shrinkage" in s for s in steps), steps

    def fails(*_):
        raise KeyError("from the callable")

    # Its exception is raised, not lost; something not callable is refused by name.
    with pytest.raises(KeyError, match="from the callable"):
        et.train(data.x, data.positions_m, kind="ridge", progress=fails)
    with pytest.raises(et.EtError, match="progress: a callable"):
        et.train(data.x, data.positions_m, kind="ridge", progress="yes")


def test_a_save_that_fails_leaves_what_was_there_and_no_partial_file(tmp_path):
    resource = pytest.importorskip("resource")
    import signal

    rng = np.random.default_rng(3)
    X = np.vstack([rng.normal(0, 1, (20, 3)), rng.normal(3, 1, (20, 3))])
    y = np.array(["a"] * 20 + ["b"] * 20)
    model = et.train(X, y, kind="lda")
    # Over a file: replaced whole.
    path = tmp_path / "m.json"
    path.write_text("old")
    model.save(path)
    assert et.Model.load(path).kind == "lda"
    saved = path.read_bytes()
    # A write that fails part way (files limited to 100 bytes, as a full disk stops one):
    # refused, the file that was there kept, nothing beside it (it was written in place, so
    # the old model was lost and part of the new one left).
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    was = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    try:
        resource.setrlimit(resource.RLIMIT_FSIZE, (100, hard))
        with pytest.raises(et.EtError, match="m.json"):
            model.save(path)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, was)
    assert path.read_bytes() == saved
    assert [p.name for p in tmp_path.iterdir()] == ["m.json"]
    # Onto a folder of files: refused, the folder as it was.
    folder = tmp_path / "f.json"
    folder.mkdir()
    (folder / "keep").write_text("keep")
    # (Said as the CLI says it: "Is a directory (os error 21)" was all it said.)
    with pytest.raises(et.EtError, match="f.json is a folder, not a regular file"):
        model.save(folder)
    assert (folder / "keep").read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.json", "m.json"]
    # Into a folder that is not there: said so (the file aside's name and the system's "No
    # such file or directory (os error 2)" were).
    with pytest.raises(et.EtError, match="the folder .*none does not exist"):
        model.save(tmp_path / "none" / "m.json")


@pytest.mark.parametrize("progress", [None, lambda what, done, total: None])
def test_ctrl_c_ends_a_training_at_its_next_step(progress):
    import _thread
    import threading
    import time

    rng = np.random.default_rng(0)
    positions = rng.uniform(-0.05, 0.05, (200, 2))
    X = np.hstack([positions, positions**2, rng.normal(0, 1, (200, 12))])
    started = time.monotonic()
    et.train(X, positions, kind="mlp", progress=progress)
    whole = time.monotonic() - started
    # Ctrl-C (SIGINT, as a terminal or Jupyter's interrupt sends it) a tenth of the way in:
    # raised at the training's next step (the training ran on to its end with the signal
    # pending, and only then raised it).
    timer = threading.Timer(whole / 10, _thread.interrupt_main)
    timer.start()
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        et.train(X, positions, kind="mlp", progress=progress)
    timer.join()
    assert time.monotonic() - started < whole / 2


def test_features_in_another_unit_than_the_trainings_are_warned_of():
    rng = np.random.default_rng(0)
    positions = rng.uniform(-0.05, 0.05, (200, 2))
    X = np.hstack([positions, positions**2, rng.normal(0, 0.01, (200, 4))]) + 0.3
    model = et.train(X[:150], positions[:150], kind="ridge")
    X, positions = X[150:], positions[150:]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.predict(X)
        model.evaluate(X, positions)
    # In mV where V was trained: predicted wrongly without a word.
    with pytest.warns(et.EtWarning, match="1000 times those the model was trained on") as said:
        model.predict(X * 1000)
    assert said[0].filename == __file__, "said at the caller's line"
    with pytest.warns(et.EtWarning, match="1/1000 of those"):
        model.evaluate(X / 1000, positions)


def test_evaluating_on_the_training_rows_is_warned_of():
    rng = np.random.default_rng(1)
    positions = rng.uniform(-0.05, 0.05, (300, 2))
    X = np.hstack([positions, positions**2, rng.normal(0, 0.01, (300, 4))]) + 0.3
    model = et.train(X[:200], positions[:200], kind="ridge")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.evaluate(X[200:], positions[200:])
    # The training's own rows scored the training's error as the model's without a word.
    with pytest.warns(et.EtWarning, match="about 100 % of these rows are rows the model was "
                                          "trained on") as said:
        scores = model.evaluate(X[:200], positions[:200])
    assert said[0].filename == __file__ and "trained_note" in scores
    # Positions in mm where the library takes m: scored errors of metres without a word.
    with pytest.warns(et.EtWarning, match="more than any touch sheet .* are they in mm"):
        scores = model.evaluate(X[200:], positions[200:] * 1000)
    assert "unit_note" in scores


def test_slips_of_shape_are_refused_with_the_fix():
    """One observation given alone, or observations as columns, are refused with the fix (they
    were "X: 1-D array of shape (4,); expected 2-D" and "the data has 200 feature columns, the
    model reads 4")."""
    rng = np.random.default_rng(3)
    positions = rng.uniform(-0.05, 0.05, (200, 2))
    X = np.hstack([positions, positions**2]) + rng.normal(0, 1e-3, (200, 4))
    model = et.train(X, positions, kind="ridge")
    with pytest.raises(et.EtError, match=r"one row\? give it as one: \[X\] or X.reshape\(1, -1\)"):
        model.predict(X[0])
    with pytest.raises(et.EtError, match=r"as many rows: are its columns the observations\? give it "
                                         r"transposed, X.T"):
        model.predict(X.T)
    assert model.predict(X[:1]).shape == (1, 2)


def test_training_errors_name_pythons_parameters():
    """The library's messages name the Python parameter beside the command line's flag (they
    said "--grid 7x7" and "fewer --folds" to a Python caller, who has neither)."""
    rng = np.random.default_rng(0)
    X, positions = rng.normal(size=(100, 4)), rng.uniform(-0.05, 0.05, (100, 2))
    labels = (positions[:, 0] > 0).astype(int)
    with pytest.raises(et.EtError, match=r"grid \(--grid, grid=\) makes classes"):
        et.train(X, labels, kind="lda", grid=(2, 2))
    with pytest.raises(et.EtError, match=r"grid=\(7, 7\)"):
        et.train(X, positions, kind="qda")
    with pytest.raises(et.EtError, match=r"fewer folds \(--folds, folds=\)"):
        et.train(X, np.r_[np.zeros(99, int), 1], kind="lda")
