"""Tests of tools/python/cadsynth/report.py, the page `cadsynth report` writes from report data.

report.py is loaded by its file path, as the C++ binary runs it: it imports nothing of the
package, so these tests need no build (but matplotlib and PIL: Debian's /usr/bin/python3).
"""

import base64
import io
import json
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import load_by_path

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")

REPORT_PY = pathlib.Path(__file__).resolve().parents[2] / "tools/python/cadsynth/report.py"
SECTION_IDS = ["run", "verify", "objects", "images", "randomization", "grasps", "physics",
               "gallery"]


report = load_by_path(REPORT_PY, "cadsynth_report_under_test")


def hist(rng, low, high, bins=20, label="", log=False, total=500):
    edges = (np.geomspace(low, high, bins + 1) if log else np.linspace(low, high, bins + 1))
    counts = np.bincount(rng.integers(0, bins, total), minlength=bins)
    return {"edges": edges.tolist(), "counts": counts.tolist(), "label": label, "log": log}


def image_uri(fmt):
    buf = io.BytesIO()
    Image.new("RGB", (8, 6), (200, 30, 30)).save(buf, format=fmt)
    mime = {"PNG": "png", "JPEG": "jpeg"}[fmt]
    return f"data:image/{mime};base64," + base64.b64encode(buf.getvalue()).decode()


def make_object(rng, obj_id):
    coverage = rng.integers(0, 5, (9, 18)).tolist()
    return {"obj_id": obj_id, "name": f"part_{obj_id}", "diameter_mm": 42.5,
            "symmetry": "discrete (4)", "instances": 120, "visible": 100, "targets": 90,
            "coverage": {"x_edges": np.linspace(-180, 180, 19).tolist(),
                         "y_edges": np.linspace(-90, 90, 10).tolist(), "counts": coverage,
                         "x_label": "azimuth (deg)", "y_label": "elevation (deg)"},
            "inplane_deg": hist(rng, -180, 180, label="deg"),
            "distance_mm": hist(rng, 300, 900, label="mm"),
            "visib_fract": hist(rng, 0, 1, label="fraction"),
            "px_count_visib": hist(rng, 10, 1e5, label="px", log=True)}


def make_sensor(rng):
    return {"name": "", "images": 6, "width": 160, "height": 120,
            "instances_per_image": hist(rng, 0, 10, 10, "instances"),
            "visible_instances_per_image": hist(rng, 0, 10, 10, "instances"),
            "occlusion_per_image": hist(rng, 0, 1, 10, "fraction"),
            "depth_min_mm": hist(rng, 300, 600, 10, "mm"),
            "depth_max_mm": hist(rng, 400, 900, 10, "mm"),
            "empty_images": 1, "sparse_images": 2, "sparse_threshold_px": 100,
            "empty_examples": ["scene 3 image 12"]}


def make_data(objects=2, sensors=True):
    rng = np.random.default_rng(0)
    return {
        "report_data": 1, "title": "bin picking", "dataset": "/data/out",
        "generated_by": "cadsynth 0.9.0",
        "run": {"version": "0.9.0", "run_key": "abc123", "recipe_path": "recipes/r.yaml",
                "recipe_text": "scenes: <bolts & nuts>\n", "started_utc": "2024-01-01T00:00:00Z",
                "seconds": 12.5, "threads": 2,
                "shards": [{"index": 0, "seconds": 6.0, "frames": 3},
                           {"index": 1, "seconds": 6.5, "frames": 3}],
                "frames": 6, "scenes": 2, "objects": objects, "instances": 24, "files": 60,
                "bytes": 1234567, "splits": {"train": 4, "test": 2}},
        "sensors": [make_sensor(rng)] if sensors else [],
        "objects": [make_object(rng, i + 1) for i in range(objects)],
        "randomization": [
            {"key": "lights.power", "kind": "number", "hist": hist(rng, 20, 80, label="W"),
             "asked": "log_uniform: [20, 80]"},
            {"key": "lights.count", "kind": "choice", "counts": {"1": 4, "2": 2},
             "asked": "choice: [1, 2]"},
            {"key": "camera.exposure", "kind": "number", "hist": hist(rng, 0.5, 2), "asked": None},
        ],
        "grasps": {"per_object": [{"obj_id": 1, "parallel_jaw": 300, "suction": 120}],
                   "per_frame": {"parallel_jaw": hist(rng, 0, 50, 10),
                                 "suction": hist(rng, 0, 30, 10)}},
        "physics": {"columns": ["scene", "settle seconds"], "rows": [[0, 0.42], [1, 0.37]]},
        "gallery": [{"title": "first", "caption": "scene 0, rgb", "scene_id": 0, "im_id": 0,
                     "sensor": "", "image": image_uri("JPEG")},
                    {"title": "masks", "caption": "visible masks", "scene_id": 0, "im_id": 1,
                     "sensor": "", "image": image_uri("PNG")}],
        "verify": {"verdict": "pass", "summary": "3 checks, 0 problems",
                   "checks": [{"name": "scene_gt", "checked": 6, "failed": 0},
                              {"name": "masks", "checked": 24, "failed": 0},
                              {"name": "depth", "checked": 6, "failed": 0}],
                   "problems": []},
    }


@pytest.fixture(scope="module")
def page():
    """The page of make_data(), built once (a page takes seconds)."""
    return report.build_html(make_data())


def img_tags(page):
    return re.findall(r"<img\b[^>]*>", page)


def test_every_section_and_image(page):
    for section in SECTION_IDS:
        assert f'<h2 id="{section}">' in page
        assert f'href="#{section}"' in page
    # 2 objects + 1 sensor + 1 randomisation grid + 1 grasps + 2 gallery images.
    tags = img_tags(page)
    assert len(tags) == 7
    for tag in tags:
        src = re.search(r'src="([^"]*)"', tag).group(1)
        uri = re.fullmatch(r"data:image/(png|jpeg);base64,([A-Za-z0-9+/=]+)", src)
        mime, payload = uri.groups()
        with Image.open(io.BytesIO(base64.b64decode(payload, validate=True))) as image:
            assert image.format == mime.upper()
            image.load()
        assert re.search(r'alt="[^"]{5,}"', tag), tag
    assert "obj_000001 part_1" in page and "obj_000002 part_2" in page
    ids = re.findall(r'\bid="([^"]*)"', page)
    assert len(ids) == len(set(ids))


def test_self_contained(page):
    links = re.findall(r'(?:src|href)="([^"]*)"', page)
    assert links and not any(re.match(r"(https?:)?//", link) for link in links)
    assert "http://" not in page and "https://" not in page
    assert "<script" not in page and "<link" not in page


def test_run_and_verify_pass(page):
    assert "<details><summary>recipe</summary><pre>scenes: &lt;bolts &amp; nuts&gt;" in page
    assert "1,234,567" in page and "train 4, test 2" in page
    assert 'class="badge pass">PASS<' in page and "FAIL" not in page
    for check in ("scene_gt", "masks", "depth"):
        assert f"<td>{check}</td>" in page


def test_verify_fail_escapes_problems():
    data = make_data(objects=0, sensors=False)
    data["verify"] = {"verdict": "fail", "summary": "1 problem",
                      "checks": [{"name": "depth", "checked": 6, "failed": 1}],
                      "problems": [{"file": "scene/000001/depth/000003.png",
                                    "reason": "depth < 0 & <script>"}]}
    page = report.build_html(data)
    assert 'class="badge fail">FAIL<' in page
    assert "scene/000001/depth/000003.png" in page
    assert "depth &lt; 0 &amp; &lt;script&gt;" in page
    assert "depth < 0" not in page and "<script>" not in page


def test_not_verified():
    data = make_data(objects=0, sensors=False)
    data["verify"] = None
    page = report.build_html(data)
    assert "not verified: run <code>cadsynth verify /data/out</code>" in page
    assert "badge" not in page.split('id="verify"')[1].split("<section>")[0]


def test_null_grasps_and_physics_are_left_out():
    data = make_data()
    data["grasps"] = data["physics"] = None
    page = report.build_html(data)
    for section in ("grasps", "physics"):
        assert f'id="{section}"' not in page and f'href="#{section}"' not in page
    assert len(img_tags(page)) == 6
    assert "<td>settle seconds</td>" not in page


def test_physics_table(page):
    assert "<th>settle seconds</th>" in page and '<td class="num">0.42</td>' in page


def test_missing_and_empty_fields():
    data = make_data()
    data["run"] = {"frames": None}
    data["randomization"] = []
    data["gallery"] = []
    data["grasps"] = {"per_object": [], "per_frame": {"parallel_jaw": None}}
    zero = {"edges": [0, 1, 2], "counts": [0, 0], "label": "x", "log": False}
    empty_object = {"obj_id": 7, "name": "ghost",
                    "coverage": {"x_edges": [0, 1], "y_edges": [0, 1], "counts": [[0]]},
                    "inplane_deg": zero, "distance_mm": None, "visib_fract": {},
                    "px_count_visib": {"edges": [1], "counts": [3]}}
    data["objects"] = [empty_object, make_object(np.random.default_rng(1), 8)]
    data["objects"][1]["inplane_deg"] = zero
    data["sensors"][0].update({k: zero for k in ("instances_per_image", "depth_max_mm")})
    page = report.build_html(data)
    assert "no randomisation" in page and "no run facts" in page and "no gallery" in page
    assert 'id="obj_000007"' in page and "no data" in page
    # The empty object has no figure; the other object, the sensor: one each; grasps none.
    assert len(img_tags(page)) == 2
    minimal = report.build_html({"report_data": 1})
    for section in ("run", "verify", "objects", "images", "randomization", "gallery"):
        assert f'<h2 id="{section}">' in minimal
    assert "<img" not in minimal


def test_main_writes_the_page(tmp_path, capsys):
    data_path, out_path = tmp_path / "data.json", tmp_path / "report.html"
    data_path.write_text(json.dumps(make_data()))
    assert report.main([str(data_path), str(out_path)]) == 0
    page = out_path.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data.json", "report.html"]


def test_main_usage_and_bad_json(tmp_path, capsys):
    assert report.main([]) == 2
    assert report.main(["only.json"]) == 2
    assert "usage" in capsys.readouterr().err
    bad, out_path = tmp_path / "bad.json", tmp_path / "report.html"
    bad.write_text('{"report_data": 1, "title": ')
    assert report.main([str(bad), str(out_path)]) == 1
    assert str(bad) in capsys.readouterr().err
    assert report.main([str(tmp_path / "missing.json"), str(out_path)]) == 1
    assert "missing.json" in capsys.readouterr().err
    bad.write_text("[1, 2]")
    assert report.main([str(bad), str(out_path)]) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]
    out_path.write_text("the last good report")
    assert report.main([str(bad), str(out_path)]) == 1
    assert out_path.read_text() == "the last good report"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "report.html"]


def test_runs_standalone_from_a_temp_dir(tmp_path):
    # As the C++ binary runs it: a copy of the file alone, no package beside it, no PYTHONPATH.
    script = tmp_path / "report.py"
    script.write_text(REPORT_PY.read_text())
    (tmp_path / "data.json").write_text(json.dumps(make_data()))
    env = {"PATH": "/usr/bin:/bin", "MPLCONFIGDIR": str(tmp_path / "mpl")}
    done = subprocess.run([sys.executable, str(script), "data.json", "out.html"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert 'id="gallery"' in (tmp_path / "out.html").read_text()
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "usage" in done.stderr


def test_thirty_objects_stay_small(page):
    # Each object adds one figure: ten of them (a page takes 0.6 s per object) bound thirty's.
    data = make_data(objects=10)
    ten = report.build_html(data)
    assert len(img_tags(ten)) == 10 + 5
    per_object = (len(ten.encode("utf-8")) - len(page.encode("utf-8"))) / (10 - 2)
    thirty = len(page.encode("utf-8")) + 28 * per_object
    print(f"30-object report: {thirty / 1e6:.2f} MB")
    assert thirty < 4e6


def test_many_randomised_keys_share_figures():
    data = make_data(objects=0, sensors=False)
    rng = np.random.default_rng(2)
    data["randomization"] = [{"key": f"k{i}", "kind": "number", "hist": hist(rng, 0, 1),
                              "asked": "uniform: [0, 1]"} for i in range(25)]
    page = report.build_html(data)
    section = page.split('id="randomization"')[1].split("<section>")[0]
    assert len(img_tags(section)) == 3  # 12 + 12 + 1 keys


def test_draws_against_the_recipe():
    """Tested draws say whether they agree (a summary names those that differ); the expected
    counts are drawn over the draws; a note says why draws were not compared."""
    data = make_data(objects=0, sensors=False)
    rng = np.random.default_rng(3)
    power = hist(rng, 20, 80, label="W")
    data["randomization"] = [
        {"key": "light.*.power", "kind": "number", "hist": power, "asked": "{uniform: [20, 80]}",
         "per": "frame", "samples": 40, "expected": [40 / len(power["counts"])] * len(
             power["counts"]),
         "check": {"test": "Kolmogorov-Smirnov", "statistic": 0.05, "p_value": 0.9,
                   "samples": 40, "agrees": True}},
        {"key": "part.*.preset", "kind": "choice", "counts": {"steel": 30, "gold": 10},
         "asked": "{choice: [steel, abs]}", "per": "scene", "samples": 40,
         "expected": {"steel": 20.0, "abs": 20.0, "gold": 0.0},
         "check": {"test": "chi-square", "statistic": float("inf"), "p_value": 0.0,
                   "samples": 40, "agrees": False}},
        {"key": "distractor.*.color[0]", "kind": "number", "hist": hist(rng, 0, 1),
         "asked": None, "check": None, "expected": None},
    ]
    page = report.build_html(data)
    section = page.split('id="randomization"')[1].split("<section>")[0]
    assert "2 of 3 randomised quantities tested against the recipe: 1 differ (part.*.preset)" \
        in section
    assert "as asked (Kolmogorov-Smirnov, p = 0.9)" in section
    assert "DIFFERS (chi-square, p = 0)" in section
    assert len(img_tags(section)) == 1
    data["randomization_note"] = "the recipe in run.json could not be read again, so ..."
    assert "could not be read again" in report.build_html(data)


def test_pile_rest_tables_and_gallery_per_sensor():
    """Physics as tables (piles with their summary and settle-time histogram, pick sequences), and
    a rig's gallery under a heading per sensor."""
    data = make_data(objects=0, sensors=False)
    rng = np.random.default_rng(4)
    data["physics"] = {"tables": [
        {"title": "Piles and dropped parts", "summary": "1 of 2 piles and drops at rest",
         "columns": ["scene", "at rest"], "rows": [[0, "no"], [1, "yes"]], "more": 3,
         "settle_seconds": hist(rng, 0.5, 3)},
        {"title": "Pick sequences", "columns": ["scene", "step"], "rows": [[0, 0], [1, 1]],
         "more": 0}]}
    image = data["gallery"][0]["image"]
    data["gallery"] = [{"title": t, "caption": "", "scene_id": 0, "im_id": 0, "sensor": s,
                        "image": image} for s in ("rgb", "depth") for t in ("first", "middle")]
    page = report.build_html(data)
    physics = page.split('id="physics"')[1].split("<section>")[0]
    assert "<h3>Piles and dropped parts</h3>" in physics and "<h3>Pick sequences</h3>" in physics
    assert "1 of 2 piles and drops at rest" in physics and "and 3 more rows" in physics
    assert len(img_tags(physics)) == 1  # the settle-time histogram
    gallery = page.split('id="gallery"')[1]
    assert gallery.index("<h3>sensor rgb</h3>") < gallery.index("<h3>sensor depth</h3>")
    assert len(img_tags(gallery)) == 4
