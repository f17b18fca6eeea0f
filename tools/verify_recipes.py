#!/usr/bin/env python3
"""Renders the first views of every shipped recipe and puts each dataset through
`cadsynth verify`: the check that every recipe writes labels the verifier recomputes
(docs/cli.md#verify).

  tools/verify_recipes.py --cadsynth build/tools/cadsynth [--views 1] [--recipes a,b]
                          [--skip c,d] [--keep DIR]

Recipes are cut as tools/compare_outputs.py cuts them (copies in a hidden folder beside recipes/). Recipes that need the shared third-party
data are skipped, saying so, where it is absent. Prints each recipe's verdict and its time; exit 1
when a run or a verification fails.
"""
import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import yaml

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from compare_outputs import ROOT, cut  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cadsynth", required=True)
    parser.add_argument("--views", type=int, default=1)
    parser.add_argument("--recipes", default="", help="comma-separated names (default: all)")
    parser.add_argument("--skip", default="", help="comma-separated names to leave out")
    parser.add_argument("--keep", help="keep the datasets in this folder")
    args = parser.parse_args()
    names = [n for n in args.recipes.split(",") if n]
    skip = [n for n in args.skip.split(",") if n]
    recipes = sorted(p for p in (ROOT / "recipes").glob("*.yaml")
                     if not p.name.startswith("_") and (not names or p.stem in names)
                     and p.stem not in skip)
    work = pathlib.Path(args.keep or tempfile.mkdtemp(prefix="cadsynth-verify-"))
    work.mkdir(parents=True, exist_ok=True)
    shared = (ROOT / ".." / "shared" / "data").resolve()
    # The cut copies go to a hidden folder beside recipes/ (their relative paths, ../../shared,
    # resolve the same), not into recipes/, which other tests read while this one runs.
    cuts = pathlib.Path(tempfile.mkdtemp(prefix=".verify-recipes-", dir=ROOT))
    failed = []
    for path in recipes:
        text = path.read_text()
        if "shared/data" in text and not shared.is_dir():
            print(f"skip {path.name}: needs {shared}")
            continue
        copy = cuts / path.name
        copy.write_text(yaml.safe_dump(cut(yaml.safe_load(text), args.views), sort_keys=False))
        out = work / path.stem
        shutil.rmtree(out, ignore_errors=True)
        env = dict(os.environ, CADSYNTH_CACHE=str(work / "cache"))
        start = time.monotonic()
        try:
            run = subprocess.run([args.cadsynth, "generate", str(copy), "-o", str(out), "--quiet"],
                                 capture_output=True, text=True, env=env)
        finally:
            copy.unlink()
        seconds = time.monotonic() - start
        if run.returncode != 0:
            failed.append(path.name)
            print(f"{path.name}: generate failed: {run.stderr.strip()}")
            continue
        start = time.monotonic()
        check = subprocess.run([args.cadsynth, "verify", str(out)], capture_output=True, text=True)
        verdict = check.stdout.strip().splitlines()[-1] if check.stdout.strip() else check.stderr
        print(f"{path.name}: generate {seconds:.1f} s, verify {time.monotonic() - start:.1f} s: "
              f"{verdict}", flush=True)
        if check.returncode != 0:
            failed.append(path.name)
            print(check.stdout)
    shutil.rmtree(cuts, ignore_errors=True)
    print(f"{len(recipes)} recipes, {len(failed)} failed" + (": " + ", ".join(failed) if failed else ""))
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
