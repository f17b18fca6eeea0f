"""Tests of tools/bench/equal_error.py's bookkeeping, which decides what a benchmark figure
means: the time to an error read off a curve, which earlier references a run may take
(--references-from) and the table of several scenes (--combine). No renderer runs: where one
would be started, the test gives a program that fails, so taking a reference that should not be
taken, or not taking one that should, shows as an exit."""

import json
import math
import pathlib
import sys

import pytest
from conftest import load_by_path

pytest.importorskip("yaml")

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "tools" / "bench" / "equal_error.py"


ee = load_by_path(SCRIPT, "equal_error_under_test")


def test_time_to_interpolates_log_log_between_the_bracketing_points():
    # (1 s, 0.2) and (4 s, 0.05): 0.1 is half way in log error, so half way in log time: 2 s.
    assert ee.time_to([(4.0, 0.05), (1.0, 0.2)], 0.1) == pytest.approx(2.0)
    # A curve whose cheapest point is already below the target: that point's time.
    assert ee.time_to([(1.0, 0.08), (4.0, 0.05)], 0.1) == 1.0
    # Never reached.
    assert ee.time_to([(1.0, 0.3), (4.0, 0.2)], 0.1) is None


def test_same_recipe_ignores_comments_and_the_spelling_of_numbers_only():
    a = "# a comment\nrender: {mode: pbr, samples: 1024, filter_glossy: 1.0}\n"
    assert ee.same_recipe(a, "render: {mode: pbr, samples: 1024, filter_glossy: 1}\n")
    assert not ee.same_recipe(a, "render: {mode: pbr, samples: 512, filter_glossy: 1}\n")


def write_reference(folder, name, text):
    (folder / f"{name}_reference" / "train" / "000000").mkdir(parents=True)
    (folder / f"{name}_reference" / "train" / "000000" / "marker").write_text("earlier")
    (folder / f"{name}_reference.yaml").write_text(text)


def test_an_earlier_cadsynth_reference_is_taken_only_for_the_same_recipe(tmp_path):
    scene = ee.Scene("workcell", str(tmp_path / "out"), "/bin/false")
    (tmp_path / "out").mkdir()
    text = scene.recipe(4096, 0.0, 7, views=scene.views()[:1])
    earlier = tmp_path / "earlier"
    # The same recipe with a comment and 1.0 written as 1 (as older runs wrote it).
    write_reference(earlier, "workcell", "# rendered last week\n"
                    + text.replace("clamp_indirect: 0.0", "clamp_indirect: 0"))
    scene.references_from = [str(earlier)]
    dataset, whole, seconds = scene.run("reference", 4096, 0.0, seed=7, views=scene.views()[:1])
    assert pathlib.Path(dataset, "train", "000000", "marker").read_text() == "earlier"
    assert math.isnan(whole) and math.isnan(seconds)

    # Another sample count is another reference: it would be rendered (here: /bin/false fails).
    other = ee.Scene("workcell", str(tmp_path / "out2"), "/bin/false")
    (tmp_path / "out2").mkdir()
    other.references_from = [str(earlier)]
    with pytest.raises(SystemExit, match="cadsynth failed"):
        other.run("reference", 1024, 0.0, seed=7, views=other.views()[:1])


def test_an_earlier_cycles_reference_is_taken_for_the_same_scene_apart_from_paths(tmp_path):
    scene = ee.Scene("workcell", str(tmp_path / "out"), "/bin/false")
    dataset = tmp_path / "out" / "workcell_reference"
    dataset.mkdir(parents=True)
    (dataset / "camera.json").write_text(json.dumps({"width": 320, "height": 240}))
    earlier = tmp_path / "earlier"
    earlier.mkdir()

    def earlier_spec(samples):
        # What another run wrote: its own paths, the one-frame name older runs used, and
        # material keys at their defaults that the other spec does not have.
        (earlier / "cycles_reference.exr").write_bytes(b"earlier image")
        spec_path = tmp_path / "probe" / "cycles_reference_000000.json"
        probe = ee.Scene("workcell", str(tmp_path / "probe"), "/bin/false")
        spec_path.parent.mkdir(exist_ok=True)
        with pytest.raises(SystemExit):  # writes the spec, then Blender (/bin/false) fails
            ee.cycles_run(probe, str(dataset), samples, 0.0, 7, "/bin/false",
                          "reference_000000")
        spec = json.loads(spec_path.read_text())
        spec["dataset"] = str(earlier / "workcell_reference")
        spec["output"] = str(earlier / "cycles_reference.exr")
        for _, material in spec["part_materials"]:
            material.update({"distribution": "ggx", "texture": None})
        (earlier / "cycles_reference.json").write_text(json.dumps(spec, indent=1))

    earlier_spec(4096)
    scene.references_from = [str(earlier)]
    path, seconds = ee.cycles_run(scene, str(dataset), 4096, 0.0, 7, "/bin/false",
                                  "reference_000000")
    assert pathlib.Path(path).read_bytes() == b"earlier image"
    assert path == str(tmp_path / "out" / "cycles_reference_000000.exr")
    assert math.isnan(seconds)

    # An earlier reference of another sample count is not this one: Blender would run.
    earlier_spec(1024)
    (tmp_path / "out" / "cycles_reference_000000.exr").unlink()
    with pytest.raises(SystemExit, match="blender failed"):
        ee.cycles_run(scene, str(dataset), 4096, 0.0, 7, "/bin/false", "reference_000000")


def test_without_defaults_drops_only_keys_at_their_defaults():
    spec = {"fixtures": [{"material": {"distribution": "ggx", "texture": None,
                                       "tangent": "x", "roughness": 0.3}}]}
    assert ee.without_defaults(spec) == {
        "fixtures": [{"material": {"tangent": "x", "roughness": 0.3}}]}


def test_combine_prints_each_scenes_times_and_ratios(tmp_path, capsys):
    pytest.importorskip("matplotlib")

    def point(seconds, parts):
        return {"seconds": seconds, "parts": parts, "all": parts, "edges": parts}

    result = {"scene": "tote", "filter_glossy": 1.0, "glossy_bounces": 0, "clamp_indirect": 10.0,
              "curves": {
                  # Fixed samples: 0.10 at 2 s (log-log half way between 1 s and 4 s).
                  "cadsynth": [point(1.0, 0.2), point(4.0, 0.05)],
                  # Adaptive: its cheapest point already at 0.04, so 0.05 "at most" 3 s.
                  "cadsynth adaptive, background 1": [point(3.0, 0.04)],
                  "Cycles": [point(10.0, 0.2), point(40.0, 0.05)],
                  "Cycles adaptive": [point(30.0, 0.08), point(60.0, 0.04)]}}
    path = tmp_path / "equal_error_tote.json"
    path.write_text(json.dumps(result))
    ee.combine([str(path)], [0.1, 0.05], str(tmp_path / "c"))
    lines = capsys.readouterr().out.splitlines()
    assert lines[2] == ("| tote (Filter Glossy 1, glossy bounces 0, Clamp Indirect 10) | 0.1 | "
                        "2.000 s (fixed) | 20.000 s (10.0x) | at most 30.000 s (15.0x) |")
    # 0.05: cadsynth's fixed curve reaches it at 4 s, its adaptive one at most at 3 s.
    # Cycles adaptive: 0.05 lies log(0.05 / 0.08) / log(0.04 / 0.08) of the way from 30 s to
    # 60 s in log terms, so at 30 s x 2^(that) = 30 s / 0.625 = 48 s.
    assert lines[3] == ("| tote (Filter Glossy 1, glossy bounces 0, Clamp Indirect 10) | 0.05 | "
                        "at most 3.000 s (adaptive, background 1) | 40.000 s (13.3x) | "
                        "48.000 s (16.0x) |")
    assert (tmp_path / "c" / "equal_error_scenes.png").stat().st_size > 10000


def test_a_missing_input_is_one_message_naming_it(tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["equal_error.py", "--combine", str(tmp_path / "no.json"),
                                      "--out", str(tmp_path / "c")])
    with pytest.raises(SystemExit, match="--combine: .*no.json: no such file"):
        ee.main()
    monkeypatch.setattr(sys, "argv", ["equal_error.py", "--references-from",
                                      str(tmp_path / "gone"), "--out", str(tmp_path / "o")])
    with pytest.raises(SystemExit, match="--references-from: .*gone: no such folder"):
        ee.main()
    assert not (tmp_path / "c").exists() and not (tmp_path / "o").exists()
