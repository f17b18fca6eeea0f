"""Shared set-up of the Python module's tests: ctest runs them with PYTHONPATH pointing at the
build tree's package (build/python) and CADSYNTH_BUILD_DIR / CADSYNTH_SOURCE_DIR set."""

import ast
import importlib.util
import os
import pathlib
import re

import pytest

from cadsynth import _cadsynth

BUILD_DIR = pathlib.Path(os.environ.get("CADSYNTH_BUILD_DIR",
                                        pathlib.Path(__file__).resolve().parents[2] / "build"))
SOURCE_DIR = pathlib.Path(os.environ.get("CADSYNTH_SOURCE_DIR",
                                         pathlib.Path(__file__).resolve().parents[2]))
CLI = BUILD_DIR / "tools" / "cadsynth"
# The type stub installed beside the compiled module: its class Frame is the one list of a frame's
# keys (docs/python.md).
STUB = pathlib.Path(_cadsynth.__file__).with_name("_cadsynth.pyi")

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


def stub_frame_keys():
    """class Frame of the stub: {key: (required, annotation, numpy dtype names, shape)}, the shape
    a tuple of dims ('H', 'W', 'N', '3', ...) from the key's docstring, None for a non-array."""
    tree = ast.parse(STUB.read_text())
    body = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Frame").body
    keys = {}
    for node, doc in zip(body, body[1:] + [None]):
        if not isinstance(node, ast.AnnAssign):
            continue
        annotation, required = node.annotation, True
        if isinstance(annotation, ast.Subscript) and ast.unparse(annotation.value) == "NotRequired":
            annotation, required = annotation.slice, False
        dtypes = {n.attr for n in ast.walk(annotation)
                  if isinstance(n, ast.Attribute) and ast.unparse(n.value) == "np"}
        text = doc.value.value if isinstance(doc, ast.Expr) else ""
        shape = re.match(r"\(([^)]*)\)", text)
        if dtypes:
            assert shape, f"{node.target.id}: the docstring starts with no shape"
            shape = tuple(d.strip() for d in shape.group(1).split(",") if d.strip())
        keys[node.target.id] = (required, ast.unparse(annotation), dtypes,
                                shape if dtypes else None)
    return keys


def load_by_path(path, name):
    """The Python file at `path` as a module called `name`, loaded as a script runs it (the
    tools the C++ binary or a user starts by path are not in a package)."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
