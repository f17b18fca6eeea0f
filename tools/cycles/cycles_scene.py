# Rebuilds one frame of a cadsynth dataset in Blender Cycles and renders its linear radiance, so
# that cadsynth's physically based mode can be compared with an independent renderer. Run inside
# Blender (Debian's `blender` package, 3.4):
#
#   blender -b --factory-startup --python tools/cycles/cycles_scene.py -- SPEC.json
#
# SPEC.json (written by tools/cycles/compare_with_cycles.py or tools/bench/equal_error.py) names
# the dataset, the frame, the materials (by part name globs, or one per instance as Run.look gives
# them: instance_materials), lights and world in SI units (metres, W, W/m^2) and Cycles'
# settings; the geometry and
# poses come from the dataset itself: models/obj_*.ply (the meshes cadsynth traced, with its
# normals), scene_gt_world.json and scene_camera.json, and the spec's fixtures (PLY files in the
# world frame). Cycles is set up as docs/testing.md's "Checked against Blender Cycles" says: GGX,
# no clamping, no glossy filter and no separate glossy bounce limit (unless the spec sets
# clamp_indirect, filter_glossy or glossy_bounces: cadsynth's render options of those names),
# a 1-pixel box filter, no light threshold, no denoising or adaptive
# sampling (unless the spec sets adaptive_threshold), the same bounces. cadsynth's noise, brushed
# and wood textures become Cycles nodes of the same kind, size and amount (texture(), not the
# same patterns), its tangent `x` the object's x axis. The result is written as
# a 32-bit EXR (linear Rec.709, W/(m^2 sr), like cadsynth's rgb_hdr/).
import fnmatch
import json
import math
import os
import sys

import bpy
import mathutils
import numpy as np


def read_ply(path):
    """cadsynth's binary PLY: float x y z nx ny nz per vertex, uchar-counted int faces (mm)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    vertices = faces = 0
    props = []
    for line in header:
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            vertices = int(words[2])
        elif words[:2] == ["element", "face"]:
            faces = int(words[2])
        elif words[:1] == ["property"] and words[1] == "float":
            props.append(words[2])
    if props[:6] != ["x", "y", "z", "nx", "ny", "nz"] or len(props) != 6:
        raise SystemExit(f"{path}: expected x y z nx ny nz floats, found {props}")
    v = np.frombuffer(data, dtype="<f4", count=6 * vertices, offset=end).reshape(-1, 6)
    f = np.frombuffer(data, dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]), count=faces,
                      offset=end + 24 * vertices)
    if np.any(f["n"] != 3):
        raise SystemExit(f"{path}: only triangles are expected")
    return v[:, :3].astype(np.float64), v[:, 3:].astype(np.float64), f["i"].astype(np.int64)


def add_mesh(name, ply, material):
    """An object of cadsynth's PLY (mm) with cadsynth's own normals per face corner, linked into
    the scene at the identity."""
    v, n, f = read_ply(ply)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata((v * 1e-3).tolist(), [], f.tolist())
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    mesh.use_auto_smooth = True
    mesh.normals_split_custom_set([tuple(n[i]) for poly in mesh.polygons for i in poly.vertices])
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def matrix(r, t):
    m = mathutils.Matrix.Identity(4)
    for i in range(3):
        for j in range(3):
            m[i][j] = r[3 * i + j]
        m[i][3] = t[i]
    return m


def principled(name, m):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    out = nodes["Material Output"]
    for n in list(nodes):
        if n != out:
            nodes.remove(n)
    c = (*m["base_color"], 1.0)
    if m.get("lambert"):
        # metallic 0, specular 0: cadsynth's lobe is then Lambert exactly; so is Diffuse BSDF at
        # roughness 0 (Principled's diffuse in 3.4 is Disney's, with its grazing retro-reflection).
        bsdf = nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = c
        bsdf.inputs["Roughness"].default_value = 0.0
        mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
        return mat
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.distribution = "MULTI_GGX" if m.get("multiscatter") else "GGX"
    bsdf.inputs["Base Color"].default_value = c
    bsdf.inputs["Metallic"].default_value = m["metallic"]
    bsdf.inputs["Roughness"].default_value = m["roughness"]
    bsdf.inputs["Specular"].default_value = m["specular"]
    bsdf.inputs["Anisotropic"].default_value = m.get("anisotropic", 0.0)
    bsdf.inputs["Clearcoat"].default_value = m.get("clearcoat", 0.0)
    bsdf.inputs["Clearcoat Roughness"].default_value = m.get("clearcoat_roughness", 0.03)
    bsdf.inputs["Sheen Tint"].default_value = 0.0
    mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    if m.get("tangent") == "x" and m.get("anisotropic", 0.0) > 0.0:
        # cadsynth's tangent `x`: the model's x axis (the object's), in the world. Tilted by a
        # milliradian: on a face whose normal is x itself Cycles' frame (cross(N, T)) vanishes
        # and the face renders black, where cadsynth takes any tangent of the face.
        axis = nodes.new("ShaderNodeCombineXYZ")
        axis.inputs["X"].default_value = 1.0
        axis.inputs["Y"].default_value = axis.inputs["Z"].default_value = 1e-3
        to_world = nodes.new("ShaderNodeVectorTransform")
        to_world.vector_type = "VECTOR"
        to_world.convert_from, to_world.convert_to = "OBJECT", "WORLD"
        mat.node_tree.links.new(axis.outputs["Vector"], to_world.inputs["Vector"])
        mat.node_tree.links.new(to_world.outputs["Vector"], bsdf.inputs["Tangent"])
    if m.get("texture"):
        texture(mat, bsdf, m)
    return mat


def texture(mat, bsdf, m):
    """cadsynth's procedural textures (render/material.cpp Pattern, EvalTexture) in kind, from
    Cycles' own nodes: the same kinds, feature sizes and amounts, not the same patterns (Cycles'
    Noise Texture is Perlin noise, cadsynth's value noise; no OSL in Debian's Blender). Enough
    for a scene of the same look and difficulty; a pixel-by-pixel comparison needs untextured
    materials. The texture frame: the object's coordinates (the model's, or the world's for the
    floor), in mm as cadsynth's."""
    t = m["texture"]
    kind, s = t["type"], t["scale"]
    if kind not in ("noise", "brushed", "wood"):
        raise SystemExit(f"texture '{kind}': no Cycles rebuild (noise, brushed and wood have one)")
    if t["bump"] > 0.0:
        raise SystemExit(f"texture '{kind}' with bump {t['bump']}: no Cycles rebuild of bump")
    nodes, links = mat.node_tree.nodes, mat.node_tree.links

    def math_node(op, a, b=None, clamp=False):
        node = nodes.new("ShaderNodeMath")
        node.operation = op
        node.use_clamp = clamp
        for i, v in enumerate((a, b)):
            if v is None:
                continue
            if isinstance(v, (int, float)):
                node.inputs[i].default_value = float(v)
            else:
                links.new(v, node.inputs[i])
        return node.outputs["Value"]

    def smoothstep(lo, hi, x):
        node = nodes.new("ShaderNodeMapRange")
        node.interpolation_type = "SMOOTHSTEP"
        node.inputs["From Min"].default_value = lo
        node.inputs["From Max"].default_value = hi
        links.new(x, node.inputs["Value"])
        return node.outputs["Result"]

    def noise(vector, octaves, w=None):
        node = nodes.new("ShaderNodeTexNoise")
        node.noise_dimensions = "4D" if w is not None else "3D"
        node.inputs["Scale"].default_value = 1.0
        node.inputs["Detail"].default_value = octaves - 1
        node.inputs["Roughness"].default_value = 0.5  # each octave half the amplitude
        node.inputs["Distortion"].default_value = 0.0
        links.new(vector, node.inputs["Vector"])
        if w is not None:
            links.new(w, node.inputs["W"])
        return node.outputs["Fac"]

    def scaled(per_axis_mm):
        """The object's coordinates (m) in mm times per_axis_mm (x, y, z)."""
        coords = nodes.new("ShaderNodeTexCoord")
        node = nodes.new("ShaderNodeVectorMath")
        node.operation = "MULTIPLY"
        node.inputs[1].default_value = [1000.0 * f for f in per_axis_mm]
        links.new(coords.outputs["Object"], node.inputs[0])
        return node.outputs["Vector"]

    def axis(vector, name):
        node = nodes.new("ShaderNodeSeparateXYZ")
        links.new(vector, node.inputs["Vector"])
        return node.outputs[name]

    if kind == "noise":
        v = noise(scaled((1 / s, 1 / s, 1 / s)), 4)
    elif kind == "brushed":
        # Streaks along x, 4 `scale` long and a fiftieth of `scale` wide.
        v = noise(scaled((1 / (4 * s), 50 / s, 50 / s)), 3)
    else:
        # Boards 8 `scale` wide across x, each its own tone (a white noise of the board's number)
        # and grain (long streaks along y), growth rings across x, a dark seam between boards.
        x = axis(scaled((1.0, 1.0, 1.0)), "X")
        board = math_node("FLOOR", math_node("DIVIDE", x, 8 * s))
        white = nodes.new("ShaderNodeTexWhiteNoise")
        white.noise_dimensions = "1D"
        links.new(board, white.inputs["W"])
        tone = white.outputs["Value"]
        grain = noise(scaled((20 / s, 1 / (4 * s), 20 / s)), 4, board)
        w = math_node("ADD", math_node("DIVIDE", x, 1.5 * s),
                      math_node("MULTIPLY", noise(scaled((0.1 / s,) * 3), 3,
                                                  math_node("ADD", board, 0.5)), 2.0))
        ring = math_node("FRACT", w)
        band = math_node("MULTIPLY", smoothstep(0.0, 0.3, ring),
                         math_node("SUBTRACT", 1.0, smoothstep(0.5, 1.0, ring)))
        across = math_node("SUBTRACT", math_node("DIVIDE", x, 8 * s), board)
        edge = math_node("MINIMUM", across, math_node("SUBTRACT", 1.0, across))
        seam = math_node("SUBTRACT", 1.0, smoothstep(0.0, 0.004, edge))
        v = math_node("ADD", math_node("ADD", math_node("MULTIPLY", grain, 0.45),
                                       math_node("MULTIPLY", band, 0.2)),
                      math_node("ADD", math_node("MULTIPLY", tone, 0.35), seam), clamp=True)
    base = nodes.new("ShaderNodeRGB")
    base.outputs["Color"].default_value = (*m["base_color"], 1.0)
    if kind == "wood":
        # The second colour blended in by amount x v; a coating, not metal.
        mix = math_node("MULTIPLY", v, t["amount"])
        blend = nodes.new("ShaderNodeMixRGB")
        blend.blend_type = "MIX"
        links.new(mix, blend.inputs["Fac"])
        links.new(base.outputs["Color"], blend.inputs["Color1"])
        blend.inputs["Color2"].default_value = (*t["color"], 1.0)
        links.new(blend.outputs["Color"], bsdf.inputs["Base Color"])
        links.new(math_node("MULTIPLY", math_node("SUBTRACT", 1.0, mix), m["metallic"]),
                  bsdf.inputs["Metallic"])
        links.new(math_node("ADD", math_node("MULTIPLY", math_node("SUBTRACT", v, 0.5),
                                             t["roughness"]), m["roughness"], clamp=True),
                  bsdf.inputs["Roughness"])
        return
    # Base colour x (1 + 2 amount (v - 0.5)), roughness + 2 roughness_amount (v - 0.5).
    d = math_node("SUBTRACT", v, 0.5)
    gain = math_node("ADD", math_node("MULTIPLY", d, 2 * t["amount"]), 1.0)
    colour = nodes.new("ShaderNodeVectorMath")
    colour.operation = "SCALE"
    links.new(base.outputs["Color"], colour.inputs[0])
    links.new(gain, colour.inputs["Scale"])
    links.new(colour.outputs["Vector"], bsdf.inputs["Base Color"])
    links.new(math_node("ADD", math_node("MULTIPLY", d, 2 * t["roughness"]), m["roughness"],
                        clamp=True), bsdf.inputs["Roughness"])


def orient(obj, direction, x_axis=(1.0, 0.0, 0.0)):
    """Turns a light so that its -Z points along `direction` and its X along x_axis's projection."""
    z = -mathutils.Vector(direction).normalized()
    x = mathutils.Vector(x_axis)
    x = x - x.dot(z) * z
    if x.length < 1e-6:
        x = mathutils.Vector((0.0, 1.0, 0.0))
        x = x - x.dot(z) * z
    x.normalize()
    y = z.cross(x)
    obj.matrix_world = mathutils.Matrix.Translation(obj.location) @ mathutils.Matrix(
        ((x[0], y[0], z[0]), (x[1], y[1], z[1]), (x[2], y[2], z[2]))).to_4x4()


def add_light(i, l):
    kind = l["type"]
    blender_type = {"point": "POINT", "spot": "SPOT", "rect": "AREA", "disc": "AREA",
                    "sun": "SUN"}[kind]
    data = bpy.data.lights.new(f"light{i}", blender_type)
    data.color = l.get("color", (1.0, 1.0, 1.0))
    data.cycles.cast_shadow = True
    if kind == "sun":
        data.energy = l["strength"]
        data.angle = l["angle_rad"]
    else:
        data.energy = l["power"]
    if kind in ("point", "spot"):
        data.shadow_soft_size = l.get("radius_m", 0.0)
    if kind == "spot":
        data.spot_size = l["spot_size_rad"]
        data.spot_blend = l["spot_blend"]
    if kind == "rect":
        data.shape = "RECTANGLE"
        data.size, data.size_y = l["size_m"]
    if kind == "disc":
        data.shape = "DISK"
        data.size = 2 * l["radius_m"]
    obj = bpy.data.objects.new(f"light{i}", data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = l.get("position_m", (0.0, 0.0, 0.0))
    orient(obj, l["direction"], l.get("x_axis", (1.0, 0.0, 0.0)))


def main():
    if bpy.app.version[0] != 3:
        # Blender 4 renamed the Principled BSDF's inputs (Specular, Clearcoat) and dropped
        # use_auto_smooth: this script speaks Blender 3's API (Debian 12's 3.4).
        print(f"Blender {bpy.app.version_string}: this script needs Blender 3")
        sys.exit(77)
    spec = json.load(open(sys.argv[sys.argv.index("--") + 1]))
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = spec["samples"]
    # Adaptive sampling only when the spec asks (tools/bench/equal_error.py, as BlenderProc's
    # default: noise threshold 0.01): the comparison's cases sample every pixel alike.
    cy.use_adaptive_sampling = spec.get("adaptive_threshold", 0.0) > 0.0
    if cy.use_adaptive_sampling:
        cy.adaptive_threshold = spec["adaptive_threshold"]
        cy.adaptive_min_samples = spec.get("adaptive_min_samples", 0)
    cy.use_denoising = False
    cy.seed = spec.get("seed", 0)
    cy.max_bounces = spec["bounces"]
    cy.diffuse_bounces = cy.transmission_bounces = spec["bounces"]
    cy.glossy_bounces = min(spec["bounces"], spec.get("glossy_bounces", 64))
    cy.transparent_max_bounces = 0
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = spec.get("clamp_indirect", 0.0)  # cadsynth's render.clamp_indirect
    cy.blur_glossy = spec.get("filter_glossy", 0.0)  # cadsynth's render.filter_glossy
    cy.light_sampling_threshold = 0.0
    cy.caustics_reflective = cy.caustics_refractive = True
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.film_exposure = 1.0
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0

    root = spec["dataset"]
    sid, im = spec["scene_id"], spec["im_id"]
    folder = f"{root}/train/{sid:06d}"
    camera = json.load(open(f"{folder}/scene_camera.json"))[str(im)]
    placed = json.load(open(f"{folder}/scene_gt_world.json"))

    # Camera: OpenCV's frame (x right, y down, z ahead) to Blender's (x right, y up, -z ahead).
    k = camera["cam_K"]
    width, height = spec["width"], spec["height"]
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.sensor_width = 36.0
    cam_data.lens = k[0] * 36.0 / width
    if abs(k[0] - k[4]) > 1e-6 * k[0]:
        raise SystemExit("fx != fy: Blender's pixels are square")
    # Shifts in units of the fitted side (the width here). cadsynth's (and bop_toolkit's) pixel u
    # spans [u, u + 1) with K's principal point in those coordinates; Blender's optical axis meets
    # the image at its centre, (width / 2, height / 2) there, with y up.
    cam_data.shift_x = (width / 2 - k[2]) / width
    cam_data.shift_y = (k[5] - height / 2) / width
    if "lens" in spec["world"]:
        # A thin lens as cadsynth's: aperture diameter = lens / f-number, focused at a distance
        # along the optical axis.
        f_number, focus_m = spec["world"]["lens"]
        cam_data.dof.use_dof = True
        cam_data.dof.aperture_fstop = f_number
        cam_data.dof.focus_distance = focus_m
        cam_data.dof.aperture_blades = 0
    cam_data.clip_start = 0.001
    cam_data.clip_end = 1000.0
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    w2c = matrix(camera["cam_R_w2c"], [t * 1e-3 for t in camera["cam_t_w2c"]])
    cam.matrix_world = w2c.inverted() @ mathutils.Matrix.Diagonal((1.0, -1.0, -1.0, 1.0))
    scene.camera = cam

    # materials.assign matches the part's name (models_cad.json's: "ring_z54"), not the
    # instance's (scene_gt_world.json's: "ring"); they differ where a scene names its instances.
    part_names = {int(k): v["name"]
                  for k, v in json.load(open(f"{root}/models/models_cad.json")).items()}
    materials = {}
    # Per instance (Run.look's, in scene_gt_world.json's order), or by the rules below.
    instance_materials = spec.get("instance_materials")
    if instance_materials is not None and len(instance_materials) != len(placed):
        raise SystemExit(f"{len(instance_materials)} instance materials for {len(placed)} "
                         "instances")
    for i, p in enumerate(placed):
        obj_id = p["obj_id"]
        if instance_materials is not None:
            obj = add_mesh(f"instance{i}", f"{root}/models/obj_{obj_id:06d}.ply",
                           principled(f"instance{i}", instance_materials[i]))
            obj.matrix_world = matrix(p["world_R_m2w"], [t * 1e-3 for t in p["world_t_m2w"]])
            continue
        if obj_id not in materials:
            # The first rule whose glob matches the part's name, as cadsynth's materials.assign.
            part = part_names[obj_id]
            rule = next((m for glob, m in spec["part_materials"]
                         if fnmatch.fnmatch(part.lower(), glob.lower())), None)
            if rule is None:
                raise SystemExit(f"no material rule matches part '{part}'")
            materials[obj_id] = principled(f"part{obj_id}", rule)
        obj = add_mesh(f"obj{obj_id}", f"{root}/models/obj_{obj_id:06d}.ply", materials[obj_id])
        obj.matrix_world = matrix(p["world_R_m2w"], [t * 1e-3 for t in p["world_t_m2w"]])

    # Fixtures (a pile's tote: drawn, no object), in the world frame as cadsynth traced them
    # (Run.fixtures, written as PLY by the caller).
    for i, fixture in enumerate(spec.get("fixtures", [])):
        add_mesh(f"fixture{i}", fixture["ply"], principled(f"fixture{i}", fixture["material"]))

    if spec.get("floor", True):
        half = spec.get("floor_half_size_m", 10.0)
        mesh = bpy.data.meshes.new("floor")
        mesh.from_pydata([(-half, -half, 0), (half, -half, 0), (half, half, 0), (-half, half, 0)],
                         [], [(0, 1, 2, 3)])
        mesh.materials.append(principled("floor", spec["floor_material"]))
        floor = bpy.data.objects.new("floor", mesh)
        scene.collection.objects.link(floor)

    for i, l in enumerate(spec["lights"]):
        add_light(i, l)

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    tree = world.node_tree
    background = tree.nodes["Background"]
    w = spec["world"]
    background.inputs["Strength"].default_value = w["strength"]
    if "image" in w:
        # As BlenderProc's set_world_background_hdr_img: Generated coordinates, a Mapping node's Z
        # rotation, an equirectangular Environment Texture (Linear interpolation, sRGB for 8 bits).
        coords = tree.nodes.new("ShaderNodeTexCoord")
        mapping = tree.nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(w["rotation_deg"]))
        texture = tree.nodes.new("ShaderNodeTexEnvironment")
        texture.image = bpy.data.images.load(w["image"])
        texture.interpolation = "Linear"
        texture.projection = "EQUIRECTANGULAR"
        tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
        tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    else:
        background.inputs["Color"].default_value = (*w["color"], 1.0)
    world.cycles.sampling_method = "AUTOMATIC"
    scene.world = world

    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.filepath = spec["output"]
    scene.render.use_file_extension = False
    scene.render.threads_mode = "AUTO"
    bpy.ops.render.render(write_still=True)
    if "compare" in spec:
        compare(spec["compare"], spec["output"], spec["stats"])


def load_exr(path):
    """Linear RGB, rows top down (Blender stores images bottom up)."""
    image = bpy.data.images.load(path)
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)


def compare(c, cycles_path, stats_path):
    """Mean radiance of both renders over the part's pixels, the floor's and all, and how 8 x 8
    blocks of pixels differ (relative to Cycles), written as JSON."""
    ours = load_exr(c["cadsynth"])
    theirs = load_exr(cycles_path)
    part = np.zeros(ours.shape[:2], dtype=bool)
    each = {}  # every instance's visible pixels, by its mask's file name
    for mask in c["masks"]:
        each[os.path.basename(mask)] = load_exr(mask)[:, :, 0] > 0.5
        part |= each[os.path.basename(mask)]
    h, w = part.shape
    regions = {"all": np.ones_like(part), "part": part, "floor": ~part}

    def means(m):
        a = ours[m].mean(axis=0)
        b = theirs[m].mean(axis=0)
        return {"cadsynth": a.tolist(), "cycles": b.tolist(),
                "ratio": float(a.sum() / max(b.sum(), 1e-12)), "pixels": int(m.sum())}

    out = {name: means(m) for name, m in regions.items() if m.sum() > 0}
    out["instances"] = {name: means(m) for name, m in sorted(each.items()) if m.sum() > 0}
    la, lb = ours.mean(axis=2), theirs.mean(axis=2)
    bh, bw = h // 8, w // 8
    block_a = la[:8 * bh, :8 * bw].reshape(bh, 8, bw, 8).mean(axis=(1, 3))
    block_b = lb[:8 * bh, :8 * bw].reshape(bh, 8, bw, 8).mean(axis=(1, 3))
    lit = block_b > 0.02 * block_b.max()
    rel = np.abs(block_a - block_b)[lit] / block_b[lit]
    out["blocks"] = {"count": int(lit.sum()), "median_rel_diff": float(np.median(rel)),
                     "p90_rel_diff": float(np.percentile(rel, 90)),
                     "p99_rel_diff": float(np.percentile(rel, 99)),
                     "max_rel_diff": float(rel.max())}
    out["shift_px"] = [float(v) for v in image_shift(la, lb)]
    json.dump(out, open(stats_path, "w"), indent=1)
    if "sheet" in c:
        write_sheet(c["sheet"], ours, theirs)


def image_shift(a, b):
    """The sub-pixel translation (x, y) that best carries image b onto image a: one Lucas-Kanade
    step on b's gradients, a(p) = b(p - d) to first order. Both renderers' pixels seeing the same
    rays give (0, 0); a camera or pixel-centre convention off by half a pixel gives about 0.5.
    Both are clipped at Cycles' 99th percentile first: fireflies (a caustic's sparkle) carry no
    geometry, and unclipped they moved the glossy cases' fit by up to 0.12 px with no shift at
    all, where clipped every case fits within 0.03 px and half a pixel still comes out as 0.25 to
    0.58 (measured on the strict cases, cadsynth's image moved by half a pixel)."""
    top = np.percentile(b, 99)
    a, b = np.minimum(a, top), np.minimum(b, top)
    gy, gx = np.gradient(b)
    diff = a - b
    inner = (slice(2, -2), slice(2, -2))  # central differences need both neighbours
    jx, jy, r = gx[inner].ravel(), gy[inner].ravel(), diff[inner].ravel()
    m = np.array([[jx @ jx, jx @ jy], [jx @ jy, jy @ jy]])
    rhs = -np.array([jx @ r, jy @ r])
    return np.linalg.solve(m, rhs)


def write_sheet(path, ours, theirs):
    """cadsynth | Cycles | |difference| x 10, exposed so that Cycles' 99th percentile is white,
    clipped and sRGB-encoded (Blender's Standard view), as a PNG."""
    scale = 1.0 / max(np.percentile(theirs.mean(axis=2), 99), 1e-6)
    panels = [ours * scale, theirs * scale, np.abs(ours - theirs) * scale * 10]
    linear = np.clip(np.concatenate(panels, axis=1), 0.0, 1.0)
    srgb = np.where(linear <= 0.0031308, 12.92 * linear,
                    1.055 * np.power(linear, 1 / 2.4) - 0.055)
    h, w = srgb.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = srgb[::-1]  # Blender's rows run bottom up
    image = bpy.data.images.new("sheet", w, h, alpha=False, float_buffer=False)
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()


main()
