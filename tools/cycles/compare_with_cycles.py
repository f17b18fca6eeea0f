#!/usr/bin/env python3
"""Renders the same small scenes with cadsynth's physically based mode and with Blender Cycles and
compares their linear radiance, to check cadsynth's light transport against an independent
renderer (issue 15). Needs Debian's `blender` package (3.4), which cadsynth itself does not use:

    apt-get install blender
    tools/cycles/compare_with_cycles.py [--samples 1024] [--cases point,spot,...] [--out DIR]

Most cases are a sphere of 40 mm radius (a mesh this script writes) resting on the floor, seen
from 0.5 m, 160 x 120 pixels (its row layout rests it tilted, so its model z axis, about which
Blender's default tangent turns, is not the world's), lit by one kind of light or the world, with one material on the sphere and a
Lambert floor (albedo 0.8). cadsynth renders it (`render.hdr`), then tools/cycles/cycles_scene.py
rebuilds that very frame in Cycles from the dataset (the mesh cadsynth traced, its normals, its
poses and camera) and the case's lights and materials in Blender's units, renders it at the same
samples and bounces and compares: the ratio of mean radiance cadsynth / Cycles over the sphere's
pixels, the floor's and all, and the relative difference of 8 x 8 pixel blocks (median, 90th
and 99th percentile), and the seconds each took (cadsynth's whole run; Cycles' render without starting
Blender), and the sub-pixel shift that best carries Cycles' image onto cadsynth's (a
Lucas-Kanade step on both clipped at Cycles' 99th percentile: within 0.03 px when both see the
same rays, about 0.5 px for a half-pixel convention error); OUT/CASE_sheet.png shows cadsynth | Cycles | |difference| x 10. Exit status 1 when a strict case's ratio (the parts', the floor's, all, or that of any
instance seen in at least --part-pixels pixels) leaves [1 - tol, 1 + tol] (--tolerance, 0.03)
or its blocks' 99th percentile exceeds --block-tolerance (0.1: a shadow in the wrong place) or
its shift exceeds --shift-tolerance (0.1 px).
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

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

LAMBERT = {"base_color": [0.8, 0.8, 0.8], "metallic": 0.0, "roughness": 0.5, "specular": 0.0,
           "lambert": True}
METAL = {"base_color": [0.9, 0.7, 0.5], "metallic": 1.0, "roughness": 0.3, "specular": 0.5}
ROUGH_METAL = {"base_color": [0.8, 0.8, 0.8], "metallic": 1.0, "roughness": 0.8, "specular": 0.5}
WHITE_METAL = {"base_color": [1.0, 1.0, 1.0], "metallic": 1.0, "roughness": 0.3, "specular": 0.5}
WHITE_ROUGH_METAL = dict(WHITE_METAL, roughness=0.8)
PLASTIC = {"base_color": [0.2, 0.4, 0.8], "metallic": 0.0, "roughness": 0.4, "specular": 0.5}
BLACK_WORLD = {"color": [0.0, 0.0, 0.0], "strength": 0.0}

# What a case shows: the parts (a recipe's parts and scene), the camera (width, height, f) and
# its view (yaw, pitch in degrees, radius in m).
SPHERE = {"parts": "[{file: sphere.obj, unit: mm}]", "scene": "{layout: row}",
          "camera": (160, 120, 131.25), "view": (30, 40, 0.5)}
WORKCELL = {"parts": "\n  - {family: spur_gear, params: {teeth: 24, module: 2, face_width: 12 mm, "
                     "bore: 10 mm}}\n  - {family: hex_bolt, params: {size: M12, length: 50 mm}}"
                     "\n  - {family: hex_nut, params: {size: M16}}\n  - {family: round_peg, "
                     "params: {diameter: 20 mm, length: 50 mm}}\n  - {family: washer, params: "
                     "{size: M16}}",
            "scene": "{layout: clutter, pose: random, copies: 1, radius: 70 mm, gap: 5 mm, "
                     "seed: 3}",
            "camera": (320, 240, 300.0), "view": (30, 55, 0.4)}

GLOSSY = {"parts": "\n  - {family: round_peg, params: {diameter: 16 mm, length: 50 mm}}"
                   "\n  - {family: stepped_shaft}\n  - {family: hex_bolt, params: {size: M12, "
                   "length: 50 mm}}",
          "scene": "{layout: clutter, pose: random, copies: 1, radius: 80 mm, gap: 5 mm, seed: 3}",
          "camera": (320, 240, 300.0), "view": (30, 55, 0.35)}
GLOSSY_METAL = dict(WHITE_METAL, roughness=0.25)
# The default job's three scenes (the paper's demo sets: a planetary gearbox, a slider-crank
# mechanism, the assembly-benchmark set), one view of each as the Kinect v1 sees it.
DEFAULT_JOB = {"scenes": "default", "camera": (640, 480, 525.0), "view": (30, 45, 0.65),
               "frames": [0, 1, 2]}
GLOSSY_LIGHTS = [{"type": "disc", "position_m": [0.15, 0.2, 0.45], "target_m": [0, 0, 0],
                  "radius_m": 0.1, "power": 40}]
GLOSSY_WORLD = {"color": [0.3, 0.3, 0.3], "strength": 1.0}

RECT = {"type": "rect", "position_m": [-0.2, 0.1, 0.5], "target_m": [0, 0, 0],
        "size_m": [0.4, 0.2], "power": 60}
SUN = {"type": "sun", "direction": [-0.4, 0.3, -1], "strength": 3, "angle_deg": 5}

# name: (sphere material, lights (SI units, Blender's), world, strict, note). Strict cases use only
# what cadsynth and Cycles 3.4 model alike (every light's units, Lambert, GGX with F = 1, the
# world, bounces, the lens, the default tangent) and must agree within --tolerance (a number
# instead of True: their own block tolerance; the lens's blur moves the blocks' p99 by 0.03
# against 0.002-0.005 between the renderers, a tangent along x instead of Blender's default to
# 0.19 against 0.03 at 128 samples); the others show where Blender 3.4's models differ from Blender 4's, which cadsynth
# follows, and are reported only.
CASES = {
    "point": (LAMBERT, [{"type": "point", "position_m": [0.2, -0.1, 0.6], "power": 100}],
              BLACK_WORLD, True, "point light 100 W; Lambert"),
    "rect": (WHITE_METAL, [RECT], BLACK_WORLD, True,
             "rect light 0.4 x 0.2 m, 60 W; white metal (F = 1: GGX alone), roughness 0.3"),
    "disc": (WHITE_METAL, [{"type": "disc", "position_m": [0.15, 0.2, 0.45],
                            "target_m": [0, 0, 0], "radius_m": 0.15, "power": 40}],
             BLACK_WORLD, True, "disc light r 0.15 m, 40 W; white metal, roughness 0.3"),
    "sun": (WHITE_METAL, [SUN], BLACK_WORLD, True, "sun 3 W/m2, 5 deg; white metal, roughness 0.3"),
    "world": (LAMBERT, [], {"color": [0.5, 0.6, 0.7], "strength": 1.0}, True,
              "uniform world only; Lambert (occlusion, inter-reflection)"),
    "image": (WHITE_METAL, [], {"image": "sky.hdr", "strength": 1.0, "rotation_deg": 0}, True,
              "equirectangular world image (a sun-like patch: the sphere's shadow); white metal"),
    "image90": (WHITE_METAL, [], {"image": "sky.hdr", "strength": 1.0, "rotation_deg": 90}, True,
                "the same image turned 90 deg (Mapping node's Z, BlenderProc's rotation_euler)"),
    "lens": (LAMBERT, [{"type": "point", "position_m": [0.2, -0.1, 0.6], "power": 100}],
             {"color": [0.1, 0.1, 0.1], "strength": 1.0, "lens": [1.4, 0.25]}, 0.015,
             "thin lens f/1.4 focused at 0.25 m (the sphere 0.5 m away: 5 px blur); Lambert"),
    "brushed": (dict(WHITE_METAL, anisotropic=0.8), [RECT], {"color": [0.05, 0.05, 0.05],
                                                             "strength": 1.0}, 0.08,
                "white metal, roughness 0.3, anisotropic 0.8 along Blender's default tangent "
                "(around the part's z axis); from 0.25 m", dict(SPHERE, view=(30, 40, 0.25))),
    "workcell": ([("spur_gear*", {"base_color": [0.56, 0.57, 0.58], "metallic": 1.0,
                                  "roughness": 0.35, "specular": 0.5}),
                  ("hex_bolt*", {"base_color": [0.25, 0.25, 0.27], "metallic": 1.0,
                                 "roughness": 0.45, "specular": 0.5}),
                  ("hex_nut*", {"base_color": [0.91, 0.92, 0.92], "metallic": 1.0,
                                "roughness": 0.25, "specular": 0.5}),
                  ("*", dict(LAMBERT, base_color=[0.6, 0.15, 0.08]))],
                 [dict(RECT, power=80), {"type": "disc", "position_m": [0.3, 0.25, 0.6],
                                         "target_m": [0, 0, 0], "radius_m": 0.1, "power": 30}],
                 {"color": [0.08, 0.08, 0.08], "strength": 1.0}, True,
                 "gear, bolt, nut (steel, dark and bright metal), peg and washer (Lambert), two "
                 "area lights and a grey world: inter-reflections between parts", WORKCELL),
    "glossy": (GLOSSY_METAL, GLOSSY_LIGHTS, GLOSSY_WORLD, False,
               "small curved glossy parts (peg, stepped shaft, bolt), white metal 0.25, one disc "
               "light and a grey world", GLOSSY),
    "glossy_floor": (GLOSSY_METAL, GLOSSY_LIGHTS, GLOSSY_WORLD, False,
                     "the same on a metal floor (grey, roughness 0.3): glossy paths between the "
                     "parts and the floor",
                     dict(GLOSSY, floor=dict(METAL, base_color=[0.6, 0.6, 0.6]))),
    # Filter Glossy (render.filter_glossy, Cycles' blur_glossy) at Blender's default 1: the glossy
    # case's parts and floor with their lobes widened after unlikely bounces in both renderers.
    "filter_glossy": (GLOSSY_METAL, GLOSSY_LIGHTS, GLOSSY_WORLD, True,
                      "the glossy case with Filter Glossy 1 (Blender's default) in both",
                      dict(GLOSSY, filter_glossy=1.0)),
    "default_metal": ([("*_z*", dict(WHITE_METAL, roughness=0.2)),  # the gears
                       ("*peg*", dict(WHITE_METAL, roughness=0.25)),
                       ("*shaft*", dict(WHITE_METAL, roughness=0.3)),
                       ("*", dict(WHITE_METAL, roughness=0.35))], GLOSSY_LIGHTS, GLOSSY_WORLD,
                      False, "the default job's three scenes, every part white metal (roughness "
                      "0.2-0.35) on a grey metal floor (0.3), one disc light and a grey world",
                      dict(DEFAULT_JOB, floor=dict(METAL, base_color=[0.6, 0.6, 0.6]))),
    # The gearbox frame of default_metal alone, strict: the frame where instance and part names
    # differ (the ring gear is part ring_z54), so a rebuild that matched materials by the
    # wrong name is caught. Its own block tolerance: gear teeth at 128 samples reach a p99 of
    # 0.10 from noise (0.05 at 512).
    "gearbox_metal": ([("*_z*", dict(WHITE_METAL, roughness=0.2)), ("*", dict(WHITE_METAL,
                                                                             roughness=0.35))],
                      GLOSSY_LIGHTS, GLOSSY_WORLD, 0.15,
                      "the default job's planetary gearbox, gears white metal 0.2, carrier 0.35, "
                      "on a grey metal floor (0.3), one disc light and a grey world",
                      dict(DEFAULT_JOB, frames=[0],
                           floor=dict(METAL, base_color=[0.6, 0.6, 0.6]))),
    "spot": (LAMBERT, [{"type": "spot", "position_m": [0.1, 0.1, 0.7], "target_m": [0, 0, 0],
                        "power": 300, "spot_size_deg": 40, "spot_blend": 0.3}],
             BLACK_WORLD, False,
             "spot 300 W, 40 deg, blend 0.3; Blender 3 also multiplies by cos to the axis"),
    "metal": (METAL, [RECT], BLACK_WORLD, False,
              "coloured metal, 0.3; Blender 3's metal Fresnel is not Schlick's (Blender 4's)"),
    "rough": (ROUGH_METAL, [SUN], BLACK_WORLD, False,
              "grey metal, 0.8; Blender 3 multiplies the two Smith masking terms, Blender 4 and "
              "cadsynth use the height-correlated form"),
    "multiscatter": (dict(WHITE_ROUGH_METAL, roughness=1.0, multiscatter=True), [SUN],
                     BLACK_WORLD, False, "white metal, 1.0, Multiscatter GGX: Blender 3's is "
                     "Heitz's random walk, cadsynth's Turquin's (Blender 4's)"),
    "plastic": (PLASTIC, [RECT], {"color": [0.05, 0.05, 0.05], "strength": 1.0}, False,
                "Principled dielectric; Blender 3's diffuse is Disney's, not energy-conserving"),
}
# BlenderProc's light paths (render.glossy_bounces 0, Cycles' glossy_bounces; render.clamp_indirect,
# Cycles' Clamp Indirect) on the workcell, strict: every surface there has one lobe in both
# renderers (GGX metals, Lambert plastic and floor), so which bounce is glossy is the same. The
# metals stop mirroring each other; the clamp, far below Blender's default 10 in these units,
# cuts a share of the Lambert parts' and floor's indirect light.
CASES["light_paths"] = CASES["workcell"][:3] + (
    True, "the workcell with glossy bounces 0 and Clamp Indirect 0.05 in both",
    dict(WORKCELL, glossy_bounces=0, clamp_indirect=0.05))


# The light-path settings cadsynth's recipe and the Cycles spec both take by these names
# (render.filter_glossy, render.glossy_bounces, render.clamp_indirect; cycles_scene.py sets
# blur_glossy, glossy_bounces and sample_clamp_indirect from them), and their values when unset.
LIGHT_PATHS = {"filter_glossy": 0.0, "glossy_bounces": 64, "clamp_indirect": 0.0}


def light_paths(shown):
    """The light-path settings of a case's (or a bench scene's) dict, unset ones at LIGHT_PATHS."""
    return {key: shown.get(key, unset) for key, unset in LIGHT_PATHS.items()}


def light_paths_yaml(paths):
    """The settings as flow-mapping entries of a recipe's render: section."""
    return ", ".join(f"{key}: {value:g}" for key, value in paths.items())


def sphere_obj(path, radius=40.0, segments=96, rings=48):
    vertices = [(0.0, 0.0, radius)]
    for i in range(1, rings):
        theta = math.pi * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            vertices.append((radius * math.sin(theta) * math.cos(phi),
                             radius * math.sin(theta) * math.sin(phi), radius * math.cos(theta)))
    vertices.append((0.0, 0.0, -radius))

    def index(i, j):  # 1-based, ring i in 1..rings-1
        return 2 + (i - 1) * segments + j % segments

    faces = [(1, index(1, j), index(1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        for j in range(segments):
            a, b, c, d = index(i, j), index(i, j + 1), index(i + 1, j + 1), index(i + 1, j)
            faces += [(a, d, c), (a, c, b)]
    last = len(vertices)
    faces += [(index(rings - 1, j), last, index(rings - 1, j + 1)) for j in range(segments)]
    with open(path, "w") as f:
        f.writelines("v %.6f %.6f %.6f\n" % v for v in vertices)
        f.writelines("f %d %d %d\n" % t for t in faces)


def sky_hdr(path, width=128, height=64):
    """A Radiance HDR equirectangular sky (linear): blue above, brown below, its hue turning with
    the azimuth, and a patch of 6 x 4 pixels of radiance 200 centred 35 degrees up at u = 0.3 (a
    sun: the sphere's shadow on the floor shows where the image points and how it is turned)."""
    def rgbe(r, g, b):
        m = max(r, g, b)
        if m < 1e-32:
            return bytes(4)
        mantissa, exponent = math.frexp(m)
        scale = mantissa * 256.0 / m
        return bytes([int(r * scale), int(g * scale), int(b * scale), exponent + 128])

    data = bytearray()
    for v in range(height):
        for u in range(width):
            turn = u / width
            if v < height // 2:
                rgb = (0.1 + 0.3 * turn, 0.25, 0.6 - 0.3 * turn)
            else:
                rgb = (0.2, 0.1 + 0.1 * turn, 0.05)
            if abs(u + 0.5 - 0.3 * width) < 3 and abs(v + 0.5 - (0.5 - 35 / 180) * height) < 2:
                rgb = (200.0, 190.0, 170.0)
            data += rgbe(*rgb)
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {height} +X {width}\n".encode())
        f.write(bytes(data))  # flat scanlines (no run-length encoding)


def yaml_list(values, unit=""):
    return "[" + ", ".join(f"{v:g}{unit}" for v in values) + "]"


def lens_mm(shown):
    """The focal length Blender's camera gets (a 36 mm wide sensor), which cadsynth's lens is given
    too: it sets the aperture, focal_length / f_number, in both."""
    width, _, f = shown["camera"]
    return f * 36.0 / width


def rules(material):
    """A case's materials as (name glob, material) pairs: one material is every part's."""
    return material if isinstance(material, list) else [("*", material)]


def recipe(material, lights, world, samples, shown):
    def mat(m):
        return (f"{{base_color: {yaml_list(m['base_color'])}, metallic: {m['metallic']}, "
                f"roughness: {m['roughness']}, specular: {m['specular']}"
                + (", distribution: multiscatter_ggx" if m.get("multiscatter") else "")
                + (f", anisotropic: {m['anisotropic']}" if m.get("anisotropic") else "") + "}")
    width, height, f = shown["camera"]
    yaw, pitch, radius = shown["view"]
    out = ([f"scenes: {shown['scenes']}"] if "scenes" in shown else
           [f"parts: {shown['parts']}", f"scene: {shown['scene']}"])
    out += [f"camera: {{width: {width}, height: {height}, fx: {f}, fy: {f}, cx: {width / 2 - 0.5}, "
           f"cy: {height / 2 - 0.5}"
           + (f", lens: {{focal_length: {lens_mm(shown):.6f} mm, f_number: {world['lens'][0]}, "
              f"focus_distance: {1000 * world['lens'][1]:g} mm}}" if "lens" in world else "")
           + "}",
           f"sweep: {{yaw: [{yaw}], pitch: [{pitch}], radius: [{radius} m]}}",
           f"render: {{mode: pbr, samples: {samples}, bounces: 3, hdr: true, view: standard, "
           f"{light_paths_yaml(light_paths(shown))}}}",
           "materials:",
           f"  floor: {mat(shown.get('floor', LAMBERT))}",
           "  assign:"]
    out += [f"    - {{name: '{glob}', texture: none, {mat(m)[1:-1]}}}"
            for glob, m in rules(material)]
    out += ["lighting:",
           "  lights:" if lights else "  lights: []"]
    for l in lights:
        keys = [f"type: {l['type']}"]
        # Lengths in metres here, in mm in the recipe (lists of them).
        keys += [f"{k[:-2]}: {yaml_list([1000 * v for v in l[k]], ' mm')}"
                 for k in ("position_m", "target_m", "size_m") if k in l]
        if "direction" in l:
            keys.append(f"direction: {yaml_list(l['direction'])}")
        if "power" in l:
            keys.append(f"power: {l['power']}")
        if "strength" in l:
            keys.append(f"strength: {l['strength']}, angle: {l['angle_deg']}")
        if "radius_m" in l:
            keys.append(f"radius: {1000 * l['radius_m']:g} mm")
        if "spot_size_deg" in l:
            keys.append(f"spot_size: {l['spot_size_deg']}, spot_blend: {l['spot_blend']}")
        out.append("    - {" + ", ".join(keys) + "}")
    if "image" in world:
        out.append(f"  environment: {{type: image, file: {world['image']}, "
                   f"strength: {world['strength']}, rotation: {world['rotation_deg']}}}")
    else:
        out.append(f"  environment: {{type: uniform, color: {yaml_list(world['color'])}, "
                   f"strength: {world['strength']}}}")
    out.append("output: {formats: [bop], model_points: 0}")
    return "\n".join(out) + "\n"


def blender_light(l):
    """The case's light as cycles_scene.py takes it: direction from the target, angles in rad."""
    b = dict(l)
    if "target_m" in l:
        b["direction"] = [t - p for t, p in zip(l["target_m"], l["position_m"])]
    b.setdefault("direction", [0.0, 0.0, -1.0])
    if "angle_deg" in l:
        b["angle_rad"] = math.radians(l["angle_deg"])
    if "spot_size_deg" in l:
        b["spot_size_rad"] = math.radians(l["spot_size_deg"])
    return b


def spec_from_look(look):
    """A scene's look in cadsynth (Run.look: its materials per instance, floor, lights and world)
    as cycles_scene.py's spec takes it: instance_materials, floor_material (or floor: false),
    floor_half_size_m, lights in m and rad, world. Fixtures and worlds other than a uniform one
    are refused (the spec's fixtures need their meshes: equal_error.py's Scene.fixtures)."""
    if look["fixtures"]:
        raise SystemExit("Run.look: fixtures are rebuilt from Run.fixtures, not here")
    env = look["environment"]
    if env["type"] != "uniform":
        raise SystemExit(f"Run.look: a {env['type']} world has no rebuild here (uniform only)")
    lights = []
    for l in look["lights"]:
        b = {"type": l["type"], "color": l["color"], "direction": l["direction"],
             "x_axis": l["x_axis"], "position_m": [c * 1e-3 for c in l["position"]],
             "radius_m": l["radius"] * 1e-3, "size_m": [l["size_x"] * 1e-3, l["size_y"] * 1e-3],
             "spot_size_rad": l["spot_size"], "spot_blend": l["spot_blend"],
             "angle_rad": l["angle"]}
        # A sun's strength (W/m^2) is LightSource::power, as the recipe's `strength`.
        b["strength" if l["type"] == "sun" else "power"] = l["power"]
        lights.append(b)
    spec = {"instance_materials": look["instances"], "lights": lights,
            "world": {"color": env["color"], "strength": env["strength"]},
            "floor": look["floor"] is not None}
    if look["floor"] is not None:
        spec["floor_material"] = look["floor"]
        spec["floor_half_size_m"] = look["floor_half_size"] * 1e-3
    return spec


def blender_env():
    """Blender's embedded Python finds its standard library (and numpy) from PATH's python3: keep
    a Python version manager's (pyenv) directories and variables away from it."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYENV", "PYTHONHOME",
                                                                      "PYTHONPATH"))}
    env["PATH"] = os.pathsep.join(d for d in env.get("PATH", "").split(os.pathsep)
                                  if ".pyenv" not in d)
    return env


def compare_frame(args, label, sid, shown, material, lights, world, strict, note, out, dataset,
                  ours):
    """Renders frame (scene sid, image 0) of a case's dataset in Cycles, prints the comparison
    and returns whether a strict case is within its tolerances."""
    frame = os.path.join(dataset, "train", f"{sid:06d}")
    masks = sorted(os.path.join(frame, "mask_visib", m)
                   for m in os.listdir(os.path.join(frame, "mask_visib")))
    spec = {"dataset": dataset, "scene_id": sid, "im_id": 0, "width": shown["camera"][0],
            "height": shown["camera"][1], "samples": args.samples, "bounces": 3,
            **light_paths(shown),
            "output": os.path.join(out, f"{label}_cycles.exr"),
            "part_materials": rules(material),
            "floor_material": shown.get("floor", LAMBERT),
            "lights": [blender_light(l) for l in lights],
            "world": dict(world, image=os.path.join(out, world["image"]))
            if "image" in world else world,
            "compare": {"cadsynth": os.path.join(frame, "rgb_hdr", "000000.exr"),
                        "masks": masks,
                        "sheet": os.path.join(out, f"{label}_sheet.png")},
            "stats": os.path.join(out, f"{label}_stats.json")}
    with open(os.path.join(out, f"{label}_spec.json"), "w") as f:
        json.dump(spec, f, indent=1)
    log = os.path.join(out, f"{label}_blender.log")
    with open(log, "w") as f:
        done = subprocess.run([args.blender, "-b", "--factory-startup", "--python-exit-code",
                               "1", "--python", os.path.join(HERE, "cycles_scene.py"), "--",
                               os.path.join(out, f"{label}_spec.json")], stdout=f, stderr=f,
                              env=blender_env())
    if done.returncode == 77:
        print(f"{args.blender}: not Blender 3 (see {log}); the scripts use Blender 3's API")
        sys.exit(77 if args.skip_without_blender else 2)
    if done.returncode != 0 or not os.path.exists(spec["stats"]):
        sys.exit(f"blender failed on case '{label}': see {log}")
    # Cycles' own render time (its log's last "Time:"), without starting Blender.
    times = re.findall(r"Time: (\d+):(\d+\.\d+)", open(log).read())
    theirs = 60 * int(times[-1][0]) + float(times[-1][1]) if times else float("nan")
    s = json.load(open(spec["stats"]))
    shift = math.hypot(*s["shift_px"])
    ratios = [s[r]["ratio"] for r in ("part", "floor", "all") if r in s]
    # Each instance of at least --part-pixels pixels on its own (a glossy part too bright
    # and another too dark can cancel in the parts' sum).
    large = {k: v for k, v in s["instances"].items() if v["pixels"] >= args.part_pixels}
    ratios += [v["ratio"] for v in large.values()]
    print(f"{label:9s} {s['part']['ratio']:7.3f} {s['floor']['ratio']:7.3f} "
          f"{s['all']['ratio']:7.3f} {s['blocks']['median_rel_diff']:10.3f} "
          f"{s['blocks']['p90_rel_diff']:6.3f} {s['blocks']['p99_rel_diff']:6.3f} "
          f"{shift:5.2f} {ours:6.1f} {theirs:6.1f}  {note}")
    if len(s["instances"]) > 1:
        print(" " * 10 + "instances: " + ", ".join(
            f"{os.path.splitext(k)[0]} {v['ratio']:.3f} ({v['pixels']} px)"
            for k, v in s["instances"].items()))
    block_tolerance = args.block_tolerance if strict is True else strict
    if strict and (any(abs(r - 1) > args.tolerance for r in ratios) or
                   s["blocks"]["p99_rel_diff"] > block_tolerance or
                   shift > args.shift_tolerance):
        return False
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cadsynth", default=os.path.join(ROOT, "build", "tools", "cadsynth"))
    parser.add_argument("--blender", default=shutil.which("blender") or "blender")
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--out", default="cycles_comparison")
    parser.add_argument("--tolerance", type=float, default=0.03,
                        help="strict cases: largest |ratio - 1| of the mean radiances")
    parser.add_argument("--block-tolerance", type=float, default=0.1,
                        help="strict cases: largest 99th percentile of the blocks' differences")
    parser.add_argument("--part-pixels", type=int, default=500,
                        help="strict cases: every instance seen in at least this many pixels must "
                        "agree within --tolerance too (its own mean radiance)")
    parser.add_argument("--shift-tolerance", type=float, default=0.1,
                        help="strict cases: largest sub-pixel shift between the images (px)")
    parser.add_argument("--strict", action="store_true", help="only the strict cases")
    parser.add_argument("--scale", type=int, default=1,
                        help="render N times the cases' width and height (for timing)")
    parser.add_argument("--skip-without-blender", action="store_true",
                        help="exit 77 (a skipped test) when Blender is not installed")
    args = parser.parse_args()
    if not shutil.which(args.blender):
        print("blender not found: apt-get install blender (Debian's 3.4), or --blender PATH")
        sys.exit(77 if args.skip_without_blender else 2)
    if not os.access(args.cadsynth, os.X_OK):
        sys.exit(f"{args.cadsynth}: no cadsynth binary (build it, or --cadsynth PATH)")
    names = args.cases.split(",")
    unknown = [n for n in names if n not in CASES]
    if unknown:
        sys.exit(f"unknown case(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    if args.strict:
        names = [n for n in names if CASES[n][3]]
    os.makedirs(args.out, exist_ok=True)
    out = os.path.abspath(args.out)
    sphere_obj(os.path.join(out, "sphere.obj"))
    sky_hdr(os.path.join(out, "sky.hdr"))
    failed = []
    print(f"{'case':9s} {'part':>7s} {'floor':>7s} {'all':>7s} {'blocks p50':>10s} "
          f"{'p90':>6s} {'p99':>6s} {'shift':>5s} {'ours s':>6s} {'Cycles':>6s}  (ratios "
          f"cadsynth / Cycles, shift in px, "
          f"{args.samples} spp, 3 bounces)")
    for name in names:
        material, lights, world, strict, note = CASES[name][:5]
        shown = dict(CASES[name][5] if len(CASES[name]) > 5 else SPHERE)
        shown["camera"] = tuple(args.scale * v for v in shown["camera"])
        with open(os.path.join(out, f"{name}.yaml"), "w") as f:
            f.write(recipe(material, lights, world, args.samples, shown))
        dataset = os.path.join(out, name)
        start = time.monotonic()
        if subprocess.run([args.cadsynth, "generate", os.path.join(out, f"{name}.yaml"), "-o",
                           dataset, "--overwrite", "--quiet", "--no-cache"]).returncode != 0:
            sys.exit(f"cadsynth failed on case '{name}' ({os.path.join(out, name + '.yaml')})")
        ours = (time.monotonic() - start) / len(shown.get("frames", [0]))  # a frame's share
        for sid in shown.get("frames", [0]):
            # A case of several scenes (the default job's) compares one frame of each.
            label = name if "frames" not in shown else f"{name}_{sid}"
            if not compare_frame(args, label, sid, shown, material, lights, world, strict, note,
                                 out, dataset, ours):
                failed.append(label)
    if failed:
        print("outside the tolerance:", ", ".join(failed))
        sys.exit(1)


if __name__ == "__main__":
    main()
