"""Shared set-up of the Python module's tests: ctest runs them with PYTHONPATH pointing at the
build tree's package (build/python) and CADSYNTH_BUILD_DIR / CADSYNTH_SOURCE_DIR set."""

import os
import pathlib

import pytest

BUILD_DIR = pathlib.Path(os.environ.get("CADSYNTH_BUILD_DIR",
                                        pathlib.Path(__file__).resolve().parents[2] / "build"))
SOURCE_DIR = pathlib.Path(os.environ.get("CADSYNTH_SOURCE_DIR",
                                         pathlib.Path(__file__).resolve().parents[2]))
CLI = BUILD_DIR / "tools" / "cadsynth"

# Two scenes of three views each at 160 x 120, path-traced, with randomised lights, a
# structured-light depth sensor and grasp labels: a gear and a bolt, a nut and a washer.
RECIPE = """\
scenes:
  - name: gear_and_bolt
    layout: grid
    gap: 20 mm
    parts:
      - {family: spur_gear, params: {teeth: 18, module: 2, face_width: 10 mm}}
      - {family: hex_bolt, params: {size: M8, length: 30 mm}}
  - name: nut_and_washer
    layout: grid
    parts:
      - {family: hex_nut, params: {size: M12}}
      - {family: washer, params: {size: M12}}
camera:
  width: 160
  height: 120
  fx: 140
  fy: 140
  cx: 79.5
  cy: 59.5
  depth: {model: structured_light, baseline: 100 mm, noise: 0.2 mm}
sweep: {yaw: [0, 120, 240], pitch: [55], radius: [0.35 m]}
render: {mode: pbr, samples: 4, bounces: 2}
randomize:
  seed: 5
  lights:
    count: {choice: [1, 2]}
    power: {log_uniform: [20, 80]}
grasps:
  gripper: franka
  samples: 300
"""


@pytest.fixture(scope="session")
def recipe_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("recipe") / "small.yaml"
    path.write_text(RECIPE)
    return path
