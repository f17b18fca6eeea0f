"""cadsynth: CAD to labelled RGB-D frames, straight into Python (docs/python.md).

    import cadsynth
    run = cadsynth.Recipe.load("recipes/bin_picking.yaml").prepare()
    for frame in run.frames():  # dicts of numpy arrays, keys as class Frame in _cadsynth.pyi
        ...

Recipe reads and checks a recipe (a bad one raises cadsynth.Error "FILE:LINE:COLUMN: what");
Recipe.prepare() builds the parts and scenes; Run.frames() renders the frames in the background,
in order, the same frames `cadsynth generate` writes; Run.write() writes them as it does.
cadsynth.torch.FrameDataset feeds a torch DataLoader (imported on use: torch is optional);
cadsynth.webdataset reads the archives of output format `webdataset`, and
cadsynth.torch.ArchiveDataset feeds them to a DataLoader.
"""

from ._cadsynth import (  # noqa: F401
    Error,
    FrameIterator,
    Recipe,
    Run,
    __version__,
    decode_image,
    default_cache,
    encode_depth,
    encode_png,
    evaluate,
    read_image,
)

__all__ = [
    "Error",
    "FrameIterator",
    "Recipe",
    "Run",
    "decode_image",
    "default_cache",
    "encode_depth",
    "encode_png",
    "evaluate",
    "read_image",
]
