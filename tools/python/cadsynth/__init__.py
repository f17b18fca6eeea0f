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

import sys as _sys

# Frames are numpy arrays: without numpy the first frame would fail after seconds of preparing,
# so say it now, naming this interpreter (often a second Python without the packages).
try:
    import numpy as _numpy  # noqa: F401
except ImportError as _missing:
    raise ImportError(
        f"cadsynth needs numpy, which {_sys.executable} (Python "
        f"{_sys.version.split()[0]}) cannot import ({_missing}). Install it for this "
        "interpreter (Debian: apt install python3-numpy, then use /usr/bin/python3), or run "
        "the Python that has it"
    ) from None

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
