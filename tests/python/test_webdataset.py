"""Archives of output format `webdataset` decode to the arrays Run.frames() gives, through the
standard library's tarfile and a DataLoader with and without workers."""

import json
import subprocess
import tarfile

import numpy as np
import pytest

import cadsynth
from cadsynth import webdataset
from conftest import CLI, RECIPE

ARCHIVE_RECIPE = RECIPE + "output: {formats: [bop, webdataset], archive_samples: 4}\n"


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The recipe written once (6 frames, archives of at most 4 samples) and its frames."""
    out = tmp_path_factory.mktemp("wds") / "out"
    recipe = cadsynth.Recipe.from_yaml(ARCHIVE_RECIPE)
    recipe.write(out)
    return out, list(recipe.prepare().frames())


def expect_frame_equal(archived, frame):
    # Every key of the frames iterator is decoded, except the two the files do not hold exactly.
    assert set(frame) - set(archived) == {"normals", "radiance", "samples"} & set(frame)
    assert set(archived) <= set(frame)
    for key, value in frame.items():
        if key not in archived:
            continue
        got = archived[key]
        if key in ("depth", "depth_gt"):
            # As the PNG holds it: rounded to depth_scale.
            scale = frame["depth_scale"]
            assert got.dtype == np.float32
            assert np.array_equal(got, cadsynth.encode_depth(value, scale).astype(np.float32)
                                  * np.float32(scale)), key
        elif key == "randomization":
            assert json.loads(got) == json.loads(value)
        elif isinstance(value, np.ndarray):
            assert got.dtype == value.dtype and got.shape == value.shape, key
            assert np.array_equal(got, value), key
        else:
            assert got == value, key


def test_archives_decode_to_the_frames_iterators_arrays(written):
    out, frames = written
    manifest, = webdataset.manifests(out)
    assert manifest["samples"] == 6 and [a["samples"] for a in manifest["archives"]] == [4, 2]
    archived = list(webdataset.frames(out))
    assert [(f["scene_id"], f["im_id"]) for f in archived] == \
        [(f["scene_id"], f["im_id"]) for f in frames]
    # This recipe has a structured-light depth sensor, randomised lights and grasp labels.
    assert {"depth_gt", "randomization", "graspnet", "split", "rgb"} <= set(archived[0])
    for a, f in zip(archived, frames):
        expect_frame_equal(a, f)


def test_members_follow_bops_webdataset_convention(written):
    out, _ = written
    with tarfile.open(webdataset.archives(out)[0]) as tar:
        names = tar.getnames()
        camera = json.load(tar.extractfile("000000_000001.camera.json"))
    # bop_toolkit's bop_webdataset.decode_sample reads these members of each sample.
    for member in ("camera.json", "gt.json", "gt_info.json", "rgb.png", "depth.png"):
        assert f"000000_000000.{member}" in names
    assert len(camera["cam_K"]) == 9 and camera["depth_scale"] == 0.1
    assert all(info.mtime == 0 and info.uid == 0 for info in tarfile.open(
        webdataset.archives(out)[0]).getmembers())


def test_a_dataloader_with_0_and_2_workers_reads_every_frame_once(written):
    torch = pytest.importorskip("torch")
    from torch.utils.data import DataLoader
    from cadsynth.torch import ArchiveDataset
    out, frames = written
    expected = {(f["scene_id"], f["im_id"]): f for f in frames}
    for workers in (0, 2):
        seen = {}
        loader = DataLoader(ArchiveDataset(out), batch_size=None, num_workers=workers)
        for f in loader:
            key = (int(f["scene_id"]), int(f["im_id"]))
            assert key not in seen
            seen[key] = f
        assert sorted(seen) == sorted(expected)
        for key, f in seen.items():
            assert np.array_equal(np.asarray(f["rgb"]), expected[key]["rgb"])
            assert np.array_equal(np.asarray(f["mask_visib"]), expected[key]["mask_visib"])
    # Two workers: each reads whole archives, worker w the archives a with a % 2 == w.
    dataset = ArchiveDataset(out)
    assert len(dataset.archives) == 2
    assert ArchiveDataset(out, shuffle=True, seed=3).mine() != [] and \
        sorted(ArchiveDataset(out, shuffle=True, seed=3).mine()) == sorted(dataset.archives)


def test_farm_tasks_archives_are_readable_before_the_merge(tmp_path):
    recipe = tmp_path / "r.yaml"
    recipe.write_text(ARCHIVE_RECIPE)
    out = tmp_path / "farm"
    subprocess.run([CLI, "generate", recipe, "-o", out, "--shard", "1/2", "--quiet"], check=True)
    # Task 1 of 2 is done: its frames can be read; the run is not complete.
    assert [(f["scene_id"], f["im_id"]) for f in webdataset.frames(out, masks=False)] == \
        [(0, 1), (1, 0), (1, 2)]
    with pytest.raises(ValueError, match=r"tasks without a manifest: \[0\]"):
        webdataset.archives(out, complete=True)
    subprocess.run([CLI, "generate", recipe, "-o", out, "--shard", "0/2", "--quiet"], check=True)
    assert len(list(webdataset.frames(out, masks=False))) == 6
    subprocess.run([CLI, "merge", out], check=True, capture_output=True)
    assert (out / "train" / "000001" / "rgb" / "000002.png").exists()
