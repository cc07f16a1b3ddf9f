"""The peer's first example done with et (python/examples/peer_example.py) finds its anomaly."""

import subprocess
import sys

from conftest import ROOT


def test_the_peers_example_finds_the_anomaly():
    script = ROOT / "python" / "examples" / "peer_example.py"
    done = subprocess.run(
        [sys.executable, str(script), "--check"], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "anomaly found at" in done.stdout
