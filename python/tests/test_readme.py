"""The README's and docs/python.md's Python, run as written: the five lines (after the `et sim`
they name), and docs/python.md's signatures, whose spelled-out defaults must be the defaults."""

import ast
import re
import subprocess
import sys

import pytest

from conftest import ROOT, SCENES


@pytest.mark.parametrize("document", ["README.md", "docs/python.md"])
def test_the_five_lines_print_the_press(et_cli, tmp_path, document):
    text = (ROOT / document).read_text()
    block = re.search(r"```python\n(import et_touch as et\n.*?)```", text, re.S).group(1)
    assert len(block.strip().splitlines()) == 5
    et_cli("sim", "--scene", SCENES / "square-13cm-16.toml", "--out", tmp_path / "touch.jsonl")
    (tmp_path / "sim").symlink_to(ROOT / "sim")
    done = subprocess.run(
        [sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    objects = ast.literal_eval(done.stdout)  # a list of dicts, as printed
    assert objects and objects[0]["sign"] == 1
    # The default scene's press is at (20, -15) mm.
    assert abs(objects[0]["x_m"] - 0.02) < 0.01 and abs(objects[0]["y_m"] + 0.015) < 0.01


def python_blocks(document):
    return re.findall(r"```python\n(.*?)```", (ROOT / document).read_text(), re.S)


def test_the_reconstructors_documented_signature_is_its_defaults(recording):
    """docs/python.md's `et.Reconstructor(...)` line, run as written, images as the defaults do."""
    import numpy as np

    import et_touch as et

    blocks = python_blocks("docs/python.md")
    block = next(b for b in blocks if b.startswith("r = et.Reconstructor("))
    sheet, protocol = et.scene(str(SCENES / "square-13cm-16.toml"))
    names = {"et": et, "sheet": sheet, "protocol": protocol}
    exec(block, names)
    v = et.read_recording(str(recording))["voltages"]
    spelled = names["r"].image(v[-1], v[:4])
    default = et.Reconstructor(sheet, protocol).image(v[-1], v[:4])
    assert spelled.objects and spelled.objects == default.objects
    np.testing.assert_array_equal(spelled.pixels, default.pixels)


def test_the_documented_training_calls_are_the_defaults(work, dataset, monkeypatch):
    """docs/python.md's two `et.train(...)` lines, run as written (X, y a table, train.npz an et
    dataset), train what the calls without arguments train."""
    import numpy as np

    import et_touch as et

    block = next(b for b in python_blocks("docs/python.md") if b.startswith("model = et.train("))
    data = et.read_dataset(str(dataset))
    X, y = data.x[::2, :12], data.positions_m[::2]  # small: `auto` tries every kind, twice here
    monkeypatch.chdir(dataset.parent)
    assert dataset.name == "train.npz"
    names = {"et": et, "X": X, "y": y}
    exec(block, names)
    model, board = names["model"], names["board"]
    by_default = et.train(X, y)
    assert model.kind == by_default.kind
    np.testing.assert_array_equal(model.predict(X), by_default.predict(X))
    np.testing.assert_array_equal(board.predict(data), et.train(data).predict(data))
