#!/usr/bin/env python3
"""Renders the first views of every shipped recipe with two cadsynth builds and compares the
output trees byte for byte: the check that a restructuring changed no output (docs/testing.md).

  tools/compare_outputs.py --before OLD/cadsynth --after build/tools/cadsynth [--views 2]
                           [--recipes pbr_demo,clutter] [--keep DIR]

Each recipe is copied beside itself (so its relative paths still resolve) with its sweep cut to
its first views; both builds run it with a part cache of their own. Recipes that need the shared
third-party data are skipped, saying so, where it is absent. Exit 1 naming every file that
differs, or that one tree has and the other lacks.
"""
import argparse
import filecmp
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

import yaml

ROOT = pathlib.Path(__file__).resolve().parent.parent


def first(value, n):
    """The first n values of a sweep axis: a value, a list, or {from, to, step}."""
    if isinstance(value, list):
        return value[:n]
    if isinstance(value, dict) and "from" in value:
        return value["from"]  # one value: a range's step may carry a unit
    return value


def cut(recipe, views):
    sweep = recipe.setdefault("sweep", {})
    if sweep.get("sampler", "grid") == "grid":
        sweep["yaw"] = first(sweep.get("yaw", {"from": 0, "to": 330, "step": 30}), views)
        if isinstance(sweep["yaw"], (int, float, str)):
            sweep["yaw"] = [sweep["yaw"]]
        sweep["pitch"] = first(sweep.get("pitch", 15), 1)
        sweep["radius"] = first(sweep.get("radius", "0.65 m"), 1)
        if isinstance(sweep["pitch"], list):
            sweep["pitch"] = sweep["pitch"][0]
        if isinstance(sweep["radius"], list):
            sweep["radius"] = sweep["radius"][0]
    else:
        sweep["count"] = views
    return recipe


def files(tree):
    """Every file of the tree but run.json (how the run went: its time differs every run)."""
    return sorted(p.relative_to(tree) for p in tree.rglob("*")
                  if p.is_file() and p != tree / "run.json")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", required=True)
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--recipes", default="", help="comma-separated names (default: all)")
    parser.add_argument("--keep", help="keep the outputs in this folder")
    args = parser.parse_args()
    names = [n for n in args.recipes.split(",") if n]
    recipes = sorted(p for p in (ROOT / "recipes").glob("*.yaml")
                     if not p.name.startswith("_cmp_") and (not names or p.stem in names))
    work = pathlib.Path(args.keep or tempfile.mkdtemp(prefix="cadsynth-compare-"))
    work.mkdir(parents=True, exist_ok=True)
    shared = (ROOT / ".." / "shared" / "data").resolve()
    differing, compared = [], 0
    for path in recipes:
        text = path.read_text()
        if "shared/data" in text and not shared.is_dir():
            print(f"skip {path.name}: needs {shared}")
            continue
        copy = path.with_name("_cmp_" + path.name)
        copy.write_text(yaml.safe_dump(cut(yaml.safe_load(text), args.views), sort_keys=False))
        try:
            trees = {}
            for side, exe in (("before", args.before), ("after", args.after)):
                out = work / side / path.stem
                shutil.rmtree(out, ignore_errors=True)
                env = dict(os.environ, CADSYNTH_CACHE=str(work / f"cache_{side}"))
                run = subprocess.run([exe, "generate", str(copy), "-o", str(out), "--quiet"],
                                     capture_output=True, text=True, env=env)
                if run.returncode != 0:
                    differing.append(f"{path.name}: {side} failed: {run.stderr.strip()}")
                    break
                trees[side] = out
        finally:
            copy.unlink()
        if len(trees) != 2:
            continue
        a, b = files(trees["before"]), files(trees["after"])
        for rel in sorted(set(a) ^ set(b)):
            differing.append(f"{path.name}: {rel} only {'before' if rel in a else 'after'}")
        same = [rel for rel in a if rel in set(b)]
        for rel in same:
            if not filecmp.cmp(trees["before"] / rel, trees["after"] / rel, shallow=False):
                differing.append(f"{path.name}: {rel} differs")
        compared += len(same)
        print(f"{path.name}: {len(same)} files compared")
    for line in differing:
        print("DIFF " + line)
    print(f"{compared} files compared, {len(differing)} differences")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
