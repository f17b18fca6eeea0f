"""The torch dataset: DataLoader workers share the recipe's frames out exactly."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")
from torch.utils.data import DataLoader  # noqa: E402

import cadsynth  # noqa: E402
from cadsynth.torch import _RAGGED, FrameDataset, collate  # noqa: E402
from conftest import stub_frame_keys  # noqa: E402


def key(frame):
    return (int(frame["scene_id"]), int(frame["im_id"]))


def test_two_workers_yield_the_frames_of_one_process(recipe_file):
    one = {key(f): f for f in FrameDataset(recipe_file, masks=False)}
    loader = DataLoader(FrameDataset(recipe_file, masks=False), batch_size=None, num_workers=2)
    two = {}
    for f in loader:
        assert key(f) not in two
        two[key(f)] = f
    assert sorted(two) == sorted(one) and len(one) == 6
    for k, f in two.items():
        # The default collation turned the arrays into tensors; the values are the same.
        assert np.array_equal(f["rgb"].numpy(), one[k]["rgb"])
        assert np.array_equal(f["depth"].numpy(), one[k]["depth"])
        assert np.array_equal(f["cam_from_model"].numpy(), one[k]["cam_from_model"])


def test_batches_and_endless_streams(recipe_file):
    loader = DataLoader(FrameDataset(recipe_file, endless=True, masks=False), batch_size=4,
                        num_workers=2, collate_fn=collate)
    batches = []
    for batch in loader:
        batches.append(batch)
        if len(batches) == 3:
            break
    # Batches alternate between the workers; the third (worker 0's second) runs from the end of
    # stream 0 into stream 2.
    assert batches[0]["rgb"].shape == (4, 120, 160, 3)
    assert batches[0]["rgb"].dtype == torch.uint8
    assert len(batches[0]["cam_from_model"]) == 4
    assert batches[0]["cam_from_model"][0].shape == (2, 4, 4)
    # Worker 0 renders stream 0 (the recipe's own frames), worker 1 stream 1 (new draws).
    own = cadsynth.Recipe.load(recipe_file).prepare().frame(0, masks=False)
    assert np.array_equal(batches[0]["rgb"][0].numpy(), own["rgb"])
    assert batches[1]["randomization"][0] != own["randomization"]


def test_a_shard_of_the_dataset_is_split_among_workers(recipe_file):
    loader = DataLoader(FrameDataset(recipe_file, shard=(1, 2), masks=False), batch_size=None,
                        num_workers=2)
    units = sorted(f["scene_id"] * 3 + f["im_id"] for f in loader)
    assert units == [1, 3, 5]


def test_spawned_workers_get_the_recipe_by_pickle(recipe_file):
    loader = DataLoader(FrameDataset(cadsynth.Recipe.load(recipe_file), masks=False),
                        batch_size=None, num_workers=2, multiprocessing_context="spawn")
    assert sorted(key(f) for f in loader) == [(s, v) for s in (0, 1) for v in range(3)]


def test_collate_keeps_keys_some_frames_lack():
    a = {"im_id": 0, "rgb": np.zeros((2, 3, 3), np.uint8), "randomization": "{}"}
    b = {"im_id": 1, "rgb": np.ones((2, 3, 3), np.uint8)}
    batch = collate([a, b])
    assert batch["rgb"].shape == (2, 2, 3, 3)
    assert batch["randomization"] == ["{}", None]
    assert batch["im_id"] == [0, 1]


def test_collate_lists_the_keys_the_stub_gives_rows_per_instance_or_grasp():
    # Frame's arrays whose first dimension is a count (N instances, M or S grasp rows), not the
    # image's height or a fixed size.
    ragged = {key for key, (*_, shape) in stub_frame_keys().items()
              if shape and not shape[0].isdigit() and shape[0] != "H"}
    assert set(_RAGGED) == ragged
