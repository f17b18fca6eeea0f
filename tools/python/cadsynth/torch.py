"""cadsynth frames as a PyTorch IterableDataset (docs/python.md, "PyTorch").

    from torch.utils.data import DataLoader
    from cadsynth.torch import FrameDataset, collate
    loader = DataLoader(FrameDataset("recipes/bin_picking.yaml"), batch_size=8,
                        num_workers=4, collate_fn=collate)

Each DataLoader worker renders its own shard of the recipe's work units (unit g goes to worker
g % workers), so the workers together produce exactly the frames one process would. With
endless=True each worker instead walks its own streams of reseeded runs (stream k: Recipe.reseeded
(k), new arrangements, piles, randomisation and views; worker w takes first_stream + w, + workers,
...), for as long as training reads.

Workers prepare their run themselves (parts, piles), after the DataLoader has started them, and
render with cpu_count // workers threads each. uint16 arrays (the instance image, 16-bit grey)
come as int32: torch has no uint16.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Callable, Iterator, Sequence

import numpy as np
import torch
from torch.utils.data import IterableDataset, get_worker_info

from ._cadsynth import Recipe

if TYPE_CHECKING:
    from ._cadsynth import Run

__all__ = ["ArchiveDataset", "FrameDataset", "collate"]

# The keys whose arrays have a row per instance or per grasp (N, M and S in class Frame of
# _cadsynth.pyi; a test holds the two together): their length varies from frame to frame, so
# collate keeps them as lists.
_RAGGED = ("obj_id", "cam_from_model", "bbox_obj", "bbox_visib", "px_count_all", "px_count_valid",
           "px_count_visib", "visib_fract", "mask", "mask_visib", "graspnet", "graspnet_labels",
           "suctionnet", "suctionnet_labels")


class FrameDataset(IterableDataset):
    """The frames of a recipe, as dicts of numpy arrays (Run.frames), for a DataLoader.

    recipe: a Recipe, or a recipe file's path.
    shard: (i, n) to take only shard i of n of the run (a cluster job's share), split further
        among the DataLoader's workers.
    endless: walk reseeded runs without end instead of the recipe's own frames once.
    first_stream: the first stream of an endless walk (0: the recipe's own seeds).
    masks: False leaves out the N x H x W masks (the instance image stays).
    transform: applied to each frame dict before it is yielded.
    threads: rendering threads per worker (default: the cores divided among the workers).
    cache: the part cache (True: the command line's; False; or a folder).
    """

    def __init__(self, recipe: Recipe | str | os.PathLike[str], *,
                 shard: tuple[int, int] | None = None, endless: bool = False,
                 first_stream: int = 0, masks: bool = True,
                 transform: Callable[[dict[str, Any]], Any] | None = None,
                 threads: int | None = None,
                 cache: bool | str | os.PathLike[str] | None = True) -> None:
        super().__init__()
        self.recipe = recipe if isinstance(recipe, Recipe) else Recipe.load(os.fspath(recipe))
        if shard is not None:
            shard = (int(shard[0]), int(shard[1]))
            if not 0 <= shard[0] < shard[1]:
                raise ValueError(f"shard {shard}: i must be in [0, n)")
        self.shard = shard
        self.endless = bool(endless)
        self.first_stream = int(first_stream)
        self.masks = bool(masks)
        self.transform = transform
        self.threads = threads
        self.cache = cache

    def _worker(self) -> tuple[int, int]:
        info = get_worker_info()
        if info is None:
            return 0, 1
        return info.id, info.num_workers

    def __iter__(self) -> Iterator[Any]:
        worker, workers = self._worker()
        threads = self.threads or max(1, (os.cpu_count() or 1) // workers)
        i, n = self.shard if self.shard is not None else (0, 1)
        if not self.endless:
            # Units g with g % n == i, dealt to the workers: g % (n * workers) == i + n * worker.
            run = self.recipe.prepare(cache=self.cache, threads=threads)
            yield from self._frames(run, (i + n * worker, n * workers), threads)
            return
        stream = self.first_stream + worker
        while True:
            run = self.recipe.reseeded(stream).prepare(cache=self.cache, threads=threads)
            yield from self._frames(run, (i, n), threads)
            stream += workers

    def _frames(self, run: Run, shard: tuple[int, int], threads: int) -> Iterator[Any]:
        frames = run.frames(shard=shard, masks=self.masks, threads=threads)
        try:
            for frame in frames:
                frame = _torch_types(frame)
                yield self.transform(frame) if self.transform else frame
        finally:
            frames.close()


class ArchiveDataset(IterableDataset):
    """The frames of webdataset archives (output format `webdataset`), decoded as Run.frames()
    yields them (cadsynth.webdataset.decode), for a DataLoader.

    source: a dataset folder (its webdataset/ manifests list the archives; tasks that have not
        finished yet are left out, complete=True refuses them) or a list of archive paths.
    Archives are dealt out whole: archive a goes to consumer a % consumers, where the consumers
    are every DataLoader worker of every process of torch.distributed (rank r, worker w: consumer
    r * workers + w); each reads its archives as streams, in order, so together they yield every
    frame once. shuffle: each epoch, a seeded permutation of the archives (seed + epoch; call
    set_epoch) before they are dealt out.
    masks, transform: as FrameDataset.
    """

    def __init__(self, source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]], *,
                 complete: bool = False, masks: bool = True, shuffle: bool = False,
                 seed: int = 0,
                 transform: Callable[[dict[str, Any]], Any] | None = None) -> None:
        super().__init__()
        from . import webdataset
        if isinstance(source, (str, os.PathLike)):
            self.archives = [os.fspath(p) for p in webdataset.archives(source, complete)]
        else:
            self.archives = [os.fspath(p) for p in source]
        self.masks = bool(masks)
        self.shuffle = bool(shuffle)
        self.seed = int(seed)
        self.epoch = 0
        self.transform = transform

    def set_epoch(self, epoch: int) -> None:
        self.epoch = int(epoch)

    def _consumer(self) -> tuple[int, int]:
        info = get_worker_info()
        worker, workers = (info.id, info.num_workers) if info is not None else (0, 1)
        rank, ranks = 0, 1
        if torch.distributed.is_available() and torch.distributed.is_initialized():
            rank, ranks = torch.distributed.get_rank(), torch.distributed.get_world_size()
        return rank * workers + worker, ranks * workers

    def mine(self) -> list[str]:
        """The archives this process and worker reads, in order."""
        order = list(self.archives)
        if self.shuffle:
            rng = np.random.default_rng(self.seed + self.epoch)
            order = [order[i] for i in rng.permutation(len(order))]
        consumer, consumers = self._consumer()
        return order[consumer::consumers]

    def __iter__(self) -> Iterator[Any]:
        from . import webdataset
        for path in self.mine():
            for key, members in webdataset.samples(path):
                frame = _torch_types(webdataset.decode(key, members, self.masks))
                yield self.transform(frame) if self.transform else frame


def _torch_types(frame: dict[str, Any]) -> dict[str, Any]:
    """uint16 arrays (the instance image, 16-bit grey) as int32: torch has no uint16."""
    for key, value in frame.items():
        if isinstance(value, np.ndarray) and value.dtype == np.uint16:
            frame[key] = value.astype(np.int32)
        elif key == "sensors":
            frame[key] = [_torch_types(f) for f in value]
    return frame


def collate(frames: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """A batch from frame dicts: arrays of equal shape under one key are stacked into a tensor;
    per-instance arrays (their length varies with the scene) and other values become lists (with
    None for a frame without the key, e.g. 'randomization' in a scene that draws nothing)."""
    batch = {}
    keys = list(dict.fromkeys(key for f in frames for key in f))  # every frame's, in order
    for key in keys:
        values = [f.get(key) for f in frames]  # None where a frame has no such key
        if all(isinstance(v, np.ndarray) for v in values) and \
                len({v.shape for v in values}) == 1 and key not in _RAGGED:
            batch[key] = torch.from_numpy(np.stack(values))
        elif all(isinstance(v, np.ndarray) for v in values):
            batch[key] = [torch.from_numpy(v) for v in values]
        else:
            batch[key] = values
    return batch
