"""Type stubs of the native module (python/src/)."""
import os
from typing import (
    Any,
    Callable,
    Dict,
    List,
    Literal,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
    overload,
)

import numpy as np
import numpy.typing as npt

__version__: str
#: "release" or "debug": how the native module was compiled.
BUILD_PROFILE: str
#: The most frames one GPU submission takes (`Simulator.batch_frames`).
MAX_BATCH: int
#: The smallest and largest size (mm) of a sized primitive ("box:x=10,y=6,z=4").
PRIMITIVE_SIZE_MM: Tuple[float, float]
REGION_NONE: int
REGION_HEMISPHERE: int
REGION_CYLINDER: int

_Path = Union[str, "os.PathLike[str]"]
_Number = Union[float, int, np.floating, np.integer]
#: "rotation=30" | "translation=10" | "s=12", or ("rotation", 30), or {"rotation": 30}
_Place = Union[str, Tuple[str, _Number], Mapping[str, _Number]]
_Image = npt.NDArray[np.uint8]
_Depth = npt.NDArray[np.float32]
Labels = Dict[str, Any]

class Sensor:
    """A GelTip sensor: the finger, its lens and the image they form."""

    def __init__(self, name: Optional[_Path] = None) -> None:
        """A preset name ("paper", "webcam70", "tube13", "tube21"; default "paper") or
        the path of a sensor TOML file, as the CLI's `--sensor`."""
    @staticmethod
    def from_toml(path_or_str: _Path, name: Optional[str] = None) -> Sensor:
        """A sensor from a TOML file (a path) or from TOML text."""
    @staticmethod
    def presets() -> List[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def image_shape(self) -> Tuple[int, int, int]:
        """(height, width, 3)."""
    @property
    def description(self) -> str: ...
    @property
    def config(self) -> Dict[str, Any]:
        """The whole configuration (the TOML file's tables) as a dict."""
    @property
    def calibration(self) -> Optional[Dict[str, Any]]:
        """The report of the calibration that made this sensor (`calibrate`): report.json's
        content (image circle, PSNR and SSIM inside it before and after, every fitted value
        with its standard error, what the frames leave loose). None for any other sensor."""
    @overload
    def project(
        self, points: npt.ArrayLike, *, reasons: Literal[False] = False
    ) -> npt.NDArray[np.float64]:
        """Points (N, 3) (or one point (3,)) in mm -> pixels (N, 2) (or (2,)) float64; NaN
        where a point is not visible."""
    @overload
    def project(
        self, points: npt.ArrayLike, *, reasons: Literal[True]
    ) -> Tuple[npt.NDArray[np.float64], Union[List[Optional[str]], Optional[str]]]:
        """(pixels, [None | why not, ...]), or (pixel, None | why not) for one point; the
        reasons are the CLI's `reason`."""
    def unproject(
        self, pixels: npt.ArrayLike
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.int8]]:
        """Pixels (N, 2) (or one (2,)) -> (points (N, 3) mm, unit normals (N, 3), region (N,)
        int8). Region codes: 0 = none (the pixel sees no part of the finger: NaN point and
        normal), 1 = hemisphere, 2 = cylinder; `geltip.region_names` maps them to strings."""

class Simulator:
    """The renderer of one sensor: GPU context, pipelines and reference frame, made once."""

    def __init__(
        self,
        sensor: Union[Sensor, _Path, None] = None,
        objects: Optional[Sequence[_Path]] = None,
        streams: int = 1,
    ) -> None:
        """`objects`: solids or mesh files to load (meshes are baked) now rather than on
        first use. `streams` (1..=4): renderers on devices of their own that `render_batch`
        shares its submissions between, at the same time (the same frames, faster on a
        software rasteriser, which leaves cores idle within one stream)."""
    @property
    def sensor(self) -> Sensor: ...
    @property
    def host(self) -> str:
        """CPU, adapter and driver the frames are rendered on."""
    @property
    def batch_frames(self) -> int:
        """Frames one GPU submission renders (8 on a software rasteriser, 64 on a GPU by
        default; settable, 1 to MAX_BATCH). The frames are the same whatever it is."""
    @batch_frames.setter
    def batch_frames(self, frames: int) -> None: ...
    def reference(self) -> _Image:
        """The empty finger (H, W, 3) uint8, as `geltip render --reference`."""
    def render(
        self,
        *,
        object: Optional[_Path] = None,
        at: Optional[_Place] = None,
        rotation: Optional[_Number] = None,
        translation: Optional[_Number] = None,
        s: Optional[_Number] = None,
        azimuth: Optional[_Number] = None,
        spin: Optional[_Number] = None,
        tilt: Optional[_Number] = None,
        tilt_towards: Optional[_Number] = None,
        depth: Optional[_Number] = None,
        pose: Union[str, npt.ArrayLike, None] = None,
        approach: Union[str, npt.ArrayLike, None] = None,
    ) -> Tuple[_Image, Labels, _Depth]:
        """One contact -> (image (H, W, 3) uint8, labels, depth map (H, W) float32 mm): the
        bytes `geltip render` writes for the same flags. Place: exactly one of `at`,
        `rotation` (deg about the tip), `translation` (mm below the junction), `s` (mm of
        arc from the tip); or `pose` (16 numbers: a row-major 4x4 matrix, or 7: x y z qw qx
        qy qz) instead of a place and depth, with `approach` (3 numbers, camera frame) the
        direction its depth is measured along (default: the object's +z). `object` is a
        built-in solid, a sized primitive ("box:x=10,y=6,z=4"), a mesh file or a name given
        to `add_mesh`."""
    def render_scene(
        self, contacts: Sequence[Mapping[str, Any]]
    ) -> Tuple[_Image, Labels, _Depth]:
        """Several contacts in one frame (`geltip render --scene`); each dict takes
        `render`'s keyword names. An error names the contact: `contacts[1].depth: ...`."""
    def render_batch(
        self,
        contacts: Sequence[Mapping[str, Any]],
        *,
        depth_maps: bool = True,
        out: Optional[npt.NDArray[np.uint8]] = None,
        depth_out: Optional[npt.NDArray[np.float32]] = None,
    ) -> Tuple[npt.NDArray[np.uint8], List[Labels], Optional[npt.NDArray[np.float32]]]:
        """Many contacts (dicts of `render`'s keyword names), batched on the GPU -> (images
        (N, H, W, 3) uint8, [labels], depth maps (N, H, W) float32 or None with
        depth_maps=False). Every contact is checked before any renders; an error names it
        (`contacts[1].depth: ...`). Frames are written straight into the arrays; pass
        `out`/`depth_out` (C-contiguous, of those shapes) to reuse your own."""
    def render_scenes(
        self,
        scenes: Sequence[Sequence[Mapping[str, Any]]],
        *,
        skip_untouching: bool = False,
        depth_maps: bool = False,
        out: Optional[npt.NDArray[np.uint8]] = None,
        depth_out: Optional[npt.NDArray[np.float32]] = None,
    ) -> Tuple[npt.NDArray[np.uint8], List[Labels], Optional[npt.NDArray[np.float32]]]:
        """Many scenes (lists of contact dicts, as `render_scene` takes), batched on the GPU
        -> (images (N, H, W, 3) uint8, [labels as `render_scene`'s], depth maps or None).
        With `skip_untouching`, a posed object that does not touch the finger is left out of
        its frame (its index listed in the labels' "untouched") instead of raising; a frame
        with none touching is the empty finger. An error names the scene: `scenes[3]: ...`."""
    def add_mesh(
        self, name: str, vertices: npt.ArrayLike, faces: npt.ArrayLike
    ) -> npt.NDArray[np.float64]:
        """Makes the mesh of `vertices` ((N, 3), mm) and `faces` ((M, 3) indices, outward
        counter-clockwise) the object `name` for this Simulator, placed and baked as the
        same vertices in an OBJ file are. Returns the point of the mesh (3,) that became the
        object's origin (its top). `name` may not be a built-in solid's or a primitive's."""

def localise(
    sensor: Sensor,
    reference: _Image,
    image: _Image,
    method: str = "change",
    threshold: Optional[float] = None,
    noise: Optional[float] = None,
    area_mm2: Optional[Tuple[float, float]] = None,
) -> Dict[str, Any]:
    """Finds the contact: {"detected", "pixel", "point", "region", "confidence",
    "regions_found", "note"}, as `geltip localise` prints. method: "change" (real and
    rendered frames), "surface" (rendered frames) or "paper"; threshold: the change method's decision threshold in
    noise spreads (default 20), as `--threshold`; noise: the sensor's noise in 8-bit levels
    (default 1; each pair's own estimate where larger), as `--noise`; area_mm2: (min, max)
    of the contact's area on the finger, change and paper methods, as `--area-mm2`."""

def load_image(path: _Path) -> _Image:
    """Reads an image file (PNG) as (H, W, 3) uint8."""

def save_image(path: _Path, image: _Image) -> None:
    """Writes an (H, W, 3) uint8 array as a PNG file, atomically (a temporary name, then
    renamed), with the encoder `geltip dataset` uses."""

def host_speed() -> Dict[str, float]:
    """How fast the host's cores run now: {"one_core_ms", "all_cores_ms"}, a fixed scalar
    loop's milliseconds on one core and on all cores at once (best of three; some 35 ms).
    Shared machines run faster and slower by phases: time it beside a speed figure."""

def keep_freed_memory() -> bool:
    """Asks the C allocator (glibc) to keep freed memory for reuse: every frame's fresh
    image buffers are then not page-faulted in again (1.0-1.4 ms a 640x480 frame on a 2-core
    VM). Process-wide, so geltip never does it on import. True when it applied."""

def dataset_labels(root: _Path) -> List[Dict[str, Any]]:
    """The label lines of the `geltip dataset` set in `root`, as dicts in file order, by the
    library's reader (only an unfinished last line is left out)."""

def evaluate(
    detector: Union[Callable[[_Image, _Image, Sensor], Optional[Sequence[Dict[str, Any]]]], str],
    *,
    dataset: Optional[_Path] = None,
    suite: Optional[str] = None,
    sensor: Optional[Union[_Path, Sensor]] = None,
    out: Optional[_Path] = None,
    gate_mm: Optional[float] = 3.0,
    name: Optional[str] = None,
    compare: Optional[_Path] = None,
    real: Optional[_Path] = None,
    threshold: Optional[float] = None,
    noise: Optional[float] = None,
    area_mm2: Optional[Tuple[float, float]] = None,
) -> Dict[str, Any]:
    """The native half of `geltip.evaluate`: `detector` answers each frame with a list of
    detections, dicts of "pixel" and/or "point" and "confidence" (or names a built-in
    localiser). Returns {"summary", "tables",
    "per_sample", "files"}."""

def calibrate(
    empty: Union[_Path, Sequence[_Path]],
    sensor: Union[Sensor, _Path, None] = None,
    *,
    contacts: Optional[_Path] = None,
    out: Optional[_Path] = None,
    leds: Optional[int] = None,
    samples: Optional[int] = None,
    starts: Optional[int] = None,
    fit: Optional[str] = None,
    led_kind: Optional[str] = None,
) -> Sensor:
    """A sensor fitted to a real GelTip's own frames, as `geltip calibrate`: `empty` is a
    frame of the empty finger (an image file) or several of the same camera (their spread
    gives the noise); `sensor` the one to start from (default "paper"): its finger, lens
    model and field of view, and every value the frames do not fit. `contacts`: a JSON-lines
    file of frames with known contacts, to fit the imprint. `out`: a directory for
    sensor.toml, report.json and the pictures (real, calibrated, residual, comparison);
    None keeps no file. `leds` (LEDs to fit), `samples` (pixels compared) and `starts`
    (starting rotations of the LEDs): None for the command's defaults; fewer samples and
    starts are faster and rougher. `fit`: what is fitted, as `--fit` (default
    "lens,light,imprint"; add "camera" for the colour matrix and gamma, "geometry" for the
    finger's length, "principal" and "focal" for the lens's principal point and focal length
    fitted to the light where the image circle is a mask); `led_kind`:
    "point" or "gel" (default: the start sensor's). Returns the calibrated Sensor, named "calibrated", whose
    `calibration` is the report. Runs with the GIL released."""
