# SPDX-License-Identifier: GPL-3.0-or-later
"""texfab: textures synthesized from a small exemplar image over meshes, solid textures, models
broken with textured interiors, and coloured slices for full-colour 3D printing.

Every function mirrors an entry of the C++ library and gives the bytes of the matching `texfab`
command. See texfab/_texfab.pyi for the signatures and help(texfab.<name>) for each."""
from ._texfab import (  # noqa: F401
    BrokenModel, Cancelled, Error, Material, Mesh, Piece, SynthesisResult, TextureResult, __version__,
    load_mesh, read_image, slice, solid, synthesize, synthesize_graph, texture_mesh, write_image)
from ._texfab import _break_model, _print_grid

_FRACTURE_ONLY = ("pieces", "impact", "roughness", "min_volume")


def fracture(mesh, **options):
    """Breaks a closed model into Voronoi pieces whose new faces show the material's interior;
    equal to `texfab fracture`. Options: pieces=10, impact=(x, y, z), roughness, min_volume, and
    the textures' (exemplar, interior, mode, texture_scale, resolution, interior_resolution,
    gutter, seed, wrap, solid_method, tile_size, contrast_gain, refine) and threads, backend,
    cache_dir, progress."""
    return _break_model(mesh, None, **options)


def cut(mesh, planes, **options):
    """Cuts a closed model by planes, [(point, normal), ...] in model units; the new faces show
    the material's interior. Equal to `texfab cut`; options as fracture()'s textures."""
    given = [name for name in _FRACTURE_ONLY if name in options]
    if given:
        raise Error(f"cut: {', '.join(given)} apply to fracture() only")
    return _break_model(mesh, list(planes), **options)


def slice_layers(mesh, *, batch=16, **options):
    """Yields the print's layers in order as (layer index, array), `batch` layers sliced at a time
    as `texfab slice` streams them. Indexed layers (the default) are uint8 (H, W) material indices:
    0 empty, i the i-th material (the manifest's "index"); with dither="none" or
    format="voxelprint", uint8 RGBA (H, W, 4). Options as slice()'s, but `output`, `layers` and
    `force`. Each layer is the one a full run writes, byte for byte: any layer range computes alone."""
    import tempfile

    import numpy as np

    for name in ("output", "layers", "force"):
        if name in options:
            raise Error(f"slice_layers: '{name}' is not an option here")
    grid_options = {k: options[k] for k in ("up", "height_mm", "unit_mm", "dpi", "layer_mm") if k in options}
    total = _print_grid(mesh, **grid_options)["layers"]
    with tempfile.TemporaryDirectory(prefix="texfab-layers-") as folder:
        for first in range(0, total, batch):
            manifest = slice(mesh, folder, layers=(first, min(first + batch, total)), force=True, **options)
            materials = manifest["print"]["materials"]
            indexed = manifest["print"]["image"]["pixels"] == "indexed"
            colors = [int(m["color"][1:], 16) for m in materials]
            if indexed and len(set(colors)) != len(colors):
                raise Error("slice_layers: two materials share a colour; read the layer PNGs of slice() instead")
            lookup = dict(zip(colors, (m["index"] for m in materials)))
            for entry in manifest["files"]:
                rgba = np.round(read_image(f"{folder}/{entry['file']}") * 255).astype(np.uint8)
                if not indexed:
                    yield entry["layer"], rgba
                    continue
                rgb = (rgba[..., 0].astype(np.uint32) << 16) | (rgba[..., 1].astype(np.uint32) << 8) | rgba[..., 2]
                index = np.zeros(rgb.shape, np.uint8)
                for color, i in lookup.items():
                    index[(rgb == color) & (rgba[..., 3] > 0)] = i
                yield entry["layer"], index
