#!/usr/bin/env python3
"""Training frames for the denoiser network (render/denoise.h, DenoiseWithNetwork): cadsynth's own
physically based renders of the shipped recipes, each view twice, with independent sampler seeds:
a noisy render at a low sample count with what the denoiser reads (the radiance, the first
surface's albedo and shading normal, the depth, the variance of each pixel's mean) and a target
render of many samples. The target need not be clean: the network is trained with a squared error,
whose minimiser is the target's mean (Noise2Noise, Lehtinen et al. 2018).

    PYTHONPATH=build/python python3 tools/denoiser/make_data.py --out /tmp/denoiser_data

Writes one OUT/<recipe>_s<stream>_u<unit>.npz per view (float16 planes, see save()). The views the
equal-error benchmark measures (pbr_demo's view 0 of every scene, tools/bench/equal_error.py) are
left out.
"""
import argparse
import copy
import os
import sys
import time

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# (recipe, streams, views per scene and stream): streams reseed the recipe's randomisation and
# view sampling (Recipe.reseeded), so each one is new scenes' looks or new views.
PLAN = [
    ("pbr_demo.yaml", [0], 8),
    ("randomized.yaml", [0, 1, 2, 3, 4], 2),
]
NOISY_SAMPLES = [1, 2, 4, 8]


def recipe_with(cadsynth, path, samples, seed, stream):
    with open(path) as f:
        spec = yaml.safe_load(f)
    spec = copy.deepcopy(spec)
    render = spec.setdefault("render", {})
    render.update({"samples": samples, "noise_threshold": 0, "min_samples": 0, "denoise": False,
                   "hdr": True, "seed": seed})
    spec.setdefault("output", {})["dir"] = "/tmp/unused"
    recipe = cadsynth.Recipe.from_dict(spec, base_dir=os.path.dirname(path))
    return recipe.reseeded(stream) if stream else recipe


def save(path, noisy, target):
    planes = {"depth": noisy["depth"], "instance": noisy["instance"].astype(np.int32),
              "albedo": noisy["denoiser_albedo"], "normal": noisy["denoiser_normal"],
              "target": target["radiance"]}
    for s, frame in noisy["by_samples"].items():
        planes[f"radiance_{s}"] = frame["denoiser_radiance"]
        planes[f"variance_{s}"] = frame["denoiser_variance"]
    np.savez(path, **{k: (v.astype(np.float16) if v.dtype == np.float32 and k != "depth" else v)
                      for k, v in planes.items()})


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--target-samples", type=int, default=64)
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    import cadsynth
    os.makedirs(args.out, exist_ok=True)
    for name, streams, per_scene in PLAN:
        path = os.path.join(ROOT, "recipes", name)
        for stream in streams:
            runs = {s: recipe_with(cadsynth, path, s, 1000 + s, stream).prepare(
                threads=args.threads, denoiser_inputs=True) for s in NOISY_SAMPLES}
            target_run = recipe_with(cadsynth, path, args.target_samples, 7, stream).prepare(
                threads=args.threads)
            views = target_run.views
            for scene in range(target_run.scenes):
                # Evenly spread views; pbr_demo's view 0 is the benchmark's.
                first = 1 if name == "pbr_demo.yaml" else 0
                picks = np.linspace(first, views - 1, per_scene).round().astype(int)
                for view in sorted(set(picks.tolist())):
                    unit = scene * views + view
                    out = os.path.join(args.out, f"{name[:-5]}_s{stream}_u{unit}.npz")
                    if os.path.exists(out):
                        continue
                    start = time.time()
                    frames = {s: run.frame(unit, masks=False) for s, run in runs.items()}
                    target = target_run.frame(unit, masks=False)
                    noisy = dict(frames[NOISY_SAMPLES[0]])
                    noisy["by_samples"] = frames
                    save(out, noisy, target)
                    print(f"{out}: {time.time() - start:.1f} s", flush=True)


if __name__ == "__main__":
    sys.exit(main())
