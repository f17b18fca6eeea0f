#!/usr/bin/env python3
"""The reference paper's loop, closed: a small pose estimator trained on CPU straight from
cadsynth's frames, scored by `cadsynth eval` (docs/python.md, "Training a pose estimator").

    PYTHONPATH=build/python python3 tools/python/examples/train_pose.py --out out/train_pose

1. The test set is the paper's assembly-benchmark demo set (round and square peg, faceplate,
   stepped shaft, M10 bolt on a grid) seen by the paper's 144-view sweep with its Kinect v1; it
   is written as a BOP dataset (its test split: every 4th view, as the paper).
2. Training frames come from the iterator, never from files: the same five parts dropped apart
   in a disc (random resting face and yaw), each stream of the recipe (Recipe.reseeded) a new
   arrangement seen from new random views over the sweep's band.
3. The model, per visible instance: its visible pixels (the frame's mask_visib: ground-truth
   segmentation stands in for a detector) back-projected with the depth into camera-frame
   points, centred on their mean; a PointNet (shared MLP, max pool) with the object's one-hot
   regresses the rotation (6D, Gram-Schmidt) and the model origin's offset from the mean.
   Loss: ADD-S on the model's points (every object of the set is symmetric).
4. Test-split estimates go to a BOP results CSV, and so do those of a trivial baseline (each
   object's mean training pose in the camera); cadsynth.evaluate (the function behind
   `cadsynth eval`) prints the paper's Table II columns for both.
"""

import argparse
import json
import os
import pathlib
import time

import numpy as np
import torch
from torch import nn

import cadsynth

PARTS = [
    {"family": "round_peg"},
    {"family": "square_peg"},
    {"family": "faceplate"},
    {"family": "stepped_shaft"},
    {"family": "hex_bolt", "params": {"size": "M10", "length": "40 mm"}},
]
# The paper's sweep (the default job's): yaw every 30 degrees, pitch 15-75 by 20, three radii.
TEST_RECIPE = {
    "scenes": [{"name": "assembly_benchmark", "layout": "grid", "gap": "30 mm", "parts": PARTS}],
    "camera": {"preset": "kinect_v1"},
    "sweep": {"yaw": {"from": 0, "to": 330, "step": 30}, "pitch": [15, 35, 55, 75],
              "radius": ["0.65 m", "1.05 m", "1.45 m"]},
}
# Training: the parts apart in a disc, random resting faces and yaws, random views in the band.
TRAIN_RECIPE = {
    "scenes": [{"name": "train", "layout": "clutter", "pose": "random", "radius": "200 mm",
                "gap": "20 mm", "parts": PARTS}],
    "camera": {"preset": "kinect_v1"},
    "sweep": {"sampler": "random", "count": 200,
              "yaw": {"from": 0, "to": 359, "step": 1}, "pitch": {"from": 10, "to": 80, "step": 1},
              "radius": {"from": "0.6 m", "to": "1.5 m", "step": "0.01 m"}},
}
POINTS = 256        # points per instance fed to the network
KEEP = 1024         # visible points kept per training instance (POINTS drawn from them per step)
MODEL_POINTS = 300  # model points in the loss
SCALE = 100.0       # mm per network unit


def read_ply_points(path):
    """x, y, z of an ASCII PLY (models/points/obj_ID.ply)."""
    lines = pathlib.Path(path).read_text().splitlines()
    start = lines.index("end_header") + 1
    return np.array([[float(v) for v in line.split()[:3]] for line in lines[start:] if line],
                    dtype=np.float32)


def instance_points(frame, i, rng, keep):
    """Camera-frame points (mm) of instance i's visible pixels, at most `keep` of them."""
    v, u = np.nonzero(frame["mask_visib"][i])
    z = frame["depth"][v, u]
    ok = z > 0
    u, v, z = u[ok], v[ok], z[ok]
    if len(z) == 0:
        return None
    if len(z) > keep:
        pick = rng.choice(len(z), keep, replace=False)
        u, v, z = u[pick], v[pick], z[pick]
    k = frame["K"]
    x = (u - k[0, 2]) * z / k[0, 0]
    y = (v - k[1, 2]) * z / k[1, 1]
    return np.stack([x, y, z], axis=1).astype(np.float32)


class PointNetPose(nn.Module):
    def __init__(self, objects):
        super().__init__()
        self.objects = objects
        self.features = nn.Sequential(
            nn.Conv1d(3, 64, 1), nn.BatchNorm1d(64), nn.ReLU(),
            nn.Conv1d(64, 128, 1), nn.BatchNorm1d(128), nn.ReLU(),
            nn.Conv1d(128, 512, 1), nn.BatchNorm1d(512), nn.ReLU())
        self.head = nn.Sequential(
            nn.Linear(512 + objects, 256), nn.ReLU(), nn.Linear(256, 128), nn.ReLU(),
            nn.Linear(128, 9))

    def forward(self, points, obj):
        """points: B x POINTS x 3 (centred, network units); obj: B (0-based). Returns the
        rotation B x 3 x 3 and the origin's offset from the points' mean, B x 3 (units)."""
        f = self.features(points.transpose(1, 2)).max(dim=2).values
        out = self.head(torch.cat([f, nn.functional.one_hot(obj, self.objects).float()], dim=1))
        a, b = out[:, 0:3], out[:, 3:6]
        x = nn.functional.normalize(a, dim=1)
        y = nn.functional.normalize(b - (x * b).sum(1, keepdim=True) * x, dim=1)
        rotation = torch.stack([x, y, torch.cross(x, y, dim=1)], dim=2)
        return rotation, out[:, 6:9]


def adds_loss(rotation, offset, gt_rotation, gt_offset, model):
    """Mean distance from each predicted model point to the closest true one (network units)."""
    predicted = model @ rotation.transpose(1, 2) + offset[:, None, :]
    truth = model @ gt_rotation.transpose(1, 2) + gt_offset[:, None, :]
    return torch.cdist(predicted, truth).min(dim=2).values.mean()


def collect(recipe, streams, rng, log):
    """Training instances from `streams` reseeded runs: points, object, pose."""
    samples = []
    poses = {}
    start = time.perf_counter()
    frames = 0
    for stream in range(streams):
        run = recipe.reseeded(stream).prepare()
        for frame in run.frames():
            frames += 1
            for i, obj in enumerate(frame["obj_id"]):
                pose = frame["cam_from_model"][i]
                poses.setdefault(int(obj), []).append(pose)
                if frame["px_count_visib"][i] < 30:
                    continue
                pts = instance_points(frame, i, rng, KEEP)
                if pts is None or len(pts) < 30:
                    continue
                samples.append((pts, int(obj) - 1, pose[:3, :3].astype(np.float32),
                                pose[:3, 3].astype(np.float32)))
        log(f"  stream {stream}: {frames} frames, {len(samples)} instances "
            f"({time.perf_counter() - start:.0f} s)")
    return samples, poses


def centred(points, rng):
    """POINTS of `points` (drawn), centred on their mean, in network units; and the mean (mm)."""
    q = points[rng.choice(len(points), POINTS, replace=len(points) < POINTS)]
    mean = q.mean(axis=0)
    return (q - mean) / SCALE, mean


def batch_of(samples, indices, rng):
    pts, obj, rot, off = [], [], [], []
    for k in indices:
        p, o, r, t = samples[k]
        q, mean = centred(p, rng)
        pts.append(q)
        obj.append(o)
        rot.append(r)
        off.append((t - mean) / SCALE)
    return (torch.from_numpy(np.stack(pts)), torch.tensor(obj), torch.from_numpy(np.stack(rot)),
            torch.from_numpy(np.stack(off)))


def mean_pose(poses):
    """The chordal mean of the rotations (SVD of their sum) and the mean translation."""
    stack = np.stack(poses)
    u, _, vt = np.linalg.svd(stack[:, :3, :3].sum(axis=0))
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    out = np.eye(4)
    out[:3, :3] = r
    out[:3, 3] = stack[:, :3, 3].mean(axis=0)
    return out


def result_line(scene, im, obj, pose, seconds):
    r = " ".join(f"{v:.9g}" for v in pose[:3, :3].flatten())
    t = " ".join(f"{v:.6f}" for v in pose[:3, 3])
    return f"{scene},{im},{obj},1,{r},{t},{seconds:.4f}\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/train_pose", help="folder for the test dataset "
                        "and the results files")
    parser.add_argument("--streams", type=int, default=8, help="training runs (reseeded)")
    parser.add_argument("--views", type=int, default=200, help="views per training run")
    parser.add_argument("--minutes", type=float, default=8.0, help="training time")
    parser.add_argument("--steps", type=int, default=0,
                        help="stop after this many steps instead (0: train for --minutes)")
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--report", help="also write both evaluations to this JSON file")
    args = parser.parse_args()
    started = time.perf_counter()
    torch.manual_seed(args.seed)
    torch.set_num_threads(os.cpu_count() or 1)
    rng = np.random.default_rng(args.seed)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    def log(line):
        print(f"[{time.perf_counter() - started:6.0f} s] {line}", flush=True)

    # 1. The test set, written as BOP (the ground truth eval reads).
    test = cadsynth.Recipe.from_dict(TEST_RECIPE).prepare()
    dataset = out / "dataset"
    test.write(dataset, overwrite=True)
    objects = test.objects
    models = []
    for o in objects:
        pts = read_ply_points(dataset / "models" / "points" / f"obj_{o['obj_id']:06d}.ply")
        models.append(pts[rng.choice(len(pts), MODEL_POINTS, replace=False)] / SCALE)
    models = torch.from_numpy(np.stack(models))
    log(f"test set: {dataset} ({test.views} views of {len(objects)} objects)")

    # 2. Training instances, straight from the iterator.
    train_recipe = dict(TRAIN_RECIPE, sweep=dict(TRAIN_RECIPE["sweep"], count=args.views))
    log(f"rendering {args.streams} training runs of {args.views} views")
    samples, train_poses = collect(cadsynth.Recipe.from_dict(train_recipe), args.streams, rng, log)

    # 3. Training.
    model = PointNetPose(len(objects))
    optimiser = torch.optim.Adam(model.parameters(), lr=1e-3)
    deadline = time.perf_counter() + 60.0 * args.minutes
    step, running = 0, None
    train_start = time.perf_counter()
    lr_dropped = False
    model.train()
    while (step < args.steps) if args.steps > 0 else (time.perf_counter() < deadline):
        indices = rng.choice(len(samples), args.batch, replace=False)
        pts, obj, rot, off = batch_of(samples, indices, rng)
        rotation, offset = model(pts, obj)
        loss = adds_loss(rotation, offset, rot, off, models[obj])
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        running = loss.item() if running is None else 0.98 * running + 0.02 * loss.item()
        step += 1
        late = (step > 0.75 * args.steps if args.steps > 0 else
                time.perf_counter() > train_start + 0.75 * 60.0 * args.minutes)
        if not lr_dropped and late:
            for group in optimiser.param_groups:
                group["lr"] = 1e-4
            lr_dropped = True
        if step % 500 == 0:
            log(f"  step {step}: ADD-S loss {running * SCALE:.1f} mm")
    log(f"trained {step} steps of {args.batch} in {(time.perf_counter() - train_start) / 60:.1f} "
        "min")

    # 4. Test-split estimates, and the baseline's.
    model.eval()
    baseline = {obj: mean_pose(p) for obj, p in train_poses.items()}
    estimates, trivial = [], []
    with torch.no_grad():
        for frame in test.frames():
            if frame["split"] != "test":
                continue
            for i, obj in enumerate(frame["obj_id"]):
                obj = int(obj)
                trivial.append(result_line(frame["scene_id"], frame["im_id"], obj, baseline[obj],
                                           0.0))
                t0 = time.perf_counter()
                pts = instance_points(frame, i, rng, 100000)
                if pts is None or len(pts) < 3:
                    pose = baseline[obj]
                else:
                    q, mean = centred(pts, rng)
                    rotation, offset = model(torch.from_numpy(q[None]), torch.tensor([obj - 1]))
                    pose = np.eye(4)
                    pose[:3, :3] = rotation[0].numpy()
                    pose[:3, 3] = offset[0].numpy() * SCALE + mean
                estimates.append(result_line(frame["scene_id"], frame["im_id"], obj, pose,
                                             time.perf_counter() - t0))
    reports = {}
    for name, lines in (("pointnet", estimates), ("baseline", trivial)):
        path = out / f"results_{name}.csv"
        path.write_text("scene_id,im_id,obj_id,score,R,t,time\n" + "".join(lines))
        table, reports[name] = cadsynth.evaluate(dataset, path)
        print(f"\n{name} ({path}; `cadsynth eval {dataset} {path}` prints the same):\n{table}")
    if args.report:
        pathlib.Path(args.report).write_text(json.dumps(reports, indent=2))
    log(f"done in {(time.perf_counter() - started) / 60:.1f} min")


if __name__ == "__main__":
    main()
