"""The training example (tools/python/examples/train_pose.py) closes the paper's loop."""

import json
import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

pytest.importorskip("torch")  # the example trains with it


def test_the_training_example_beats_the_mean_pose(tmp_path):
    """tools/python/examples/train_pose.py, shortened to 100 steps on 100 views: most test
    instances already lie within 10% of their diameter, none under the mean training pose."""
    report = tmp_path / "report.json"
    subprocess.run([sys.executable, str(SOURCE_DIR / "tools/python/examples/train_pose.py"),
                    "--out", str(tmp_path / "out"), "--streams", "1", "--views", "100",
                    "--steps", "100", "--report", str(report)], check=True,
                   env=dict(os.environ), stdout=subprocess.DEVNULL)
    reports = json.loads(report.read_text())
    learned = reports["pointnet"]["overall"]
    trivial = reports["baseline"]["overall"]
    assert learned["instances"] == trivial["instances"] == 180  # 36 test images x 5 objects
    assert learned["within_10pct_diameter"] > 0.8
    assert trivial["within_10pct_diameter"] < 0.1
    assert learned["mean_error_mm"] < 0.2 * trivial["mean_error_mm"]
