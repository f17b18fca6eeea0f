"""Types of cadsynth's compiled part (tools/python/*.cpp) for editors and type checkers; what each
function does is in its docstring (help()) and in docs/python.md.

class Frame below is the one list of a frame's keys: docs/python.md, the module's docstrings and
cadsynth.torch refer to it, and tests/python/test_frames.py checks it against real frames (every
key a frame holds is here with its dtype and shape, and every key here is produced). To annotate
with it:

    from typing import TYPE_CHECKING
    if TYPE_CHECKING:
        from cadsynth._cadsynth import Frame
"""

import os
import pathlib
from typing import Any, NotRequired, TypeAlias, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str

_StrPath: TypeAlias = str | os.PathLike[str]
# (i, n) or "i/n": the work units g with g % n == i (as `cadsynth generate --shard i/n`).
_Shard: TypeAlias = tuple[int, int] | str
# True: the command line's part cache; False or None: none; or a folder.
_Cache: TypeAlias = bool | _StrPath | None

class Error(RuntimeError):
    """A bad recipe ("FILE:LINE:COLUMN: what"), a file that cannot be read, a failed render."""

class Frame(TypedDict):
    """One view as one sensor sees it: what Run.frames() yields and Run.frame() returns, exactly
    what `cadsynth generate` encodes into the files named below (docs/formats.md).

    Shapes are numpy's: H and W the image's height and width, N the scene's instances in
    scene_gt.json's order (instance i: obj_id[i], mask[i], instance image value i + 1), M and S
    the frame's grasp and suction rows. Lengths are mm unless a key says otherwise. The camera
    frame is OpenCV's and BOP's (x right, y down, z forward); the world frame has the floor at
    z = 0, z up. A NotRequired key is there only when the recipe or the call asks for it.
    """

    scene_id: int
    """BOP's scene id: the scene's index in the run (SPLIT/SCENEID/)."""
    im_id: int
    """BOP's image id: the view's index in the sweep (IMID in the file names)."""
    sensor: NotRequired[str]
    """A rig's (`cameras:`) sensor name, as its folders are named (rgb_NAME/, depth_NAME/, ...)."""
    width: int
    """W, pixels."""
    height: int
    """H, pixels."""
    K: NDArray[np.float64]
    """(3, 3) The camera matrix, pixels (scene_camera.json cam_K)."""
    cam_from_world: NDArray[np.float64]
    """(4, 4) World to camera frame, mm: the inverse of the camera's pose (cam_R_w2c, cam_t_w2c).
    An instance's world pose is inverse(cam_from_world) @ cam_from_model[i]."""
    depth_scale: float
    """A depth PNG's value x depth_scale = mm (scene_camera.json; encode_depth's argument)."""
    split: NotRequired[str]
    """'train' or 'test', as splits/ lists the image; only when the recipe skips no views
    (sweep.min_visible_pixels 0), since otherwise the split is known only once a scene's views
    are written."""
    obj_id: NDArray[np.int32]
    """(N,) BOP's obj_id per instance (scene_gt.json; Run.objects names them)."""
    cam_from_model: NDArray[np.float64]
    """(N, 4, 4) Each instance's exact pose, model to camera frame, mm (scene_gt.json cam_R_m2c,
    cam_t_m2c)."""
    bbox_obj: NDArray[np.int32]
    """(N, 4) x, y, width, height of the full silhouette, pixels; it may reach outside the image
    (scene_gt_info.json; [-1, -1, -1, -1] for an instance with no visible pixel)."""
    bbox_visib: NDArray[np.int32]
    """(N, 4) x, y, width, height of the visible pixels (scene_gt_info.json)."""
    px_count_all: NDArray[np.int32]
    """(N,) Pixels of the full silhouette, its parts outside the image included
    (scene_gt_info.json)."""
    px_count_valid: NDArray[np.int32]
    """(N,) Pixels of the full silhouette with a value in the depth image (scene_gt_info.json)."""
    px_count_visib: NDArray[np.int32]
    """(N,) Visible pixels, by output.visibility (scene_gt_info.json)."""
    visib_fract: NDArray[np.float64]
    """(N,) px_count_visib / px_count_all (0 when px_count_all is 0)."""
    mask: NotRequired[NDArray[np.bool_]]
    """(N, H, W) Each instance's full silhouette, also where others hide it (mask/); left out
    with masks=False."""
    mask_visib: NotRequired[NDArray[np.bool_]]
    """(N, H, W) Its visible part, by output.visibility (mask_visib/); left out with
    masks=False."""
    graspnet: NotRequired[NDArray[np.float32]]
    """(M, 17) The frame's parallel-jaw grasps in graspnetAPI's GraspGroup layout, camera frame,
    metres (graspnet/SCENEID/IMID.npy; docs/formats.md, "Grasp labels"). With `grasps:` and its
    graspnet format (the default), for the first sensor only."""
    graspnet_labels: NotRequired[NDArray[np.float32]]
    """(M, 6) Per graspnet row: instance index, obj_id, approach blocked, first and second contact
    seen, the grasp's index in its object's ACRONYM file (graspnet/SCENEID/IMID_labels.npy)."""
    suctionnet: NotRequired[NDArray[np.float32]]
    """(S, 8) The frame's suction grasps in SuctionNet's SuctionGroup layout: score, direction,
    point (m), obj_id; camera frame (suctionnet/SCENEID/IMID.npy). With a cup
    (grasps.suction) and the suctionnet format, for the first sensor only."""
    suctionnet_labels: NotRequired[NDArray[np.float32]]
    """(S, 6) Per suctionnet row: instance index, obj_id, approach blocked, point seen, seal score,
    wrench score (suctionnet/SCENEID/IMID_labels.npy)."""
    rgb: NotRequired[NDArray[np.uint8]]
    """(H, W, 3) The colour image, R, G, B (rgb/); a grey camera has gray instead."""
    gray: NotRequired[NDArray[np.uint8] | NDArray[np.uint16]]
    """(H, W) A grey camera's image as gray/ holds it: uint8 for camera.image gray, uint16 for
    gray16."""
    depth: NDArray[np.float32]
    """(H, W) Depth, mm: the camera-frame z of the first surface, 0 where there is none; what the
    depth sensor returns, with its noise and holes (depth/)."""
    depth_gt: NotRequired[NDArray[np.float32]]
    """(H, W) The exact depth, mm, with a depth model other than ideal (depth_gt/). Every label
    comes from it."""
    instance: NDArray[np.uint16]
    """(H, W) The visible instance at each pixel, its index + 1 (0: none)."""
    ir: NotRequired[NDArray[np.uint8]]
    """(H, W) An active_stereo camera's left IR image, the one its matcher read (written to ir/
    with output.infrared)."""
    normals: NotRequired[NDArray[np.float32]]
    """(H, W, 3) Unit surface normals, camera frame, 0 where nothing is hit (render.normals)."""
    radiance: NotRequired[NDArray[np.float32]]
    """(H, W, 3) render.hdr (rgb_hdr/): in pbr mode the linear radiance, W/(m^2 sr), before
    exposure; in fast mode the colour before rounding."""
    denoiser_radiance: NotRequired[NDArray[np.float32]]
    """(H, W, 3) Recipe.prepare(denoiser_inputs=True), pbr mode: the linear radiance before
    denoising (the denoiser's input; training one: tools/denoiser/)."""
    denoiser_albedo: NotRequired[NDArray[np.float32]]
    """(H, W, 3) with denoiser_inputs: the first surface's albedo, mean over the pixel's paths."""
    denoiser_normal: NotRequired[NDArray[np.float32]]
    """(H, W, 3) with denoiser_inputs: the first surface's shading normal, world frame, mean over
    the pixel's paths."""
    denoiser_variance: NotRequired[NDArray[np.float32]]
    """(H, W) with denoiser_inputs: the variance of the pixel's mean luminance."""
    samples: NotRequired[NDArray[np.int32]]
    """(H, W) pbr mode: the paths each pixel's colour averages (render.samples, fewer where
    adaptive sampling stopped early, render.noise_threshold). Not written to the dataset."""
    randomization: NotRequired[str]
    """The frame's draws as a JSON object (scene_randomization.json); only when the recipe
    randomises something."""
    sensors: NotRequired[list[Frame]]
    """A rig of several cameras: every sensor's frame, in `cameras:` order; the top level is a
    copy of the first, without this key."""
    kept: NotRequired[bool]
    """Run.frame() only: whether the writer keeps the view (sweep.min_visible_pixels)."""

# An object of the run: BOP obj_id i + 1 for entry i of Run.objects.
RunObject = TypedDict("RunObject", {"obj_id": int, "name": str, "class": str, "class_id": int})

class Texture(TypedDict):
    type: str  # noise, brushed, turned, checker, concrete, wood, rust, scratches, image
    scale: float  # mm
    amount: float
    roughness: float
    bump: float
    color: list[float]  # linear RGB
    seed: int
    file: str  # image
    projection: str  # image: auto, triplanar or uv

class Material(TypedDict):
    """A pbr material as the renderer shades it before any randomisation (Run.look)."""

    base_color: list[float]  # linear RGB (a base_from_part one already the instance's)
    metallic: float
    roughness: float
    specular: float
    anisotropic: float
    clearcoat: float
    clearcoat_roughness: float
    distribution: str  # ggx or multiscatter_ggx
    multiscatter: bool
    tangent: str  # radial or x
    base_from_part: bool
    textured: bool
    texture: Texture | None

FixtureMaterial = Material

class InstanceMaterial(Material):
    name: str  # the instance's (scene_gt_world.json's)

class Look(TypedDict):
    """A scene's look in the pbr mode (Run.look). Lights and the environment are dicts of their
    recipe keys (lengths in mm, angles in radians, a rect's sides size_x and size_y, type)."""

    instances: list[InstanceMaterial]  # in scene_gt_world.json's order
    floor: Material | None
    floor_half_size: float  # mm
    fixtures: list[Material]
    lights: list[dict[str, Any]]
    environment: dict[str, Any]

class Fixture(TypedDict):
    name: str
    vertices: NDArray[np.float32]  # N x 3, mm, world frame
    normals: NDArray[np.float32]  # N x 3, or 0 x 3 without normals
    triangles: NDArray[np.uint32]  # M x 3
    material: FixtureMaterial

class WriteSummary(TypedDict):
    """What Recipe.write() and Run.write() wrote (as `cadsynth generate` reports it)."""

    frames: int
    resumed: int
    skipped_empty: int
    skipped_sparse: int
    scenes: int
    objects: int
    instances: int
    seconds: float

class Recipe:
    @staticmethod
    def load(path: _StrPath) -> Recipe: ...
    @staticmethod
    def from_yaml(text: str, name: str = "<string>", base_dir: _StrPath = ".") -> Recipe: ...
    @staticmethod
    def from_dict(recipe: dict[str, Any], base_dir: _StrPath = ".") -> Recipe: ...
    @staticmethod
    def default() -> Recipe: ...
    def reseeded(self, stream: int) -> Recipe: ...
    @property
    def path(self) -> pathlib.Path | None: ...
    @property
    def stream(self) -> int: ...
    @property
    def scenes(self) -> list[str]: ...
    @property
    def views(self) -> int: ...
    def prepare(
        self,
        cache: _Cache = True,
        threads: int = 0,
        verbose: bool = False,
        denoiser_inputs: bool = False,
    ) -> Run: ...
    def write(
        self,
        output: _StrPath,
        overwrite: bool = False,
        shard: _Shard | None = None,
        cache: _Cache = True,
        threads: int = 0,
    ) -> WriteSummary: ...

class FrameIterator:
    def __iter__(self) -> FrameIterator: ...
    def __next__(self) -> Frame: ...
    def __len__(self) -> int: ...
    def close(self) -> None: ...

class Run:
    @property
    def scenes(self) -> int: ...
    @property
    def views(self) -> int: ...
    @property
    def units(self) -> int: ...
    @property
    def objects(self) -> list[RunObject]: ...
    @property
    def sensors(self) -> list[str]: ...
    def fixtures(self, scene: int) -> list[Fixture]: ...
    def look(self, scene: int) -> Look: ...
    def frames(
        self, shard: _Shard | None = None, masks: bool = True, skip: bool = True, threads: int = 0
    ) -> FrameIterator: ...
    def frame(self, unit: int, masks: bool = True) -> Frame: ...
    def write(
        self,
        output: _StrPath,
        overwrite: bool = False,
        shard: _Shard | None = None,
        threads: int = 0,
    ) -> WriteSummary: ...

def encode_png(image: NDArray[np.uint8] | NDArray[np.uint16]) -> bytes: ...
def encode_depth(depth_mm: ArrayLike, depth_scale: float = 1.0) -> NDArray[np.uint16]: ...
def read_image(path: _StrPath) -> NDArray[np.uint8] | NDArray[np.uint16]: ...
def decode_image(data: bytes) -> NDArray[np.uint8] | NDArray[np.uint16]: ...
def evaluate(
    dataset: _StrPath, results: _StrPath, sensor: str = ""
) -> tuple[str, dict[str, Any]]: ...
def default_cache() -> pathlib.Path | None: ...
