# SPDX-License-Identifier: GPL-3.0-or-later
# Type stubs of the extension texfab._texfab (re-exported by texfab; fracture and cut: __init__.pyi).
# Arrays: images are float32 (H, W, C), top row first, values as the files store them normalized
# (0..1 for 8/16-bit images; base colours sRGB-encoded); meshes are float32 (N, 3) positions and
# uint32 (M, 3) triangles, counter-clockwise seen from outside.
# Every long function releases the GIL, takes `threads` (0 = all cores), `backend` ("cpu",
# "vulkan", "auto"), `cache_dir` (exemplar analyses: None = $TEXFAB_CACHE_DIR or ~/.cache/texfab,
# as the command line; False = no cache) and `progress`, and raises texfab.Error with the command
# line's message on bad input, texfab.Cancelled when `progress` asked to stop.
import os
from typing import Callable, Iterator, Literal, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike[str]]
# An image: a file, or an array (H, W) or (H, W, C): uint8 (0..255), uint16 (0..65535) or float (as is).
ImageLike = Union[PathLike, npt.ArrayLike]
# (stage, fraction done in [0, 1]) -> False (or raising) cancels; None or True goes on. Called from
# texfab's worker threads with the GIL held: when a stage (or a step inside one) begins (0), as it
# advances (at most every 0.1 s) and when it ends (1).
Progress = Callable[[str, float], Optional[bool]]
Backend = Literal["cpu", "vulkan", "auto"]
Wrap = Literal["auto", "tile", "clamp"]
SolidMethod = Literal["lazy", "tiles"]
Up = Literal["x", "-x", "y", "-y", "z", "-z"]
CacheDir = Union[None, Literal[False], PathLike]

__version__: str

class Error(Exception): ...
class Cancelled(Error): ...

def read_image(path: PathLike) -> npt.NDArray[np.float32]: ...
def write_image(image: ImageLike, path: PathLike, *, bits: Literal[8, 16, 32] = 8) -> None:
    """Writes as texfab does (8-bit: round(255 v), clamped)."""

class Material:
    name: str
    base_color_factor: npt.NDArray[np.float32]        # (4,) linear RGBA
    metallic_factor: float
    roughness_factor: float
    base_color: Optional[npt.NDArray[np.float32]]      # (H, W, C) sRGB-encoded
    normal: Optional[npt.NDArray[np.float32]]          # tangent space, +Y up (OpenGL)
    metallic_roughness: Optional[npt.NDArray[np.float32]]  # G roughness, B metallic

class Mesh:
    def __init__(self, vertices: npt.ArrayLike, triangles: npt.ArrayLike,
                 uvs: Optional[npt.ArrayLike] = None) -> None: ...
    vertices: npt.NDArray[np.float32]                  # (N, 3)
    triangles: npt.NDArray[np.uint32]                  # (M, 3)
    uvs: Optional[npt.NDArray[np.float32]]             # (M, 3, 2) per corner, v up (OpenGL, Blender)
    face_materials: npt.NDArray[np.uint32]             # (M,) index into materials
    face_tags: npt.NDArray[np.uint32]                  # (M,) 1 = a cut (interior) face
    materials: list[Material]
    def save(self, path: PathLike, *, up: Up = "y", draco: bool = False, embed: bool = False,
             texture_format: Literal["keep", "png", "jpeg", "webp"] = "keep") -> None:
        """Writes .glb .gltf .obj .ply .off .stl .3mf as the command line does; `up`: the model's
        up axis (3MF builds along +z; the command line's auto is z for STL models, else y)."""

def load_mesh(path: PathLike) -> Mesh: ...

class SynthesisResult:
    image: npt.NDArray[np.float32]                     # (H, W, C) the exemplar through coords
    coords: npt.NDArray[np.int32]                      # (H, W, 2) exemplar pixel (x, y) per texel
    maps: dict[str, npt.NDArray[np.float32]]           # companion maps through the same coords
    wrap: str

def synthesize(exemplar: ImageLike, size: tuple[int, int] = (512, 512), *,
               window: Optional[tuple[int, int, int, int]] = None, seed: int = 1,
               jitter: Optional[Sequence[float]] = None, passes: int = 2, interleave: int = 2,
               k: int = 2, feature_weight: float = ..., tileable: bool = False, wrap: Wrap = "auto",
               maps: Optional[Mapping[str, ImageLike]] = None, threads: int = 0,
               backend: Backend = "cpu", cache_dir: CacheDir = None,
               progress: Optional[Progress] = None) -> SynthesisResult: ...

def synthesize_graph(graph: PathLike, size: tuple[int, int] = (512, 512), *,
                     window: Optional[tuple[int, int, int, int]] = None, zoom: float = 1.0, seed: int = 1,
                     jitter: Optional[Sequence[float]] = None, passes: int = 2, interleave: int = 2,
                     tileable: bool = False, threads: int = 0, cache_dir: CacheDir = None,
                     progress: Optional[Progress] = None) -> SynthesisResult:
    """Multiscale synthesis from an exemplar graph file (docs/exemplar-graphs.md) at `zoom` (a
    power of two: output texels are 1/zoom of a root pixel); equal to `texfab synth --graph`.
    `maps` holds the companion maps the graph's exemplars give ("normal", "roughness", "height").
    `tileable`: the output wraps at its size."""

def solid(exemplar: ImageLike, *, points: Optional[npt.ArrayLike] = None,
          box: Optional[tuple[int, int, int, int, int, int]] = None,
          plane: Optional[tuple[Sequence[float], Sequence[float], Sequence[float]]] = None,
          size: Optional[tuple[int, int]] = None, voxel_size: float = 1.0, seed: int = 1, method: SolidMethod = "lazy",
          tile_size: int = 32, contrast_gain: float = 2.0, refine: int = 0, wrap: Wrap = "auto",
          threads: int = 0, backend: Backend = "cpu", cache_dir: CacheDir = None,
          progress: Optional[Progress] = None) -> npt.NDArray[np.float32]:
    """Colours of the solid texture: at `points` (N, 3) (output units; a voxel is `voxel_size`
    wide) -> (N, C); of every voxel of `box` (x, y, z, nx, ny, nz) -> (nz, ny, nx, C); on `plane`
    (origin, u, v) with `size` (W, H) -> (H, W, C), pixel (i, j) at origin + (i + .5) u + (j + .5) v."""

class TextureResult:
    mesh: Mesh                                         # the input with atlas UVs and one material
    base_color: npt.NDArray[np.float32]
    normal: Optional[npt.NDArray[np.float32]]
    metallic_roughness: Optional[npt.NDArray[np.float32]]
    height: Optional[npt.NDArray[np.float32]]
    texture_scale: float                               # exemplar pixels per model unit used
    charts: int
    repairs: list[str]                                 # what made the input a surface to texture
    warnings: list[str]
    def save(self, path: PathLike, *, up: Up = "y", draco: bool = False, embed: bool = False,
             texture_format: str = "keep") -> None: ...   # as Mesh.save

def texture_mesh(mesh: Union[Mesh, PathLike], exemplar: Optional[ImageLike] = None, *,
                 mode: Literal["surface", "solid"] = "surface",
                 resolution: Union[int, tuple[int, int]] = 2048, gutter: int = 4,
                 texture_scale: float = 0.0, feature_size: float = 0.0, seed: int = 1,
                 direction: tuple[float, float, float] = ..., field: Literal["direction", "curvature"] = "direction",
                 maps: Optional[Mapping[str, ImageLike]] = None, graph: Optional[PathLike] = None,
                 wrap: Wrap = "auto", solid_method: SolidMethod = "lazy", tile_size: int = 32,
                 contrast_gain: float = 2.0, refine: int = 0, threads: int = 0,
                 backend: Backend = "cpu", cache_dir: CacheDir = None,
                 progress: Optional[Progress] = None) -> TextureResult:
    """`graph`: an exemplar graph file instead of `exemplar` (`texfab texture --graph`), surface
    mode, with the companion maps its exemplars give."""

class Piece:
    name: str
    mesh: Mesh                                         # model frame; materials outer..., interior...
    centroid: npt.NDArray[np.float64]                  # (3,)
    volume: float
    cut_area: float

class BrokenModel:
    pieces: list[Piece]
    model_volume: float
    interior_scale: float
    notes: list[str]
    repairs: list[str]
    def save(self, path: PathLike, *, explode: float = 0.0, up: Up = "y", draco: bool = False,
             embed: bool = False, texture_format: str = "keep") -> None: ...  # .glb/.gltf, a node per piece

def _break_model(mesh: Union[Mesh, PathLike], planes: Optional[list] = None, **options) -> BrokenModel: ...

def slice(mesh: Union[Mesh, PathLike], output: PathLike, *, exemplar: Optional[ImageLike] = None,
          mode: Literal["solid", "surface"] = "solid", up: Up = "y", height_mm: float = 50.0, unit_mm: float = 0.0,
          dpi: tuple[float, float] = (600.0, 300.0), layer_mm: float = 0.027, shell_mm: float = 1.0,
          layers: Optional[tuple[int, int]] = None, dither: Literal["blue-noise", "floyd-steinberg", "none"] = "blue-noise",
          format: Literal["png", "voxelprint"] = "png", core: str = "white",
          materials: Optional[PathLike] = None, icc_profile: Optional[PathLike] = None,
          texture_scale: float = 0.0, feature_size: float = 0.0,
          seed: int = 1, wrap: Wrap = "auto", solid_method: SolidMethod = "lazy", tile_size: int = 32,
          contrast_gain: float = 2.0, refine: int = 0, resolution: int = 2048, force: bool = False,
          threads: int = 0, backend: Backend = "cpu", cache_dir: CacheDir = None,
          progress: Optional[Progress] = None) -> dict:
    """Writes the folder `texfab slice` writes (slice_NNNNN.png and slices.json); returns the manifest.
    `layers`: (A, B), layers A..B-1 only, byte for byte as in a full run. `icc_profile`: the printer's
    ICC output profile; mixes aim at the colours it says the printer reproduces."""

def _print_grid(mesh: Union[Mesh, PathLike], *, up: Up = "y", height_mm: float = 50.0, unit_mm: float = 0.0,
                dpi: tuple[float, float] = (600.0, 300.0), layer_mm: float = 0.027) -> dict: ...
