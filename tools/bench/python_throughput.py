#!/usr/bin/env python3
"""Frames per second through the Python iterator (no files written) against `cadsynth generate`
writing the same recipe (docs/benchmarks.md). Both read the parts from a warm part cache.

    PYTHONPATH=build/python python3 tools/bench/python_throughput.py [RECIPE] [--cli build/tools/cadsynth]

Without RECIPE: the default job. Each is run `--repeat` times; the best is reported.
"""

import argparse
import os
import pathlib
import shutil
import subprocess
import tempfile
import time

import cadsynth


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipe", nargs="?")
    parser.add_argument("--cli", default=str(pathlib.Path(__file__).resolve().parents[2] /
                                             "build" / "tools" / "cadsynth"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-masks", action="store_true", help="frames without N x H x W masks")
    args = parser.parse_args()

    recipe = cadsynth.Recipe.load(args.recipe) if args.recipe else cadsynth.Recipe.default()
    recipe.prepare()  # warms the part cache
    tmp = pathlib.Path(tempfile.mkdtemp())
    cli_best = py_best = None
    frames = 0
    try:
        for _ in range(args.repeat):
            out = tmp / "cli"
            command = [args.cli, "generate"] + ([args.recipe] if args.recipe else []) + \
                ["-o", str(out), "--overwrite", "--quiet"]
            t0 = time.perf_counter()
            subprocess.run(command, check=True)
            cli = time.perf_counter() - t0
            cli_best = cli if cli_best is None else min(cli_best, cli)

            t0 = time.perf_counter()
            run = recipe.prepare()
            prepared = time.perf_counter() - t0
            frames = 0
            for frame in run.frames(masks=not args.no_masks):
                frames += 1
            py = time.perf_counter() - t0
            py_best = py if py_best is None else min(py_best, py)
            print(f"cli {cli:.2f} s; python {py:.2f} s (prepare {prepared:.2f} s), {frames} frames")
    finally:
        shutil.rmtree(tmp)
    print(f"best: cli {frames / cli_best:.1f} frames/s (writing), python {frames / py_best:.1f} "
          f"frames/s (iterating): {100 * cli_best / py_best:.0f}% of the cli's rate; "
          f"{os.cpu_count()} cores")


if __name__ == "__main__":
    main()
