# SPDX-License-Identifier: GPL-3.0-or-later
# Type stubs of the texfab package: the extension's entries (_texfab.pyi) and the break jobs.
from typing import Iterator, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._texfab import *  # noqa: F401,F403
from ._texfab import (BrokenModel, Backend, CacheDir, ImageLike, Mesh, PathLike, Progress, SolidMethod,
                      Wrap, __version__)

def fracture(mesh: Union[Mesh, PathLike], *, pieces: int = 10,
             impact: Optional[tuple[float, float, float]] = None, roughness: float = 0.0,
             min_volume: float = 0.0, exemplar: Optional[ImageLike] = None,
             interior: Optional[ImageLike] = None, mode: Literal["solid", "surface"] = "solid",
             texture_scale: float = 0.0, resolution: Union[int, tuple[int, int]] = 2048,
             interior_resolution: Union[int, tuple[int, int]] = 0, gutter: int = 4, seed: int = 1,
             wrap: Wrap = "auto", solid_method: SolidMethod = "lazy", tile_size: int = 32,
             contrast_gain: float = 2.0, refine: int = 0, threads: int = 0,
             backend: Backend = "cpu", cache_dir: CacheDir = None,
             progress: Optional[Progress] = None) -> BrokenModel: ...

def cut(mesh: Union[Mesh, PathLike], planes: Sequence[tuple[Sequence[float], Sequence[float]]], *,
        exemplar: Optional[ImageLike] = None, interior: Optional[ImageLike] = None,
        mode: Literal["solid", "surface"] = "solid", texture_scale: float = 0.0,
        resolution: Union[int, tuple[int, int]] = 2048, interior_resolution: Union[int, tuple[int, int]] = 0,
        gutter: int = 4, seed: int = 1, wrap: Wrap = "auto", solid_method: SolidMethod = "lazy",
        tile_size: int = 32, contrast_gain: float = 2.0, refine: int = 0, threads: int = 0,
        backend: Backend = "cpu", cache_dir: CacheDir = None, progress: Optional[Progress] = None) -> BrokenModel:
    """planes: (point, normal) pairs in model units; the texture options as fracture()'s."""


def slice_layers(mesh: Union[Mesh, PathLike], *, batch: int = 16,
                 **options) -> Iterator[tuple[int, npt.NDArray[np.uint8]]]:
    """The print's layers in order, (index, uint8 material indices (H, W), or RGBA (H, W, 4) with
    dither="none" or format="voxelprint"); options as slice()'s but output, layers and force."""
