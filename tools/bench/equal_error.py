#!/usr/bin/env python3
"""Equal-error speed of the physically based mode (issue 44): for each renderer and scene, the
error of a frame against that renderer's own many-sample reference, and the time it took, over a
range of sample counts and adaptive-sampling thresholds; then the time each needs to reach a given
error (interpolated on the error-time curve, log-log), and a picture of the curves.

    tools/bench/equal_error.py --scene workcell [--renderers cadsynth,cycles] [--out DIR]
    tools/bench/equal_error.py --scene pbr_demo --renderers cadsynth --reference-samples 1024
    tools/bench/equal_error.py --scene pbr_demo ... --denoise --background-samples 1
    tools/bench/equal_error.py --scene tote ... --references-from EARLIER_OUT   (both renderers'
        curves in one run against references rendered once: hours at 1,024 samples)

Error: the relative RMSE of the displayed values (the linear radiance of rgb_hdr/ or Cycles' EXR,
exposed and put through the recipe's display transform, standard or filmic, as cadsynth's 8-bit
images are; values 0-1): sqrt(mean((x - ref)^2)) / mean(ref) over the three channels of a region's
pixels. Regions: the whole frame, the parts' pixels (the union of the frame's mask_visib/) and the
parts' edge pixels (parts' pixels with a 4-neighbour of another instance or the background; what
a denoiser must not blur). The reference is the same renderer at --reference-samples without
adaptive sampling, with another seed, so its own noise is independent of the runs'.

Time: cadsynth, the path tracer's seconds per frame: the whole process as a user runs it
(`cadsynth generate`, warm part cache) less the same run in the fast mode (start-up, exact labels,
writing: what an exact frame costs anyway), divided by the frames it wrote (workcell: four views,
the error is view 0's; the whole process's time is in the JSON too); Cycles, its render time of
the one frame from its log, without starting Blender or building the scene (tools/cycles
cycles_scene.py rebuilds cadsynth's frame: the same meshes, normals, poses, camera, lights and
materials). Both use every core of the machine.

Scenes: workcell (tools/cycles/compare_with_cycles.py's case: a gear, a bolt, a nut, a peg and a
washer, metal and Lambert, two area lights and a grey world, 320 x 240); pbr_demo
(recipes/pbr_demo.yaml's three default scenes, four views each of which view 0 is measured, 640 x
480; Cycles rebuilds each of the three from Run.look, its steel, aluminium, black oxide and wood
textures in kind from Cycles' own nodes: the same kinds, sizes and amounts, not the same
patterns); tote (an XYZ-IBD-like frame: 60
steel bolts dropped into bin_picking.yaml's tote under one area light, 1440 x 1080, two views of
which view 0 is measured; Cycles gets the tote's own mesh and material from Run.fixtures).
Writes DIR/equal_error_SCENE.json and DIR/equal_error_SCENE.png; `--combine` reads several such
JSONs and writes DIR/equal_error_scenes.png (their parts' curves side by side) and prints a table.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "cycles"))
import compare_with_cycles as cwc  # noqa: E402

WORKCELL_VIEWS = [30, 120, 210, 300]  # yaw (deg) of the views one cadsynth run renders
# pbr_demo's, per scene: a scene's frames after the first overlap their writing with the next
# frame's rendering, as in a user's run of many views (the error is view 0's, yaw 0).
PBR_DEMO_VIEWS = [0, 90, 180, 270]
# tote's: an XYZ-IBD-like frame, 60 steel bolts dropped into a tote (recipes/bin_picking.yaml's
# pile) under one area light, seen from above at 1440 x 1080; view 0 is measured.
TOTE_VIEWS = [0, 90]
TOTE = {"scenes": "[{name: pile, parts: [{family: hex_bolt, params: {size: M16, length: 60 mm}}], "
                  "layout: pile, copies: 60, seed: 1, container: {type: tote, "
                  "inner: [355 mm, 265 mm], height: 150 mm, wall: 6 mm, floor: 6 mm, "
                  "corner_radius: 15 mm, color: [0.15, 0.3, 0.6]}, "
                  "physics: {density: 7850, friction: 0.7, restitution: 0.1}}]",
        "camera": (1440, 1080, 1800.0), "view": (0, 85, 0.85)}
TOTE_MATERIAL = [("hex_bolt*", {"base_color": [0.56, 0.57, 0.58], "metallic": 1.0,
                                "roughness": 0.3, "specular": 0.5})]
TOTE_LIGHTS = [{"type": "rect", "position_m": [0.15, -0.1, 1.2], "target_m": [0, 0, 0],
                "size_m": [0.6, 0.3], "power": 25}]
TOTE_WORLD = {"color": [0.3, 0.3, 0.3], "strength": 0.1}


def read_exr(path):
    import cadsynth  # the build's Python module (PYTHONPATH=build/python)
    return cadsynth.read_image(path).astype(np.float64)


def read_png(path):
    import cadsynth
    return cadsynth.read_image(path)


def display(linear, exposure, filmic):
    """cadsynth's display transform (render/path_tracer.h DisplayValue) of exposed radiance."""
    x = np.maximum(linear * 2.0 ** exposure, 0.0)
    if filmic:
        x = np.minimum(1.0, x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14))
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def regions(frame_dir, im_id, shape):
    """The frame's parts' pixels and their edge pixels, from mask_visib/."""
    ids = np.zeros(shape, dtype=np.int32)
    masks = sorted(m for m in os.listdir(os.path.join(frame_dir, "mask_visib"))
                   if m.startswith(f"{im_id:06d}_"))
    for k, m in enumerate(masks):
        ids[read_png(os.path.join(frame_dir, "mask_visib", m)) > 0] = k + 1
    parts = ids > 0
    edge = np.zeros_like(parts)
    edge[:, 1:] |= ids[:, 1:] != ids[:, :-1]
    edge[:, :-1] |= ids[:, 1:] != ids[:, :-1]
    edge[1:, :] |= ids[1:, :] != ids[:-1, :]
    edge[:-1, :] |= ids[1:, :] != ids[:-1, :]
    return {"all": np.ones(shape, dtype=bool), "parts": parts, "edges": edge & parts}


def time_to(points, target):
    """Seconds to reach `target` error on a curve of (seconds, error) points, interpolated
    log-log between the first pair that brackets it; None if never reached."""
    points = sorted(points)
    best = None
    for (t0, e0), (t1, e1) in zip(points, points[1:]):
        if e0 > target >= e1 and e0 > 0 and e1 > 0:
            f = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            best = math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
            break
    if best is None and points and points[0][1] <= target:
        best = points[0][0]  # the cheapest point is already there
    return best


class Scene:
    def __init__(self, name, out, cadsynth_bin):
        self.name, self.out, self.bin = name, out, cadsynth_bin
        self.fast_seconds = None  # per frame, the same views in the fast mode
        self.min_samples = 0  # adaptive sampling's (0: cadsynth's default)
        self.denoise = False
        self.denoiser = "network"
        self._fixtures = None  # fixtures(), once
        self._looks = {}  # look(), once
        # Both renderers' light-path settings (Filter Glossy, the glossy bounce limit, Clamp
        # Indirect: cwc.LIGHT_PATHS), their references' too.
        self.light_paths = dict(cwc.LIGHT_PATHS)
        self.background_samples = 0  # render.background_samples of the curves (0: off)
        self.references_from = []  # earlier OUT folders whose references may be taken
        if name == "workcell":
            case = cwc.CASES["workcell"]
            self.material, self.lights, self.world = case[0], case[1], case[2]
            self.shown = dict(case[5])
            self.exposure, self.filmic = 0.0, False
        elif name == "tote":
            self.material, self.lights, self.world = TOTE_MATERIAL, TOTE_LIGHTS, TOTE_WORLD
            self.shown = dict(TOTE)
            self.exposure, self.filmic = 0.0, True
        elif name == "pbr_demo":
            self.exposure, self.filmic = 0.0, True
        else:
            raise SystemExit(f"unknown scene '{name}': workcell, tote or pbr_demo")

    def look(self, sid):
        """Scene sid's look in the pbr mode (Run.look), once per scene."""
        if sid not in self._looks:
            import cadsynth
            run = cadsynth.Recipe.from_yaml(self.recipe(1, 0.0, 0), f"{self.name}.yaml").prepare()
            self._looks.update({i: run.look(i) for i in range(run.scenes)})
        return self._looks[sid]

    def views(self):
        return {"workcell": WORKCELL_VIEWS, "tote": TOTE_VIEWS}.get(self.name, PBR_DEMO_VIEWS)

    def fixtures(self):
        """The scene's fixtures for Cycles (the tote), each written as a PLY in the world frame
        with its material: cadsynth's own geometry and pbr material (Run.fixtures)."""
        if self.name != "tote":
            return []
        if self._fixtures is not None:
            return self._fixtures
        import cadsynth
        run = cadsynth.Recipe.from_yaml(self.recipe(1, 0.0, 0), "tote.yaml").prepare()
        out = []
        for i, f in enumerate(run.fixtures(0)):
            if f["material"]["textured"]:
                sys.exit(f"fixture {f['name']}: textured; the Cycles rebuild has no textures")
            if len(f["normals"]) != len(f["vertices"]):
                sys.exit(f"fixture {f['name']}: no normals; the Cycles rebuild takes cadsynth's")
            path = os.path.join(self.out, f"fixture{i}.ply")
            write_ply(path, f["vertices"], f["normals"], f["triangles"])
            out.append({"ply": path, "material": f["material"]})
        self._fixtures = out
        return out

    def recipe(self, samples, threshold, seed, mode="pbr", views=None, background=0):
        render = (f"render: {{mode: {mode}, samples: {samples}, noise_threshold: {threshold}, "
                  f"denoise: {'true' if self.denoise and mode == 'pbr' else 'false'}, "
                  f"denoiser: {self.denoiser}, "
                  f"min_samples: {min(self.min_samples, samples) if threshold else 0}, "
                  + (f"background_samples: {min(background, samples)}, " if background else "") +
                  f"bounces: 3, hdr: true, view: {'filmic' if self.filmic else 'standard'}, "
                  f"{cwc.light_paths_yaml(self.light_paths)}, seed: {seed}}}")
        if self.name in ("workcell", "tote"):
            text = cwc.recipe(self.material, self.lights, self.world, samples, self.shown)
            text = re.sub(r"^render: .*$", render, text, flags=re.M)
            yaw = ", ".join(str(y) for y in (views or self.views()))
            pitch, radius = self.shown["view"][1], self.shown["view"][2]
            text = re.sub(r"^sweep: .*$", f"sweep: {{yaw: [{yaw}], pitch: [{pitch}], "
                                          f"radius: [{radius} m]}}", text, flags=re.M)
            return text
        lines = []
        skip = False
        for line in open(os.path.join(ROOT, "recipes", "pbr_demo.yaml")):
            if line.startswith(("sweep:", "render:", "output:")):
                skip = True
                continue
            if skip and line.startswith(" "):
                continue
            skip = False
            lines.append(line)
        yaw = ", ".join(str(y) for y in (views or PBR_DEMO_VIEWS))
        return ("".join(lines) + f"sweep: {{yaw: [{yaw}], pitch: [40], radius: [0.65 m]}}\n"
                + render
                + "\noutput: {formats: [bop], model_points: 0}\n")

    def frames(self):
        """(folder, im_id) of the frames whose error is measured."""
        if self.name in ("workcell", "tote"):
            return [("000000", 0)]
        return [("000000", 0), ("000001", 0), ("000002", 0)]

    def run(self, tag, samples, threshold, seed=0, mode="pbr", views=None, reuse=False):
        """The dataset and its seconds per frame: the whole process's, and the path tracer's
        share (less the same run in the fast mode: the start-up, the labels and the writing)."""
        path = os.path.join(self.out, f"{self.name}_{tag}.yaml")
        # (The reference and the fast run sample every pixel alike.)
        background = self.background_samples if mode == "pbr" and tag != "reference" else 0
        text = self.recipe(samples, threshold, seed, mode, views, background)
        dataset = os.path.join(self.out, f"{self.name}_{tag}")
        if tag == "reference":
            for earlier in self.references_from:
                old = os.path.join(earlier, f"{self.name}_reference")
                if (os.path.isdir(os.path.join(old, "train")) and os.path.exists(old + ".yaml")
                        and same_recipe(open(old + ".yaml").read(), text)):
                    if os.path.abspath(old) != os.path.abspath(dataset):
                        shutil.rmtree(dataset, ignore_errors=True)
                        shutil.copytree(old, dataset, copy_function=link_or_copy)
                        with open(path, "w") as f:
                            f.write(text)
                    print(f"{self.name}: cadsynth reference taken from {old}")
                    return dataset, float("nan"), float("nan")
        # Reused only when made from the same recipe (samples, light paths, ...).
        if (reuse and os.path.isdir(os.path.join(dataset, "train")) and os.path.exists(path)
                and open(path).read() == text):
            return dataset, float("nan"), float("nan")
        with open(path, "w") as f:
            f.write(text)
        start = time.monotonic()
        done = subprocess.run([self.bin, "generate", path, "-o", dataset, "--overwrite",
                               "--quiet"], capture_output=True, text=True)
        seconds = time.monotonic() - start
        if done.returncode != 0:
            sys.exit(f"cadsynth failed on {path}: {done.stderr}")
        count = sum(len(os.listdir(os.path.join(dataset, "train", s, "rgb")))
                    for s in os.listdir(os.path.join(dataset, "train")))
        if mode == "fast":
            return dataset, seconds / count
        if self.fast_seconds is None:
            self.fast_seconds = sorted(self.run("fast", 1, 0.0, mode="fast")[1]
                                       for _ in range(3))[1]
        return dataset, seconds / count, max(seconds / count - self.fast_seconds, 1e-3)


def same_recipe(a, b):
    """Whether two recipe texts describe the same run: the same YAML, comments and the spelling
    of numbers aside (`1` and `1.0`)."""
    import yaml  # python3-yaml, only here
    return yaml.safe_load(a) == yaml.safe_load(b)


# Material keys that specs gained after earlier references were made, at the values
# cycles_scene.py takes when a key is absent: a spec with them builds the same Cycles scene.
MATERIAL_DEFAULTS = {"distribution": "ggx", "tangent": "radial", "base_from_part": True,
                     "texture": None}


def without_defaults(value):
    """`value` (a spec) without MATERIAL_DEFAULTS' keys where they have their default values."""
    if isinstance(value, list):
        return [without_defaults(v) for v in value]
    if isinstance(value, dict):
        return {k: without_defaults(v) for k, v in value.items()
                if not (k in MATERIAL_DEFAULTS and v == MATERIAL_DEFAULTS[k])}
    return value


def link_or_copy(src, dst):
    """A hard link where the file system allows one (references are large), else a copy."""
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def write_ply(path, vertices, normals, triangles):
    """cadsynth's binary PLY layout (tools/cycles/cycles_scene.py read_ply): float x y z nx ny nz,
    uchar-counted int faces."""
    v = np.concatenate([vertices, normals], axis=1).astype("<f4")
    f = np.zeros(len(triangles), dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]))
    f["n"], f["i"] = 3, triangles
    with open(path, "wb") as out:
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
                   + "".join(f"property float {p}\n" for p in ("x", "y", "z", "nx", "ny", "nz"))
                   + f"element face {len(f)}\nproperty list uchar int vertex_indices\n"
                   "end_header\n").encode("ascii"))
        out.write(v.tobytes())
        out.write(f.tobytes())


def cycles_run(scene, dataset, samples, threshold, seed, blender, tag, sid=0, reuse=False):
    """Renders frame (scene sid, image 0) of `dataset` in Cycles: its EXR and render seconds
    (with `reuse`, the EXR already there when it was made from the same spec, and NaN)."""
    camera = json.load(open(os.path.join(dataset, "camera.json")))
    spec = {"dataset": dataset, "scene_id": sid, "im_id": 0, "width": camera["width"],
            "height": camera["height"], "samples": samples, "bounces": 3, "seed": seed,
            "adaptive_threshold": threshold,
            "output": os.path.join(scene.out, f"cycles_{tag}.exr"), **scene.light_paths}
    if scene.name == "pbr_demo":
        # Everything from cadsynth's own look of the scene (Run.look): each instance's material
        # (textures rebuilt in kind from Cycles' nodes), the floor's, the lights and the world.
        spec.update(cwc.spec_from_look(scene.look(sid)))
    else:
        spec.update({"part_materials": cwc.rules(scene.material), "floor_material": cwc.LAMBERT,
                     "lights": [cwc.blender_light(l) for l in scene.lights],
                     "world": scene.world, "fixtures": scene.fixtures()})
    spec_path = os.path.join(scene.out, f"cycles_{tag}.json")
    text = json.dumps(spec, indent=1)
    if tag.startswith("reference"):
        # An earlier folder's reference made from the same spec, its paths aside (one-frame
        # scenes' references were once called cycles_reference).
        def scene_of(s, folder):
            return without_defaults(json.loads(
                json.dumps({k: v for k, v in s.items() if k not in ("dataset", "output")})
                .replace(json.dumps(folder)[1:-1], "OUT")))
        for earlier in scene.references_from:
            for name in (f"cycles_{tag}", "cycles_reference"):
                old = os.path.join(earlier, name)
                if (os.path.exists(old + ".json") and os.path.exists(old + ".exr")
                        and scene_of(json.load(open(old + ".json")), earlier)
                        == scene_of(spec, scene.out)
                        and (name != "cycles_reference" or len(scene.frames()) == 1)):
                    if os.path.abspath(old + ".exr") != os.path.abspath(spec["output"]):
                        if os.path.exists(spec["output"]):
                            os.remove(spec["output"])
                        link_or_copy(old + ".exr", spec["output"])
                        with open(spec_path, "w") as f:
                            f.write(text)
                    print(f"  Cycles reference taken from {old}.exr")
                    return spec["output"], float("nan")
    if (reuse and os.path.exists(spec["output"]) and os.path.exists(spec_path)
            and open(spec_path).read() == text):
        return spec["output"], float("nan")
    with open(spec_path, "w") as f:
        f.write(text)
    log = os.path.join(scene.out, f"cycles_{tag}.log")
    with open(log, "w") as f:
        done = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1",
                               "--python", os.path.join(ROOT, "tools", "cycles",
                                                        "cycles_scene.py"), "--", spec_path],
                              stdout=f, stderr=f, env=cwc.blender_env())
    if done.returncode != 0:
        sys.exit(f"blender failed: see {log}")
    times = re.findall(r"Time: (\d+):(\d+\.\d+)", open(log).read())
    return spec["output"], 60 * int(times[-1][0]) + float(times[-1][1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cadsynth", default=os.path.join(ROOT, "build", "tools", "cadsynth"))
    parser.add_argument("--blender", default="blender")
    parser.add_argument("--scene", default="workcell")
    parser.add_argument("--renderers", default="cadsynth,cycles")
    parser.add_argument("--reference-samples", type=int, default=4096)
    parser.add_argument("--samples", default="1,2,4,8,16,32,64,128",
                        help="fixed sample counts (no adaptive sampling)")
    parser.add_argument("--thresholds", default="0.04,0.02,0.01,0.005,0.0025",
                        help="cadsynth's render.noise_threshold values (samples: --max-samples)")
    parser.add_argument("--cycles-thresholds", default="0.2,0.1,0.05,0.02,0.01",
                        help="Cycles' adaptive_threshold values (samples: --max-samples)")
    parser.add_argument("--max-samples", type=int, default=1024)
    parser.add_argument("--min-samples", type=int, default=0,
                        help="cadsynth's render.min_samples for the adaptive runs (0: default)")
    parser.add_argument("--targets", default="0.1,0.05")
    parser.add_argument("--denoise", action="store_true",
                        help="also cadsynth's fixed sample counts and thresholds with render.denoise")
    parser.add_argument("--denoisers", default="filter",
                        help="with --denoise: render.denoiser values, each its own curves")
    parser.add_argument("--filter-glossy", type=float, default=0.0,
                        help="both renderers' Filter Glossy (render.filter_glossy, Cycles' "
                             "blur_glossy; Blender's default 1): less noise from glossy caustics "
                             "for some bias; each renderer's reference has it too")
    parser.add_argument("--glossy-bounces", type=int, default=64,
                        help="both renderers' glossy bounce limit (render.glossy_bounces, Cycles' "
                             "glossy_bounces; BlenderProc sets 0)")
    parser.add_argument("--clamp-indirect", type=float, default=0.0,
                        help="both renderers' Clamp Indirect (render.clamp_indirect, Cycles' "
                             "sample_clamp_indirect; Blender's default 10)")
    parser.add_argument("--background-samples", type=int, default=0,
                        help="cadsynth's curves again with render.background_samples N: the "
                             "samples as set where a 4 x 4 tile shows a part, N elsewhere")
    parser.add_argument("--reuse-reference", action="store_true",
                        help="keep DIR's references when they are there, made from the same "
                             "recipe (cadsynth) and spec (Cycles)")
    parser.add_argument("--references-only", action="store_true",
                        help="render the references and stop (their time is not measured: "
                             "the curves can then run on a quiet machine with "
                             "--reuse-reference)")
    parser.add_argument("--references-from", default="",
                        help="earlier OUT folders (comma-separated) whose references are taken, "
                             "hard-linked, where made from the same recipe (cadsynth: the same "
                             "YAML, comments and the spelling of numbers aside) and spec (Cycles: "
                             "the same, its paths aside)")
    parser.add_argument("--cycles-from", help="take the Cycles curves from an earlier JSON")
    parser.add_argument("--combine", help="earlier runs' JSONs (comma-separated): print their "
                                          "times to --targets on the parts and draw their curves "
                                          "side by side in DIR/equal_error_scenes.png; no runs")
    parser.add_argument("--out", default="equal_error")
    args = parser.parse_args()
    if args.combine:
        return combine(args.combine.split(","), list(map(float, args.targets.split(","))),
                       args.out)
    for d in args.references_from.split(","):
        if d and not os.path.isdir(d):
            sys.exit(f"--references-from: {d}: no such folder")
    os.makedirs(args.out, exist_ok=True)
    out = os.path.abspath(args.out)
    scene = Scene(args.scene, out, args.cadsynth)
    scene.min_samples = args.min_samples
    scene.references_from = [os.path.abspath(d) for d in args.references_from.split(",") if d]
    scene.light_paths = {"filter_glossy": args.filter_glossy,
                         "glossy_bounces": args.glossy_bounces,
                         "clamp_indirect": args.clamp_indirect}
    renderers = args.renderers.split(",")
    result = {"scene": args.scene, "reference_samples": args.reference_samples,
              **scene.light_paths,
              "background_samples": args.background_samples, "curves": {}}

    # cadsynth: the reference (another seed), then the curves.
    first_view = scene.views()[:1]
    ref_dataset, ref_seconds, _ = scene.run("reference", args.reference_samples, 0.0, seed=7,
                                            views=first_view, reuse=args.reuse_reference)
    masks = {}
    refs = {}
    for folder, im in scene.frames():
        frame_dir = os.path.join(ref_dataset, "train", folder)
        linear = read_exr(os.path.join(frame_dir, "rgb_hdr", f"{im:06d}.exr"))
        refs[(folder, im)] = display(linear, scene.exposure, scene.filmic)
        masks[(folder, im)] = regions(frame_dir, im, linear.shape[:2])
    print(f"{args.scene}: cadsynth reference {args.reference_samples} spp, "
          f"{ref_seconds:.1f} s per frame")
    if args.references_only and "cycles" not in renderers:
        return

    def errors(images, refs=refs):
        """Pooled over the measured frames: RMSE over their regions' values / mean value."""
        e = {}
        for region in ("all", "parts", "edges"):
            num = den = total = 0.0
            for key, x in images.items():
                m = masks[key][region]
                d = x[m] - refs[key][m]
                num += float(np.sum(d * d))
                den += float(np.sum(refs[key][m]))
                total += float(m.sum() * 3)
            e[region] = math.sqrt(num / total) / (den / total) if total else float("nan")
        return e

    def cadsynth_point(tag, samples, threshold):
        dataset, whole, seconds = scene.run(tag, samples, threshold)
        images = {}
        for folder, im in scene.frames():
            linear = read_exr(os.path.join(dataset, "train", folder, "rgb_hdr", f"{im:06d}.exr"))
            images[(folder, im)] = display(linear, scene.exposure, scene.filmic)
        point = {"samples": samples, "threshold": threshold, "seconds": seconds,
                 "whole_seconds": whole, **errors(images)}
        print(f"  cadsynth {tag:>12s}: {seconds:7.3f} s/frame ({whole:.3f} s whole)  "
              f"rel. RMSE all {point['all']:.4f}"
              f"  parts {point['parts']:.4f}  edges {point['edges']:.4f}", flush=True)
        return point

    if "cadsynth" in renderers and not args.references_only:
        # Without render.background_samples, then (--background-samples N) with it: the parts'
        # samples as set, N paths in the tiles that show no part.
        for background in sorted({0, args.background_samples}):
            scene.background_samples = background
            suffix = f", background {background}" if background else ""
            bg = f"bg{background}" if background else ""
            result["curves"]["cadsynth" + suffix] = [
                cadsynth_point(f"spp{n}{bg}", n, 0.0) for n in map(int, args.samples.split(","))]
            result["curves"]["cadsynth adaptive" + suffix] = [
                cadsynth_point(f"t{t}{bg}", args.max_samples, float(t))
                for t in args.thresholds.split(",") if t]
            for denoiser in (args.denoisers.split(",") if args.denoise else []):
                scene.denoise, scene.denoiser = True, denoiser
                result["curves"][f"cadsynth denoised ({denoiser}){suffix}"] = [
                    cadsynth_point(f"{denoiser}{n}{bg}", n, 0.0)
                    for n in map(int, args.samples.split(","))]
                if args.thresholds:
                    result["curves"][f"cadsynth adaptive denoised ({denoiser}){suffix}"] = [
                        cadsynth_point(f"{denoiser}t{t}{bg}", args.max_samples, float(t))
                        for t in args.thresholds.split(",")]
                scene.denoise = False
        scene.background_samples = 0
    if args.cycles_from:
        earlier = json.load(open(args.cycles_from))
        for name in ("Cycles", "Cycles adaptive"):
            result["curves"][name] = earlier["curves"][name]

    if "cycles" in renderers:
        # Each measured frame rebuilt from cadsynth's reference dataset (the same poses and
        # camera), its own Cycles reference at --reference-samples with another seed.
        cycles_refs = {}
        ref_t = 0.0
        for folder, im in scene.frames():
            ref_path, t = cycles_run(scene, ref_dataset, args.reference_samples, 0.0, 7,
                                     args.blender, f"reference_{folder}", int(folder),
                                     reuse=args.reuse_reference)
            ref_t += t
            cycles_refs[(folder, im)] = display(read_exr(ref_path), scene.exposure, scene.filmic)
        print(f"  Cycles reference {args.reference_samples} spp: "
              f"{ref_t / len(cycles_refs):.1f} s per frame")
        # How alike the two scenes look: the mean displayed value over the parts, each
        # renderer's reference (pbr_demo's textures are rebuilt in kind, not copied).
        result["reference_parts_mean"] = {
            name: float(np.mean([np.mean(r[key][masks[key]["parts"]]) for key in r]))
            for name, r in (("cadsynth", refs), ("Cycles", cycles_refs))}
        print(f"  parts' mean value in the references: {result['reference_parts_mean']}")
        if args.references_only:
            return

        def cycles_point(tag, samples, threshold):
            images, seconds = {}, 0.0
            for folder, im in scene.frames():
                path, t = cycles_run(scene, ref_dataset, samples, threshold, 0, args.blender,
                                     f"{tag}_{folder}", int(folder))
                seconds += t / len(scene.frames())
                images[(folder, im)] = display(read_exr(path), scene.exposure, scene.filmic)
            point = {"samples": samples, "threshold": threshold, "seconds": seconds,
                     **errors(images, cycles_refs)}
            print(f"  Cycles   {tag:>12s}: {seconds:7.3f} s/frame  rel. RMSE all "
                  f"{point['all']:.4f}  parts {point['parts']:.4f}  edges {point['edges']:.4f}",
                  flush=True)
            return point

        result["curves"]["Cycles"] = [cycles_point(f"spp{n}", n, 0.0)
                                      for n in map(int, args.samples.split(","))]
        result["curves"]["Cycles adaptive"] = [
            cycles_point(f"t{t}", args.max_samples, float(t))
            for t in args.cycles_thresholds.split(",") if t]

    result["time_to"] = {}
    for target in map(float, args.targets.split(",")):
        row = {}
        for name, points in result["curves"].items():
            for region in ("all", "parts"):
                row[f"{name} {region}"] = time_to([(p["seconds"], p[region]) for p in points],
                                                  target)
        result["time_to"][str(target)] = row
        print(f"time to rel. RMSE {target}: " + ", ".join(
            f"{k} {v:.3f} s" if v else f"{k} not reached" for k, v in row.items()))
    with open(os.path.join(out, f"equal_error_{args.scene}.json"), "w") as f:
        json.dump(result, f, indent=1)
    plot(result, os.path.join(out, f"equal_error_{args.scene}.png"))


CURVE_STYLES = {"cadsynth": "C0--", "cadsynth adaptive": "C0-o",
                "cadsynth denoised (network)": "C2-s",
                "cadsynth adaptive denoised (network)": "C2-o",
                "cadsynth denoised (filter)": "C1-s", "cadsynth adaptive denoised (filter)": "C1-o",
                "Cycles": "C3--", "Cycles adaptive": "C3-o"}


def draw_curves(ax, result, region):
    """Every curve of `result`, error on `region` against seconds, log-log, on `ax`."""
    for name, points in result["curves"].items():
        points = sorted(points, key=lambda p: p["seconds"])
        base = name.split(", background")[0]
        style = CURVE_STYLES.get(base, "C7-")
        if base != name:  # render.background_samples: the same colour, dotted, triangles
            style = style[:2] + ":" + {"s": "^", "o": "v"}.get(style[-1], "")
        ax.loglog([p["seconds"] for p in points], [p[region] for p in points],
                  style, label=name, markersize=4)
    for target in (0.05, 0.1):
        ax.axhline(target, color="grey", linewidth=0.5)
    ax.set_xlabel("seconds per frame (2 cores)")
    ax.set_ylabel(f"relative RMSE, {region} pixels")
    ax.grid(True, which="both", linewidth=0.2)


def light_paths_title(result):
    paths = []
    if result.get("filter_glossy", 0.0):
        paths.append(f"Filter Glossy {result['filter_glossy']:g}")
    if result.get("glossy_bounces", 64) < 3:
        paths.append(f"glossy bounces {result['glossy_bounces']}")
    if result.get("clamp_indirect", 0.0):
        paths.append(f"Clamp Indirect {result['clamp_indirect']:g}")
    return f" ({', '.join(paths)})" if paths else ""


def combine(paths, targets, out):
    """Several scenes' JSONs: a table of each one's time to the targets on the parts (cadsynth's
    fastest curve against Cycles' fixed and adaptive sampling) and their parts' curves side by
    side in OUT/equal_error_scenes.png."""
    for p in paths:
        if not os.path.isfile(p):
            sys.exit(f"--combine: {p}: no such file (an earlier run's equal_error_SCENE.json)")
    results = [json.load(open(p)) for p in paths]
    print("| scene | parts' error | cadsynth (its fastest curve) | Cycles fixed | "
          "Cycles adaptive |")
    print("|---|---|---|---|---|")
    for r in results:
        for target in targets:
            times = {name: time_to([(p["seconds"], p["parts"]) for p in points], target)
                     for name, points in r["curves"].items()}
            # "at most": the curve's cheapest point is already below the target.
            at_most = {name: bool(points) and min(points, key=lambda p: p["seconds"])["parts"]
                       <= target for name, points in r["curves"].items()}
            mine = {n: t for n, t in times.items() if n.startswith("cadsynth") and t}
            cells = []
            if mine:
                name = min(mine, key=mine.get)
                best = mine[name]
                kind = name.removeprefix("cadsynth")
                kind = "fixed" + kind if kind.startswith(",") or not kind else kind.strip()
                cells.append(f"{'at most ' if at_most[name] else ''}{best:.3f} s ({kind})")
            else:
                best = None
                cells.append("not reached")
            for cycles in ("Cycles", "Cycles adaptive"):
                t = times.get(cycles)
                cells.append("not reached" if not t else
                             f"{'at most ' if at_most[cycles] else ''}{t:.3f} s"
                             + (f" ({t / best:.1f}x)" if best else ""))
            print(f"| {r['scene']}{light_paths_title(r)} | {target:g} | " + " | ".join(cells)
                  + " |")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(results), figsize=(5 * len(results), 5.5))
    for ax, r in zip(np.atleast_1d(axes), results):
        draw_curves(ax, r, "parts")
        ax.set_title(f"{r['scene']}: parts" + light_paths_title(r), fontsize=9)
    labels = {}
    for ax in np.atleast_1d(axes):
        for h, label in zip(*ax.get_legend_handles_labels()):
            labels.setdefault(label, h)
    rows = (len(labels) + 3) // 4
    fig.legend(list(labels.values()), list(labels), loc="lower center", ncol=4, fontsize=7.5)
    fig.tight_layout(rect=(0, 0.05 * rows, 1, 1))
    os.makedirs(out, exist_ok=True)
    fig.savefig(os.path.join(out, "equal_error_scenes.png"), dpi=100)


def plot(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 5.5 if len(result["curves"]) > 8 else 4.5))
    for ax, region in zip(axes, ("parts", "all")):
        draw_curves(ax, result, region)
        ax.set_title(f"{result['scene']}: {region}" + light_paths_title(result), fontsize=9)
    # One legend for both, below them (inside, it hid the curves).
    handles, labels = axes[0].get_legend_handles_labels()
    rows = (len(labels) + 2) // 3
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=7.5)
    fig.tight_layout(rect=(0, 0.045 * rows, 1, 1))
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
