"""Shared fixtures: the `et` command the module is checked against, and its outputs."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "sim" / "scenes"


def _et_binary() -> Path:
    """The `et` command: $ET_BIN, or the workspace's debug build (built when missing)."""
    if os.environ.get("ET_BIN"):
        return Path(os.environ["ET_BIN"])
    binary = ROOT / "target" / "debug" / "et"
    if not binary.exists():
        subprocess.run(["cargo", "build", "-p", "et-host", "--bin", "et"], cwd=ROOT, check=True)
    return binary


@pytest.fixture(scope="session")
def et_cli():
    """Runs `et ARGS...` and returns its stdout (parsed when it is JSON)."""
    binary = _et_binary()

    def run(*args):
        done = subprocess.run(
            [str(binary), *map(str, args)], capture_output=True, text=True, check=False
        )
        if done.returncode != 0:
            raise AssertionError(f"et {' '.join(map(str, args))}: {done.stderr}")
        out = done.stdout.strip()
        try:
            return json.loads(out.splitlines()[-1]) if out else None
        except json.JSONDecodeError:
            return out

    return run


@pytest.fixture(scope="session")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("et")


@pytest.fixture(scope="session")
def scene(work):
    """The default scene (13 cm square, 16 electrodes, adjacent), its press from 0.3 s on."""
    text = (SCENES / "square-13cm-16.toml").read_text()
    assert "start = 0.05" in text
    path = work / "square.toml"
    path.write_text(text.replace("start = 0.05", "start = 0.3"))
    return path


@pytest.fixture(scope="session")
def recording(et_cli, work, scene):
    """`et sim`'s recording of the scene: 12.8 ms frames, 23 untouched, then the press."""
    path = work / "touch.jsonl"
    et_cli("sim", "--scene", scene, "--frames", 40, "--out", path)
    return path


@pytest.fixture(scope="session")
def dataset(et_cli, work):
    """A small `et collect` dataset (.npz): 3 x 3 classes, two visits."""
    path = work / "train.npz"
    et_cli(
        "collect", "--scene", SCENES / "square-13cm-16.toml", "--grid", "3x3", "--visits", 2,
        "--scans", 3, "--subsections", 5, "--out", path,
    )
    return path
