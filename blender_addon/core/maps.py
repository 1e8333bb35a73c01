"""The core's output maps as the add-on meets them (no bpy): their kinds (:func:`map_kinds`, the one place the add-on
learns them), UDIM tile sets stacked into one texture and split again (:func:`stack_tiles`, :func:`split_tiles`),
and the textures a material plan writes (:class:`Textures`, written by the core's own writer).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import spectral_skin

# The token that stands for a UDIM tile number in a file name (the core's src/maps/udim.rs: UDIM_TOKEN).
UDIM_TOKEN = "<UDIM>"

# The Principled input each of the plan's values sets (core/material_plan.py MaterialPlan), by the plan's field: the
# inputs a texture can feed and the animation keys per frame.
PLAN_INPUTS = {"base_color": "Base Color", "radius": "Subsurface Radius", "specular_ior_level": "Specular IOR Level",
               "coat_weight": "Coat Weight", "coat_roughness": "Coat Roughness"}
@dataclass(frozen=True)
class MapKind:
    """One of the core's output maps: its name (the ``maps()`` output's key and its file's name), channels, unit and
    the Principled input it feeds; and what the add-on makes of it: the plan's field of that input, whether its
    texture holds a colour."""

    name: str
    channels: tuple[str, ...]
    unit: str
    principled_input: str
    # The colour space to load its texture in: None for the run's working space (a colour), else data (Non-Color).
    color_space: str | None

    @property
    def field(self) -> str:
        """The plan's field (a MaterialPlan attribute) this map's texture stands in for."""
        return next(field for field, name in PLAN_INPUTS.items() if name == self.principled_input)

    @property
    def colour(self) -> bool:
        """Whether the texels are a colour (linear RGB in the working space), not data."""
        return self.color_space is None

    @property
    def scalar(self) -> bool:
        """Whether the map holds one value per texel (the surface's maps), not an RGB triple."""
        return len(self.channels) == 1


@functools.cache
def map_kinds() -> tuple[MapKind, ...]:
    """The core's map kinds (``spectral_skin.map_kinds()``, from src/maps/kinds.rs), in its order (albedo, radius,
    then the surface's single-channel maps): the one place the add-on takes them from."""
    return tuple(MapKind(name=k["name"], channels=tuple(k["channels"]), unit=k["unit"],
                         principled_input=k["principled_input"], color_space=k["color_space"])
                 for k in spectral_skin.map_kinds())


def map_kind(name: str) -> MapKind:
    """The map kind of that name."""
    return next(kind for kind in map_kinds() if kind.name == name)


def stack_tiles(parts: Sequence[tuple[int, Any]], what: str) -> tuple[Any, tuple[tuple[int, int], ...]]:
    """A UDIM tile set's images ``(tile, array of (rows, W, ...))``, in stacking order, stacked top to bottom into one
    C-contiguous image, as the core computes and writes a tile set (``tiles=`` of ``maps().write``, ``write_maps``,
    ``AlbedoMapFit.write``), and each tile's ``(tile, rows)``. ValueError naming ``what`` and each tile's width when
    the widths differ (one texture has one width)."""
    import numpy as np

    arrays = [(tile, np.asarray(image)) for tile, image in parts]
    widths = {tile: int(a.shape[1]) for tile, a in arrays}
    if len(set(widths.values())) != 1:
        raise ValueError(f"{what}: the tiles are computed as one texture, so they must be all of one width; found "
                         + ", ".join(f"{tile}: {width}" for tile, width in widths.items()))
    stacked = np.ascontiguousarray(np.concatenate([a for _, a in arrays], axis=0))
    return stacked, tuple((tile, int(a.shape[0])) for tile, a in arrays)


def split_tiles(stacked: Any, tiles: Sequence[tuple[int, int]]) -> Iterator[tuple[int, Any]]:
    """The tiles of an image stacked by :func:`stack_tiles`: ``(tile, its rows)`` in stacking order."""
    first = 0
    for tile, rows in tiles:
        yield tile, stacked[first:first + rows]
        first += rows


@dataclass(frozen=True, eq=False)
class Textures(Mapping[str, Any]):
    """The textures a material plan writes: {map name: the core's read-only float32 texels, (H, W, 3) or (H, W),
    row 0 at the top}, in the core's map order, read as a mapping; the folder and file prefix they go to, and a
    tile set's (tile, rows) stacked top to bottom. ``source``: the core's ``Maps`` result when the textures are
    every map it holds (it then writes itself); None when the plan keeps only some of them or takes one from
    another computation."""

    images: Mapping[str, Any]
    folder: str = ""
    prefix: str = ""
    tiles: tuple[tuple[int, int], ...] = ()
    source: Any = None

    def __getitem__(self, kind: str) -> Any:
        return self.images[kind]

    def __iter__(self) -> Iterator[str]:
        return iter(self.images)

    def __len__(self) -> int:
        return len(self.images)

    def write(self) -> dict[str, str]:
        """Write the textures with the core's writer (half-float EXRs, compression chosen per file, staged as
        temporary files and renamed into place together; an earlier file of this prefix, and tiles, that is not
        written again is removed): ``<folder>/<prefix>_albedo.exr`` etc., ``<prefix>_albedo.<UDIM>.exr`` for a tile
        set. The core's ``Maps.write`` when they are its result's maps; else ``spectral_skin.write_maps``, which
        reads the core's read-only arrays in place. Returns {map name: the path the core wrote} (empty without
        textures: nothing is written). Raises spectral_skin.SpectralSkinIOError naming a file that cannot be
        written; the final paths are then untouched."""
        if not self.images:
            return {}
        tiles = list(self.tiles) or None
        if self.source is not None:
            written = self.source.write(self.folder, self.prefix, tiles=tiles)
        else:
            written = spectral_skin.write_maps(dict(self.images), self.folder, self.prefix, tiles=tiles)
        return {kind: str(path) for kind, path in written.items()}


NO_TEXTURES = Textures(images={})
