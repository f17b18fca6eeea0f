"""Frames from Python are the frames `cadsynth generate` writes (docs/python.md)."""

import ast
import json
import re
import subprocess

import numpy as np
import pytest

import cadsynth
from cadsynth import _cadsynth
from conftest import CLI, STUB, stub_frame_keys


def read_json(path):
    return json.loads(path.read_text())


@pytest.fixture(scope="module")
def cli_dataset(recipe_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "dataset"
    subprocess.run([str(CLI), "generate", str(recipe_file), "-o", str(out), "--quiet"],
                   check=True)
    return out


@pytest.fixture(scope="module")
def run(recipe_file):
    return cadsynth.Recipe.load(recipe_file).prepare()


def test_frames_equal_the_files_the_cli_writes(run, cli_dataset):
    frames = list(run.frames())
    assert len(frames) == 6
    assert [(f["scene_id"], f["im_id"]) for f in frames] == [(s, v) for s in (0, 1)
                                                             for v in range(3)]
    for f in frames:
        scene = cli_dataset / "train" / f"{f['scene_id']:06d}"
        im = f"{f['im_id']:06d}"
        # The images, encoded as the writer encodes them, are the files' bytes.
        assert cadsynth.encode_png(f["rgb"]) == (scene / "rgb" / f"{im}.png").read_bytes()
        depth = cadsynth.encode_depth(f["depth"], f["depth_scale"])
        assert cadsynth.encode_png(depth) == (scene / "depth" / f"{im}.png").read_bytes()
        depth_gt = cadsynth.encode_depth(f["depth_gt"], f["depth_scale"])
        assert cadsynth.encode_png(depth_gt) == (scene / "depth_gt" / f"{im}.png").read_bytes()
        # The sensor's depth is not the exact one (noise, shadows), the exact one is exact.
        assert not np.array_equal(f["depth"], f["depth_gt"])
        # Masks, pixel for pixel.
        for i in range(len(f["obj_id"])):
            name = f"{im}_{i:06d}.png"
            assert np.array_equal(cadsynth.read_image(scene / "mask" / name) == 255, f["mask"][i])
            assert np.array_equal(cadsynth.read_image(scene / "mask_visib" / name) == 255,
                                  f["mask_visib"][i])
        # The visible ids and the visible masks agree (exact visibility, BOP's default here).
        for i in range(len(f["obj_id"])):
            assert np.array_equal(f["instance"] == i + 1, f["mask_visib"][i])
        # Poses and boxes as scene_gt.json and scene_gt_info.json hold them.
        gt = read_json(scene / "scene_gt.json")[str(f["im_id"])]
        info = read_json(scene / "scene_gt_info.json")[str(f["im_id"])]
        camera = read_json(scene / "scene_camera.json")[str(f["im_id"])]
        assert f["K"].flatten().tolist() == camera["cam_K"]
        assert f["cam_from_world"][:3, :3].flatten().tolist() == camera["cam_R_w2c"]
        assert f["cam_from_world"][:3, 3].tolist() == camera["cam_t_w2c"]
        for i, entry in enumerate(gt):
            assert f["obj_id"][i] == entry["obj_id"]
            assert f["cam_from_model"][i][:3, :3].flatten().tolist() == entry["cam_R_m2c"]
            assert f["cam_from_model"][i][:3, 3].tolist() == entry["cam_t_m2c"]
            assert f["bbox_obj"][i].tolist() == info[i]["bbox_obj"]
            assert f["bbox_visib"][i].tolist() == info[i]["bbox_visib"]
            assert f["px_count_visib"][i] == info[i]["px_count_visib"]
            assert f["visib_fract"][i] == info[i]["visib_fract"]
        # The split, as splits/ lists the image.
        split = (cli_dataset / "splits" / f"{f['split']}.txt").read_text().split("\n")
        assert f"{f['scene_id']:06d} {f['im_id']:06d}" in split
        # Randomised lights: the draws the dataset records.
        drawn = read_json(scene / "scene_randomization.json")[str(f["im_id"])]
        assert json.loads(f["randomization"]) == drawn
        # Grasp labels: the GraspNet rows of the frame's .npy files.
        rows = np.load(cli_dataset / "graspnet" / f"{f['scene_id']:06d}" / f"{im}.npy")
        labels = np.load(cli_dataset / "graspnet" / f"{f['scene_id']:06d}" /
                         f"{im}_labels.npy")
        assert np.array_equal(rows, f["graspnet"])
        assert np.array_equal(labels, f["graspnet_labels"])
    assert sum(len(f["graspnet"]) for f in frames) > 0


def test_shards_together_are_the_whole_run(run):
    whole = {(f["scene_id"], f["im_id"]): f["rgb"].tobytes() for f in run.frames(masks=False)}
    parts = {}
    for i in range(2):
        for f in run.frames(shard=(i, 2), masks=False, threads=1):
            assert (f["scene_id"] * run.views + f["im_id"]) % 2 == i
            parts[(f["scene_id"], f["im_id"])] = f["rgb"].tobytes()
    assert parts == whole


def test_one_frame_and_the_run_object(run):
    assert (run.scenes, run.views, run.units) == (2, 3, 6)
    assert [o["obj_id"] for o in run.objects] == [1, 2, 3, 4]
    f = run.frame(4, masks=False)
    assert (f["scene_id"], f["im_id"], f["kept"]) == (1, 1, True)
    assert "mask" not in f
    assert f["rgb"].shape == (120, 160, 3) and f["rgb"].dtype == np.uint8
    assert f["depth"].dtype == np.float32 and f["instance"].dtype == np.uint16
    assert f["cam_from_model"].shape == (2, 4, 4)
    # The pose puts the model's origin where the depth sees it: in front of the camera, at
    # about the sweep's radius.
    assert 250 < f["cam_from_model"][0][2, 3] < 450


def test_a_run_writes_what_the_cli_writes(run, cli_dataset, tmp_path):
    summary = run.write(tmp_path / "out")
    assert summary["frames"] == 6
    for name in ("train/000001/rgb/000002.png", "train/000000/scene_gt.json",
                 "models/models_info.json", "graspnet/000001/000000.npy"):
        assert (tmp_path / "out" / name).read_bytes() == (cli_dataset / name).read_bytes(), name


def test_reseeded_runs_are_new_and_reproducible(recipe_file):
    recipe = cadsynth.Recipe.load(recipe_file)
    assert recipe.reseeded(0).stream == 0
    first = recipe.reseeded(7).prepare().frame(0, masks=False)
    again = recipe.reseeded(7).prepare().frame(0, masks=False)
    own = recipe.prepare().frame(0, masks=False)
    assert np.array_equal(first["rgb"], again["rgb"])
    assert first["randomization"] == again["randomization"]
    assert first["randomization"] != own["randomization"]


def test_bad_recipes_raise_with_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("scenes:\n  - name: a\n    parts: [{family: round_peg}]\n    layout: gird\n")
    with pytest.raises(cadsynth.Error, match=r"bad\.yaml:4:13: .*gird"):
        cadsynth.Recipe.load(bad)
    with pytest.raises(cadsynth.Error, match=r"^<string>:1:\d+: .*rendr"):
        cadsynth.Recipe.from_yaml("rendr: {mode: pbr}")
    with pytest.raises(cadsynth.Error, match=r"^<dict>:\d+:\d+: .*samples"):
        cadsynth.Recipe.from_dict({"render": {"mode": "pbr", "samples": -3}})
    with pytest.raises(cadsynth.Error, match="missing.yaml"):
        cadsynth.Recipe.load(tmp_path / "missing.yaml")
    # cadsynth.Error is a RuntimeError.
    assert issubclass(cadsynth.Error, RuntimeError)


def test_recipes_from_dicts_and_pickles():
    import pickle
    recipe = cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [60], "radius": ["0.3 m"]},
    })
    assert recipe.views == 1
    copy = pickle.loads(pickle.dumps(recipe.reseeded(5).reseeded(3)))  # streams do not compound
    assert copy.stream == 3
    a = recipe.reseeded(3).prepare(cache=False).frame(0, masks=False)
    b = copy.prepare(cache=False).frame(0, masks=False)
    assert np.array_equal(a["rgb"], b["rgb"])
    assert a["rgb"].shape == (48, 64, 3)


def test_a_rig_gives_every_sensors_frame_as_written(tmp_path):
    recipe = tmp_path / "rig.yaml"
    recipe.write_text("""\
parts: [{family: hex_nut, params: {size: M12}}]
cameras:
  - {name: grey, width: 96, height: 72, fx: 90, fy: 90, cx: 47.5, cy: 35.5, image: gray16}
  - {name: colour, width: 80, height: 60, fx: 70, fy: 70, cx: 39.5, cy: 29.5,
     position: [40 mm, 0, 0], look_at: [0, 0, 300 mm]}
sweep: {yaw: [0, 180], pitch: [60], radius: [0.3 m]}
""")
    out = tmp_path / "out"
    subprocess.run([str(CLI), "generate", str(recipe), "-o", str(out), "--quiet"], check=True)
    run = cadsynth.Recipe.load(recipe).prepare()
    assert run.sensors == ["grey", "colour"]
    for f in run.frames():
        assert [s["sensor"] for s in f["sensors"]] == ["grey", "colour"]
        assert f["sensor"] == "grey" and "sensors" not in f["sensors"][0]
        grey, colour = f["sensors"]
        assert grey["gray"].dtype == np.uint16 and grey["gray"].shape == (72, 96)
        assert "rgb" not in grey and colour["rgb"].shape == (60, 80, 3)
        scene = out / "train" / "000000"
        im = f"{f['im_id']:06d}.png"
        assert cadsynth.encode_png(grey["gray"]) == (scene / "gray_grey" / im).read_bytes()
        assert cadsynth.encode_png(colour["rgb"]) == (scene / "rgb_colour" / im).read_bytes()
        assert np.array_equal(f["gray"], grey["gray"])



def check_frame(frame, keys, seen):
    """The frame (and a rig's every sensor's) holds what the stub says; its keys go into `seen`."""
    assert set(frame) <= set(keys), f"keys not in the stub: {set(frame) - set(keys)}"
    missing = {k for k, (required, *_) in keys.items() if required} - set(frame)
    assert not missing, f"required keys missing: {missing}"
    seen.update(frame)
    # Letters stand for the frame's sizes: H, W and N fixed, the others (grasp rows) taken from
    # their first key.
    dims = {"H": frame["height"], "W": frame["width"], "N": len(frame["obj_id"])}
    for key, value in frame.items():
        _, annotation, dtypes, shape = keys[key]
        if dtypes:
            assert isinstance(value, np.ndarray), key
            assert value.dtype.type.__name__ in dtypes, (key, value.dtype, dtypes)
            assert value.ndim == len(shape), (key, value.shape, shape)
            for dim, size in zip(shape, value.shape):
                assert size == (int(dim) if dim.isdigit() else dims.setdefault(dim, size)), \
                    (key, value.shape, shape)
        elif annotation == "list[Frame]":
            for sensor in value:
                check_frame(sensor, keys, seen)
        else:
            expected = {"int": int, "float": float, "str": str, "bool": bool}[annotation]
            assert type(value) is expected, (key, type(value), annotation)


def test_frames_hold_the_keys_the_stub_documents(run, tmp_path):
    keys = stub_frame_keys()
    seen = set()
    for f in run.frames():  # colour, a depth model, grasp rows, randomised lights
        check_frame(f, keys, seen)
    check_frame(run.frame(4, masks=False), keys, seen)
    # What the small recipe lacks: a rig of two grey cameras (8 and 16 bits), the first an active
    # stereo sensor (IR), normals, HDR radiance and suction rows.
    recipe = tmp_path / "everything.yaml"
    recipe.write_text("""\
parts: [{family: hex_nut, params: {size: M12}}]
cameras:
  - {name: ir, width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5, image: gray,
     depth: active_stereo}
  - {name: deep, width: 48, height: 36, fx: 45, fy: 45, cx: 23.5, cy: 17.5, image: gray16,
     position: [40 mm, 0, 0], look_at: [0, 0, 300 mm]}
sweep: {yaw: [0, 180], pitch: [60], radius: [0.3 m]}
render: {normals: true, hdr: true}
grasps: {gripper: franka, samples: 200, suction: true}
""")
    for f in cadsynth.Recipe.load(recipe).prepare(cache=False).frames():
        check_frame(f, keys, seen)
    # And what training a denoiser reads (pbr, Recipe.prepare(denoiser_inputs=True)).
    check_frame(pbr_peg(denoise=True).prepare(cache=False, denoiser_inputs=True).frame(0),
                keys, seen)
    assert seen == set(keys), f"documented but never produced: {set(keys) - seen}"


def test_the_stub_names_what_the_module_has():
    """Every public class, function and method of the compiled module is in the stub, with its
    parameters' names and defaults as pybind11's signatures give them, and nothing else is."""
    tree = ast.parse(STUB.read_text())
    typed_dicts = set()  # for checkers only: TypedDicts and their subclasses
    for n in tree.body:
        if isinstance(n, ast.ClassDef) and any(ast.unparse(b) in typed_dicts | {"TypedDict"}
                                               for b in n.bases):
            typed_dicts.add(n.name)
    names = {n.name for n in tree.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    assert names - typed_dicts == {n for n in dir(_cadsynth) if not n.startswith("_")}

    def parameters(function):  # [(name, default)] without self
        args = function.args.args
        defaults = [None] * (len(args) - len(function.args.defaults)) + [
            ast.literal_eval(d) for d in function.args.defaults]
        return [(a.arg, d) for a, d in zip(args, defaults) if a.arg != "self"]

    def signature(routine):  # pybind11's first docstring line: name(a: T, b: T = default) -> R
        inside = re.match(r"\w+\((.*)\) ->", routine.__doc__.split("\n")[0]).group(1)
        out = []
        for part in re.split(r", (?![^\[]*\])", inside) if inside else []:
            name, _, default = part.partition(" = ")
            name = name.split(":")[0]
            if name != "self":
                out.append((name, ast.literal_eval(default) if default else None))
        return out

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            assert parameters(node) == signature(getattr(_cadsynth, node.name)), node.name
        if not isinstance(node, ast.ClassDef) or node.name in typed_dicts:
            continue
        cls = getattr(_cadsynth, node.name)
        methods = {n.name: n for n in node.body if isinstance(n, ast.FunctionDef)}
        assert {n for n in methods if not n.startswith("_")} == \
            {n for n in vars(cls) if not n.startswith("_")}, node.name
        for name, method in methods.items():
            if not any(ast.unparse(d) == "property" for d in method.decorator_list):
                assert parameters(method) == signature(getattr(cls, name)), f"{node.name}.{name}"


def test_a_piles_tote_is_given_as_traced():
    # A tote of inner 100 x 80 mm, 40 mm high, walls 4 mm and floor 5 mm, centred on the origin
    # on the floor: its outside spans 108 x 88 x 45 mm (tools/cycles rebuilds frames from this).
    run = cadsynth.Recipe.from_dict({
        "scenes": [{"name": "pile", "parts": [{"family": "round_peg"}], "layout": "pile",
                    "copies": 2, "seed": 1,
                    "container": {"type": "tote", "inner": ["100 mm", "80 mm"],
                                  "height": "40 mm", "wall": "4 mm", "floor": "5 mm",
                                  "corner_radius": "5 mm", "color": [0.5, 0.25, 0.0]}}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [90], "radius": ["0.3 m"]},
    }).prepare(cache=False)
    [tote] = run.fixtures(0)
    assert tote["name"] == "tote"
    v, n, t = tote["vertices"], tote["normals"], tote["triangles"]
    assert v.dtype == np.float32 and t.dtype == np.uint32
    np.testing.assert_allclose(v.min(axis=0), [-54, -44, 0], atol=1e-3)
    np.testing.assert_allclose(v.max(axis=0), [54, 44, 45], atol=1e-3)
    assert n.shape == v.shape and np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-5)
    assert t.shape[1] == 3 and t.max() < len(v)
    # sRGB 0.5, 0.25, 0 in linear RGB; the default dielectric (Scene::DefaultMaterial).
    m = tote["material"]
    np.testing.assert_allclose(m["base_color"], [0.2140, 0.0509, 0.0], atol=1e-4)
    assert (m["metallic"], m["specular"], m["textured"]) == (0.0, 0.5, False)
    assert (m["anisotropic"], m["clearcoat"], m["multiscatter"]) == (0.0, 0.0, False)
    assert abs(m["roughness"] - 0.45) < 1e-6
    assert cadsynth.Recipe.default().prepare().fixtures(0) == []
    with pytest.raises(IndexError):
        run.fixtures(1)


def test_look_gives_each_instance_its_material_as_the_renderer_shades_it():
    # Two pegs: the first (the assign rule's) brushed aluminium along the model's x, the second
    # ABS taking the part's colour (part 1's of the palette), a wood floor, one rect light by
    # its target and a uniform world: what tools/cycles rebuilds a frame from.
    run = cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}, {"family": "square_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [90], "radius": ["0.3 m"]},
        "render": {"mode": "pbr"},
        "materials": {"floor": {"preset": "wood"},
                      "assign": [{"family": "round_peg", "preset": "aluminium"},
                                 {"name": "*", "preset": "abs"}]},
        "lighting": {"lights": [{"type": "rect", "position": ["0.1 m", "0", "1 m"],
                                 "target": [0, 0, 0], "size": ["0.4 m", "0.2 m"],
                                 "power": 30}],
                     "environment": {"type": "uniform", "color": [0.2, 0.2, 0.2],
                                     "strength": 0.5}},
    }).prepare(cache=False)
    look = run.look(0)
    metal, plastic = look["instances"]
    assert (metal["name"], plastic["name"]) == ("round_peg", "square_peg")
    # The aluminium preset (render/material.cpp): its own colour, brushed along x, 6 mm streaks.
    np.testing.assert_allclose(metal["base_color"], [0.91, 0.92, 0.92], atol=1e-6)
    assert (metal["metallic"], metal["tangent"], metal["base_from_part"]) == (1.0, "x", False)
    assert abs(metal["anisotropic"] - 0.4) < 1e-6 and metal["distribution"] == "ggx"
    assert metal["textured"] and metal["texture"]["type"] == "brushed"
    assert metal["texture"]["scale"] == 6.0 and abs(metal["texture"]["amount"] - 0.04) < 1e-6
    # ABS takes the part's colour, resolved to linear; untextured. PaletteColor(1)
    # (render/scene.cpp): hue (0.08 + 0.618034) x 6 = 4.188, sector 4, f = 0.188: (t, p, v) =
    # (0.9 (1 - 0.65 (1 - f)), 0.9 x 0.35, 0.9) = sRGB (0.4251, 0.315, 0.9), linear as below.
    np.testing.assert_allclose(plastic["base_color"], [0.1512, 0.0809, 0.7874], atol=2e-4)
    assert plastic["base_from_part"] and plastic["texture"] is None
    assert look["floor"]["texture"]["type"] == "wood" and look["floor_half_size"] == 10000.0
    [light] = look["lights"]
    assert (light["type"], light["power"], light["size_x"], light["size_y"]) == (
        "rect", 30.0, 400.0, 200.0)
    np.testing.assert_allclose(light["position"], [100, 0, 1000])
    np.testing.assert_allclose(np.cross(light["direction"], [-100, 0, -1000]), 0, atol=1e-9)
    assert look["environment"]["type"] == "uniform"
    np.testing.assert_allclose(look["environment"]["color"], [0.2] * 3, atol=1e-7)
    assert look["fixtures"] == []
    with pytest.raises(IndexError):
        run.look(1)


def pbr_peg(**render):
    return cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [60], "radius": ["0.3 m"]},
        "render": {"mode": "pbr", "samples": 2, "hdr": True, **render},
    })


def test_pbr_frames_give_what_the_denoiser_reads():
    # Without the denoiser, its input radiance is the frame's radiance; with it, the frame's is
    # the denoised one and the input stays the noisy one (the same paths: same seed).
    plain = pbr_peg().prepare(cache=False, denoiser_inputs=True).frame(0, masks=False)
    assert np.array_equal(plain["denoiser_radiance"], plain["radiance"])
    seen = plain["depth"] > 0
    assert plain["denoiser_albedo"].shape == (48, 64, 3)
    assert plain["denoiser_albedo"][seen].min() >= 0 and plain["denoiser_albedo"][seen].max() <= 1
    lengths = np.linalg.norm(plain["denoiser_normal"][seen], axis=1)
    # A mean of unit normals: unit inside a face, shorter where a pixel's paths hit two faces.
    assert np.median(lengths) > 0.999 and lengths.max() < 1.001
    assert plain["denoiser_variance"].shape == (48, 64) and plain["denoiser_variance"].min() >= 0
    for denoiser in ("network", "filter"):
        run = pbr_peg(denoise=True, denoiser=denoiser).prepare(cache=False, denoiser_inputs=True)
        frame = run.frame(0, masks=False)
        assert np.array_equal(frame["denoiser_radiance"], plain["radiance"])
        assert not np.array_equal(frame["radiance"], plain["radiance"])
        assert np.array_equal(frame["depth"], plain["depth"])
    assert "denoiser_albedo" not in pbr_peg().prepare(cache=False).frame(0, masks=False)


def test_pbr_frames_give_the_paths_each_pixel_got():
    # Adaptive sampling: every pixel gets between min_samples and samples paths; a flat lit floor
    # far from the part stops at the first check more often than not.
    recipe = cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [60], "radius": ["0.3 m"]},
        "render": {"mode": "pbr", "samples": 32, "min_samples": 4, "noise_threshold": 0.05},
    })
    frame = recipe.prepare(cache=False).frame(0, masks=False)
    samples = frame["samples"]
    assert samples.dtype == np.int32 and samples.shape == (48, 64)
    assert samples.min() >= 4 and samples.max() <= 32
    assert samples.min() < samples.max()
    fast = cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [60], "radius": ["0.3 m"]},
    }).prepare(cache=False).frame(0, masks=False)
    assert "samples" not in fast


def test_background_samples_cap_the_tiles_away_from_the_parts():
    # render.background_samples: the 4 x 4 tiles that neither show the peg nor touch a tile that
    # does take one path; the peg's own pixels keep the 8 asked for.
    recipe = cadsynth.Recipe.from_dict({
        "parts": [{"family": "round_peg"}],
        "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5},
        "sweep": {"yaw": [0], "pitch": [60], "radius": ["0.45 m"]},
        "render": {"mode": "pbr", "samples": 8, "background_samples": 1},
    })
    frame = recipe.prepare(cache=False).frame(0, masks=False)
    samples, instance = frame["samples"], frame["instance"]
    assert (instance > 0).sum() > 10
    assert np.all(samples[instance > 0] == 8)
    assert set(np.unique(samples)) == {1, 8}
    tiles = samples.reshape(12, 4, 16, 4).transpose(0, 2, 1, 3).reshape(12, 16, 16)
    assert all(len(np.unique(t)) == 1 for t in tiles.reshape(-1, 16))  # one count per tile
    # 8 exactly in the tiles that show the peg and their 8 neighbours.
    shows = (instance > 0).reshape(12, 4, 16, 4).any(axis=(1, 3))
    padded = np.pad(shows, 1)
    near = np.zeros_like(shows)
    for dy in range(3):
        for dx in range(3):
            near |= padded[dy:dy + 12, dx:dx + 16]
    assert np.array_equal(tiles[:, :, 0] == 8, near)
    assert (samples == 1).mean() > 0.5
