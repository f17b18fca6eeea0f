#!/usr/bin/env python3
"""Batches of cadsynth frames from a torch DataLoader, and how fast they come (docs/python.md, "PyTorch").

    PYTHONPATH=build/python python3 tools/python/examples/batches.py recipes/bin_picking.yaml \
        --workers 2 --batch 4 --batches 10

Trains nothing: it shows what a batch holds and measures frames per second through the loader.
"""

import argparse
import time

from torch.utils.data import DataLoader

from cadsynth.torch import FrameDataset, collate


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipe")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--batch", type=int, default=4)
    parser.add_argument("--batches", type=int, default=10)
    parser.add_argument("--endless", action="store_true", help="reseeded runs without end")
    args = parser.parse_args()

    dataset = FrameDataset(args.recipe, endless=args.endless, masks=False)
    loader = DataLoader(dataset, batch_size=args.batch, num_workers=args.workers,
                        collate_fn=collate)
    start = time.perf_counter()
    frames = 0
    for n, batch in enumerate(loader):
        if n == 0:
            first = time.perf_counter() - start
            for key, value in batch.items():
                if hasattr(value, "shape"):
                    print(f"  {key:16s} {tuple(value.shape)} {value.dtype}")
                elif isinstance(value, list) and hasattr(value[0], "shape"):
                    print(f"  {key:16s} {len(value)} x {tuple(value[0].shape)} (per frame)")
            start = time.perf_counter()
        else:
            frames += len(batch["im_id"])
        if n + 1 == args.batches:
            break
    seconds = time.perf_counter() - start
    print(f"first batch after {first:.1f} s (preparing the run); then {frames} frames in "
          f"{seconds:.1f} s: {frames / max(seconds, 1e-9):.1f} frames/s")


if __name__ == "__main__":
    main()
