"""Reading cadsynth's webdataset archives (output format `webdataset`; docs/formats.md).

    from cadsynth.webdataset import archives, frames
    for frame in frames("out"):          # the dataset folder, or a list of .tar paths
        ...                              # dict of numpy arrays, as Run.frames() yields

A run (or each farm task) writes OUT/webdataset/shard-IIIIII-KKKK.tar and the task's manifest
shard-IIIIII.json (samples, bytes and SHA-256 per archive). archives() lists the archives the
manifests name, so that training can start on the tasks that have finished. Each sample (key
SCENEID_IMID) decodes to the keys of class Frame (_cadsynth.pyi) that its files hold:

- exactly Run.frames()'s values: scene_id, im_id, width, height, K, cam_from_world, depth_scale,
  split (when known), obj_id, cam_from_model, the gt_info arrays, mask, mask_visib, rgb or gray,
  ir, instance (from the visible masks: exact with output.visibility exact, the default),
  randomization, graspnet / suctionnet and their labels, sensor and sensors (a rig);
- depth and depth_gt as the PNG holds them: encode_depth(depth, depth_scale) * depth_scale, that
  is, rounded to depth_scale (0.1 mm by default); rgb as its file holds it (lossy with
  output.rgb: jpg);
- normals (8-bit PNG) and radiance (EXR) are not decoded (their files are in the archive), and
  samples (pbr: paths per pixel) is not written to datasets.

Only the standard library's tarfile, numpy and the module's PNG decoder are used.
"""

from __future__ import annotations

import io
import json
import os
import pathlib
import tarfile
from typing import Any, Iterable, Iterator

import numpy as np

from ._cadsynth import decode_image

__all__ = ["archives", "manifests", "samples", "decode", "frames"]

_Path = str | os.PathLike[str]


def manifests(root: _Path) -> list[dict[str, Any]]:
    """The task manifests in ROOT/webdataset (shard-IIIIII.json), by task."""
    folder = pathlib.Path(root) / "webdataset"
    return [json.loads(p.read_text()) for p in sorted(folder.glob("shard-[0-9]*.json"))
            if len(p.name) == 17]


def archives(root: _Path, complete: bool = False) -> list[pathlib.Path]:
    """The archives the manifests in ROOT/webdataset list, in task and archive order. With
    complete=True, raise ValueError unless every task of the run has its manifest."""
    found = manifests(root)
    if complete:
        shards = {m["shards"] for m in found}
        have = {m["shard"] for m in found}
        if len(shards) != 1 or have != set(range(next(iter(shards)))):
            missing = sorted(set(range(max(shards or {0}))) - have)
            raise ValueError(f"{root}: tasks without a manifest: {missing or 'unknown count'}")
    folder = pathlib.Path(root) / "webdataset"
    return [folder / a["file"] for m in found for a in m["archives"]]


def samples(archive: _Path) -> Iterator[tuple[str, dict[str, bytes]]]:
    """(key, {member name after the key: bytes}) per sample of one archive, in order, read as
    a stream."""
    key, members = None, {}
    with tarfile.open(archive, mode="r|") as tar:
        for info in tar:
            if not info.isfile():
                continue
            name = info.name.rsplit("/", 1)[-1]
            sample_key, _, rest = name.partition(".")
            if sample_key != key:
                if key is not None:
                    yield key, members
                key, members = sample_key, {}
            members[rest] = tar.extractfile(info).read()
    if key is not None:
        yield key, members


def _fragment(text: bytes) -> dict[str, Any]:
    lines = text.decode().split("\n")
    return {"camera": json.loads(lines[0]), "coco": json.loads(lines[3]),
            "randomization": lines[5] if len(lines) > 5 and lines[5] else None}


def _pose(rotation, translation) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = np.asarray(rotation, np.float64).reshape(3, 3)
    m[:3, 3] = np.asarray(translation, np.float64).reshape(3)
    return m


def _sensor_frame(key: str, members: dict[str, bytes], x: str, masks: bool) -> dict[str, Any]:
    scene_id, im_id = (int(v) for v in key.split("_"))
    fragment = _fragment(members[f"cadsynth{x}.json"])
    camera = json.loads(members[f"camera{x}.json"])
    gt = json.loads(members[f"gt{x}.json"])
    info = json.loads(members[f"gt_info{x}.json"])
    scale = float(camera["depth_scale"])
    n = len(gt)
    f: dict[str, Any] = {"scene_id": scene_id, "im_id": im_id}
    if x:
        f["sensor"] = x[1:]
    f["width"] = int(fragment["coco"]["width"])
    f["height"] = int(fragment["coco"]["height"])
    f["K"] = np.asarray(camera["cam_K"], np.float64).reshape(3, 3)
    f["cam_from_world"] = _pose(camera["cam_R_w2c"], camera["cam_t_w2c"])
    f["depth_scale"] = scale
    if "split.txt" in members:
        f["split"] = members["split.txt"].decode()
    f["obj_id"] = np.array([g["obj_id"] for g in gt], np.int32)
    f["cam_from_model"] = np.array([_pose(g["cam_R_m2c"], g["cam_t_m2c"]) for g in gt],
                                   np.float64).reshape(n, 4, 4)
    for k in ("bbox_obj", "bbox_visib"):
        f[k] = np.array([i[k] for i in info], np.int32).reshape(n, 4)
    for k in ("px_count_all", "px_count_valid", "px_count_visib"):
        f[k] = np.array([i[k] for i in info], np.int32)
    f["visib_fract"] = np.array([i["visib_fract"] for i in info], np.float64)
    h, w = f["height"], f["width"]
    visib = np.zeros((n, h, w), bool)
    for i in range(n):
        visib[i] = decode_image(members[f"mask_visib{x}_{i:06d}.png"]) > 0
    if masks:
        f["mask"] = np.array([decode_image(members[f"mask{x}_{i:06d}.png"]) > 0
                              for i in range(n)], bool).reshape(n, h, w)
        f["mask_visib"] = visib
    for name in ("rgb", "gray"):
        for ext in (".png", ".jpg"):
            if f"{name}{x}{ext}" in members:
                f[name] = decode_image(members[f"{name}{x}{ext}"])
    for name in ("depth", "depth_gt"):
        if f"{name}{x}.png" in members:
            f[name] = decode_image(members[f"{name}{x}.png"]).astype(np.float32) * np.float32(scale)
    instance = np.zeros((h, w), np.uint16)
    for i in range(n):
        instance[visib[i]] = i + 1
    f["instance"] = instance
    if f"ir{x}.png" in members:
        f["ir"] = decode_image(members[f"ir{x}.png"])
    if fragment["randomization"] is not None:
        f["randomization"] = fragment["randomization"]
    for name in ("graspnet", "graspnet_labels", "suctionnet", "suctionnet_labels"):
        if f"{name}.npy" in members:
            f[name] = np.load(io.BytesIO(members[f"{name}.npy"]))
    return f


def decode(key: str, members: dict[str, bytes], masks: bool = True) -> dict[str, Any]:
    """One sample as the frame dict Run.frames() yields (see the module's docstring for what is
    exact). A rig's sample: the first sensor's frame with 'sensors', every sensor's frame."""
    suffixes = [name[len("cadsynth"):-len(".json")] for name in members
                if name.startswith("cadsynth") and name.endswith(".json")]
    if not suffixes:
        raise ValueError(f"sample {key}: no cadsynth.json member (not a cadsynth archive)")
    if suffixes == [""]:
        return _sensor_frame(key, members, "", masks)
    sensors = [_sensor_frame(key, members, x, masks) for x in suffixes]
    grasp_keys = ("graspnet", "graspnet_labels", "suctionnet", "suctionnet_labels")
    for other in sensors[1:]:  # grasp rows are the first sensor's
        for k in grasp_keys:
            other.pop(k, None)
    return dict(sensors[0], sensors=sensors)


def frames(source: _Path | Iterable[_Path], masks: bool = True) -> Iterator[dict[str, Any]]:
    """The decoded samples of a dataset folder's archives (archives(source)), or of the given
    archive paths, in order."""
    if isinstance(source, (str, os.PathLike)):
        paths: Iterable[_Path] = archives(source)
    else:
        paths = source
    for path in paths:
        for key, members in samples(path):
            yield decode(key, members, masks)
