#!/usr/bin/env python3
"""Generated tables of the docs, from the core's own data and stamped with the model's version
(scripts/lib/doc_stamp.py): README.md's list of the texture map files (block ``map files``, from
``spectral_skin.map_kinds()``) and its table of the presets (block ``skin types``, from ``presets()`` and
``evaluate``), and docs/blender-targets.md's table of Blender versions (block ``blender targets``, from
``spectral_skin.blender_targets()``, i.e. ``VERSION_TABLE`` in src/fit/blender_target.rs) and the presets' inputs on
each target (block ``presets on targets``, from ``evaluate``).

    .venv/bin/python scripts/reports/doc_tables.py
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "lib"))

import spectral_skin  # noqa: E402
from doc_stamp import command, paragraph, write_blocks  # noqa: E402
from doc_stamp import markdown_table as table  # noqa: E402

README = ROOT / "README.md"
TARGETS_DOC = ROOT / "docs" / "blender-targets.md"
# How the add-on names a texture file: this prefix and the map kind's file (blender_addon/core/maps.py).
ADDON_PREFIX = "<blend>_<material>_"
# Words for the names blender_targets() gives a random walk's model (a new name shows as it is).
ALPHA_WORDS = {"wrenninge_fit": "Wrenninge fit", "van_de_hulst": "Van de Hulst"}
RADIUS_WORDS = {
    "four_pi_mean_free_path": "Radius = 4π ℓ",
    "mean_free_path": "Radius = ℓ",
    "skin_dipole": "Radius = ℓ / √(3(1 − α′))",
}
ENGINE_WORDS = {"cycles": "Cycles", "eevee": "EEVEE"}
RANDOM_WALK = "RANDOM_WALK"


def map_files_table() -> str:
    """One row per kind of texture map: the file the add-on writes, the Principled input it feeds, its channels,
    unit and colour space, and the output that computes it."""
    rows = [
        [
            f"`{ADDON_PREFIX}{kind['file']}`",
            kind["principled_input"],
            ", ".join(kind["channels"]),
            kind["unit"] or "–",
            kind["color_space"] or "the scene's working space",
            f"`{kind['output']}`",
        ]
        for kind in spectral_skin.map_kinds()
    ]
    header = ["file", "Principled BSDF input", "channels", "unit", "colour space", "computed by output"]
    return table(header, rows)


def _walk_model(model: dict[str, Any]) -> str:
    """A method's model in words: 'Wrenninge fit, Radius = 4π ℓ'."""
    if model.get("kind") != "random_walk":
        return str(model.get("kind", "?"))
    alpha, radius = model["alpha"], model["radius"]
    return f"{ALPHA_WORDS.get(alpha, alpha)}, {RADIUS_WORDS.get(radius, radius)}"


def _methods(version: dict[str, Any]) -> str:
    """The methods a version offers, by Blender enum id in menu order; one not validated by renders is marked."""
    return ", ".join(f"`{m['blender_id']}`" + ("" if m["tested"] else " (untested)") for m in version["methods"])


def _random_walk(version: dict[str, Any]) -> str:
    models = [_walk_model(m["model"]) for m in version["methods"] if m["blender_id"] == RANDOM_WALK]
    return models[0] if models else "–"


def _as_earlier(cells: list[str], earlier: list[tuple[str, list[str]]], column: int) -> str:
    """``cells[column]``, or 'as 4.2' when the first earlier row with the same value is 4.2's."""
    same = [name for name, row in earlier if row[column] == cells[column]]
    return f"as {same[0]}" if same else cells[column]


def targets_table() -> str:
    """One row per entry of the core's version table: EEVEE's engine id, the methods offered, what ``RANDOM_WALK``
    does, and whether renders validated Cycles and EEVEE in exactly that version."""
    earlier: list[tuple[str, list[str]]] = []
    rows = []
    targets = spectral_skin.blender_targets()
    for version in targets["versions"]:
        cells = [_methods(version), _random_walk(version)]
        shown = [_as_earlier(cells, earlier, column) for column in range(len(cells))]
        earlier.append((version["version"], cells))
        tested = " / ".join("yes" if version[key] else "no" for key in ("tested", "eevee_tested"))
        rows.append([version["version"], f"`{version['engine_ids']['eevee']}`", *shown, tested])
    header = [
        "row",
        "EEVEE engine id",
        "methods offered (Blender enum id)",
        "`RANDOM_WALK` model",
        "tested: Cycles / EEVEE",
    ]
    return table(header, rows) + "\n\n" + _targets_summary(targets)


def _targets_summary(targets: dict[str, Any]) -> str:
    """The sentence under the table: Cycles' engine id, the supported range and the default target."""
    cycles = sorted({version["engine_ids"]["cycles"] for version in targets["versions"]})
    default = targets["default"]
    tested = "tested" if default["tested"] else "untested"
    text = (
        f"Cycles' engine id is {' or '.join(f'`{c}`' for c in cycles)} in every version. Supported: Blender "
        f"{targets['oldest_supported']} and newer (older versions are refused with a message naming the range); "
        f"the default target is the current release, Blender {default['blender']} with "
        f"{ENGINE_WORDS.get(default['engine'], default['engine'])} ({tested})."
    )
    return paragraph(text)


def _srgb_hex(linear: Sequence[float]) -> str:
    """The sRGB code of a linear Rec.709 colour (IEC 61966-2-1's transfer function, 8 bits)."""

    def encode(v: float) -> int:
        v = min(max(v, 0.0), 1.0)
        e = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
        return round(255 * e)

    return "`#" + "".join(f"{encode(v):02x}" for v in linear) + "`"


def _triple(values: Sequence[float], digits: int) -> str:
    return ", ".join(f"{v:.{digits}f}" for v in values)


def _albedo(name: str, **options: Any) -> list[float]:
    return list(spectral_skin.evaluate(preset=name, outputs=["albedo"], **options)["diffuse_reflectance_rgb"])


def skin_types_table() -> str:
    """README's presets: the four knobs and the colour of the default (exact) model and of the paper's diffusion."""
    rows = [
        [
            f"`{name}`",
            f"{p['melanin']:g}",
            f"{p['melanin_blend']:g}",
            f"{p['hemoglobin']:g}",
            f"{p['oiliness']:g}",
            _srgb_hex(_albedo(name)),
            _srgb_hex(_albedo(name, transport="diffusion")),
        ]
        for name, p in spectral_skin.presets().items()
    ]
    header = ["preset", "C_m", "β_m", "C_h", "oil", "sRGB (default, exact)", "sRGB (the paper's diffusion)"]
    return table(header, rows)


def _method(name: str, method: str, **target: Any) -> dict[str, Any]:
    ev = spectral_skin.evaluate(preset=name, outputs=["albedo", "radius"], **target)
    return dict(ev["methods"][method])


def presets_on_targets_table() -> str:
    """Each preset's Principled inputs (default transport and accuracy) on the current release's targets and on
    Blender 5.0's Random Walk."""
    rows = []
    for name in spectral_skin.presets():
        burley = _method(name, "burley")
        walk = _method(name, "random_walk")
        walk_50 = _method(name, "random_walk", blender="5.0")
        eevee = _method(name, "burley", engine="eevee")
        rows.append([
            f"`{name}`",
            _triple(burley["base_color"], 3),
            _triple(burley["subsurface_radius_mm"], 2),
            f"{_triple(walk['base_color'], 3)} / {_triple(walk['subsurface_radius_mm'], 3)}",
            f"{_triple(walk_50['base_color'], 3)} / {_triple(walk_50['subsurface_radius_mm'], 2)}",
            _triple(eevee["subsurface_radius_mm"], 2),
        ])
    header = [
        "preset",
        "albedo = Burley Base Color (linear Rec.709)",
        "Burley radius R, G, B (mm)",
        "Random Walk, 5.2+: Base Color / radius (mm)",
        "Random Walk, 4.2–5.1: Base Color / radius (mm)",
        "EEVEE radius (mm)",
    ]
    return table(header, rows)


def main() -> None:
    cmd = command(__file__)
    write_blocks(README, cmd, {"map files": map_files_table(), "skin types": skin_types_table()})
    write_blocks(TARGETS_DOC, cmd, {"blender targets": targets_table(), "presets on targets": presets_on_targets_table()})
    print(
        f"doc_tables: wrote the map files and skin types blocks of {README.name} and the blender targets and "
        f"presets on targets blocks of {TARGETS_DOC.relative_to(ROOT)} (model {spectral_skin.MODEL_VERSION})"
    )


if __name__ == "__main__":
    main()
