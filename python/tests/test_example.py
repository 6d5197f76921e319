"""examples/plot_trajectory.py plans a query and writes its PNG (skipped without matplotlib)."""

import json
import os
import subprocess
import sys

import pytest

from conftest import GOAL, SOURCE, START


def test_plot_example_writes_a_png(bundle_path, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "trajectory.png"
    query = {"id": "example", "start": START, "goal": {"q": GOAL, "tolerance": 0.1},
             "planner": "lazyboe", "budget": 20, "stop_at_first": True, "seed": 1}
    out = subprocess.run(
        [sys.executable, str(SOURCE / "examples" / "plot_trajectory.py"), "--bundle",
         str(bundle_path), "--out", str(png), "--query", json.dumps(query)],
        check=True, capture_output=True, text=True, env=dict(os.environ)).stdout
    assert "lazyboe: solved" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000
