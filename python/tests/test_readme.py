"""The README's and docs/python.md's five lines, run as written (after the `et sim` they name)."""

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
