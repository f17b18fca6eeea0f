"""A new user's first hour (docs/first_hour.md, issue 49), through the command line as a user runs
it: the template recipe with a part of their own (here a family part exported as STEP by
`cadsynth variants --export-step`, standing in for the user's file), preview against itself on
the grey camera's images, and the bad inputs of the issue each refused in one line with its
place, exit status 1 and no output folder. Also `import cadsynth` without numpy."""

import os
import pathlib
import re
import subprocess
import sys

import pytest

from conftest import CLI, SOURCE_DIR

TEMPLATE = SOURCE_DIR / "recipes" / "my_part_in_a_tote.yaml"


def run(*args, cwd=None):
    return subprocess.run([str(CLI), *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=600)


@pytest.fixture(scope="module")
def part(tmp_path_factory):
    """A stand-in for the user's STEP file: an M12 x 40 bolt written as STEP by cadsynth."""
    folder = tmp_path_factory.mktemp("part")
    (folder / "bolt.yaml").write_text(
        "parts: [{family: hex_bolt, params: {size: M12, length: 40 mm}}]\n")
    done = run("variants", folder / "bolt.yaml", "--export-step", folder / "step")
    assert done.returncode == 0, done.stderr
    steps = sorted((folder / "step").glob("*.step"))
    assert len(steps) == 1
    return steps[0]


def template_with(folder, part, **replace):
    text = TEMPLATE.read_text().replace("file: my_part.step", f"file: {part}")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    recipe = folder / "my_part_in_a_tote.yaml"
    recipe.write_text(text)
    return recipe


def test_the_template_runs_with_a_part_of_ones_own_and_previews(tmp_path, part):
    recipe = template_with(tmp_path, part, **{"count: 10 ": "count: 3 "})
    done = run("generate", recipe, "--progress", "lines")
    assert done.returncode == 0, done.stderr
    out = tmp_path / "out" / "my_part_in_a_tote"
    assert "wrote 3 frames (1 scene) of 1 object (" in done.stdout, done.stdout
    frames = sorted(out.glob("*/000000/gray/*.png"))  # grey images, in train/ (and test/)
    assert len(frames) == 3
    assert len(list(out.glob("*/000000/depth/*.png"))) == 3
    assert (out / "graspnet").is_dir() and (out / "suctionnet").is_dir()
    verify = run("verify", out)
    assert verify.returncode == 0, verify.stdout + verify.stderr
    # Preview, and preview against another dataset of grey images (the same one): no raw
    # OpenCV log line, one sheet written.
    sheet = tmp_path / "preview.jpg"
    shown = run("preview", out, "-o", sheet)
    assert shown.returncode == 0, shown.stderr
    versus = run("preview", out, "--versus", out, "-o", tmp_path / "versus.jpg")
    assert versus.returncode == 0, versus.stderr
    assert "WARN" not in versus.stderr and "global " not in versus.stderr, versus.stderr
    assert (tmp_path / "versus.jpg").stat().st_size > 1000


# The bad inputs: each refused before any simulation or rendering, in one line naming
# the recipe's line, with exit status 1 and no output folder.
BAD = {
    "a part wider than the tote": (
        {"inner: [355 mm, 265 mm], height: 150 mm": "inner: [80 mm, 15 mm], height: 50 mm",
         "corner_radius: 15 mm": "corner_radius: 5 mm"},
        r"my_part_in_a_tote\.yaml:\d+:\d+: scene 'tote': part '.*' is \d+ mm across at its "
        r"thinnest, wider than the tote's inside"),
    "more parts than the tote holds": (
        {"copies: 30\n": "copies: 5000\n"},
        r"my_part_in_a_tote\.yaml:\d+:13: scene 'tote': 5000 parts of \d+ cm3 of solid cannot fit"),
    "a sweep radius in metres without its unit": (
        {"radius: {from: 0.8 m, to: 0.95 m, step: 0.01 m}": "radius: {from: 0.8, to: 0.95}"},
        r"my_part_in_a_tote\.yaml:\d+:\d+: sweep.radius: 0.8 is read as 0.8 mm .*did you mean "
        r"'0.8 m'\?"),
    "a tote in metres without its unit": (
        {"inner: [355 mm, 265 mm]": "inner: [0.4, 0.3]"},
        r"my_part_in_a_tote\.yaml:\d+:\d+: scenes\[0\]\.container\.inner: 0.4 is read as 0.4 mm"),
    "a density in g/cm3": (
        {"density: 7850, friction": "density: 7.85, friction"},
        r"my_part_in_a_tote\.yaml:\d+:\d+: scenes\[0\]\.physics\.density: 7.85 is read as kg/m3.*"
        r"did you mean 7850"),
    "a camera inside the tote": (
        {"radius: {from: 0.8 m, to: 0.95 m, step: 0.01 m}": "radius: 100 mm"},
        r"sweep: view 0 of scene 'tote' puts the camera at .* inside the tote"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_impossible_inputs_are_refused_in_one_line(tmp_path, part, name):
    replace, message = BAD[name]
    recipe = template_with(tmp_path, part, **replace)
    done = run("generate", recipe, "--quiet")
    assert done.returncode == 1, (name, done.stdout, done.stderr)
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, done.stderr
    assert re.search(message, lines[0]), lines[0]
    assert not (tmp_path / "out").exists()


def test_import_without_numpy_names_the_interpreter():
    code = "import sys; sys.modules['numpy'] = None; import cadsynth"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ), timeout=120)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: cadsynth needs numpy, which " + sys.executable), last
