"""Headless batch use: apply Spectral Skin to named materials of a .blend and save it, without the UI.

From Python with bpy (``import bpy`` as a module, or Blender's own Python)::

    from blender_addon.batch import apply_to_materials
    from blender_addon.core import SkinSettings
    apply_to_materials("in.blend", ["Skin"], SkinSettings.from_preset("asian"), "out.blend")

or as a script::

    python blender_addon/batch.py in.blend out.blend --material Skin --preset asian [--melanin-map m.exr] [--pack]

Every material's plan is computed (and its maps written) before any material changes; on an error nothing is saved.
The saved .blend refers to the textures by paths relative to itself, or packs them with ``pack=True``.
"""

from __future__ import annotations

import os
import sys
from typing import Any

if __package__ in (None, ""):  # run as a script: import the add-on as the package `blender_addon`
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    __package__ = os.path.basename(os.path.dirname(os.path.abspath(__file__)))  # noqa: A001

import bpy  # noqa: E402

from . import nodes, props, register  # noqa: E402
from .core import PARAMETERS, SkinSettings, make_plan, write_textures  # noqa: E402


def _ensure_registered() -> None:
    if not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply"):
        register()


def apply_to_materials(blend_path: str, material_names: list[str], settings: SkinSettings, out_blend: str,
                       pack: bool = False) -> dict[str, dict[str, Any]]:
    """Open ``blend_path``, apply ``settings`` to each named material, save as ``out_blend``; returns the plans.

    ``settings.output_dir`` (used only with maps) may start with ``//``: relative to ``blend_path``'s folder; empty
    means ``//skin_maps``. ``settings.file_prefix`` is replaced by each material's name and ``settings.scale_length``
    by the scene's unit scale. Raises spectral_skin.SpectralSkinError / ValueError / OSError; nothing is saved then.
    """
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(blend_path))
    _ensure_registered()
    missing = [name for name in material_names if name not in bpy.data.materials]
    if missing:
        raise ValueError(f"no material named {', '.join(map(repr, missing))} in {blend_path}")
    scene = bpy.context.scene
    output_dir = bpy.path.abspath(settings.output_dir or "//skin_maps")
    plans = {}
    for name in material_names:
        material_settings = settings.replace(
            file_prefix=name, output_dir=output_dir, scale_length=scene.unit_settings.scale_length)
        plans[name] = make_plan(material_settings)
    for plan in plans.values():
        write_textures(plan)
    for name, plan in plans.items():
        material = bpy.data.materials[name]
        nodes.apply_plan(material, plan)
        props.store_result(material, plan)
        if pack:
            for node in nodes.tagged_nodes(material.node_tree):
                if node.type == "TEX_IMAGE" and node.image is not None:
                    node.image.pack()
    out_blend = os.path.abspath(out_blend)
    os.makedirs(os.path.dirname(out_blend), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out_blend, relative_remap=True)
    return plans


def _read_map(path: str, name: str) -> Any:
    image = bpy.data.images.load(os.path.abspath(path))
    try:
        return props._image_parameter_map(image, name)
    finally:
        bpy.data.images.remove(image)


def main(argv: list[str] | None = None) -> int:
    import argparse

    import spectral_skin

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("blend")
    parser.add_argument("out_blend")
    parser.add_argument("--material", action="append", required=True, help="material name (repeatable)")
    parser.add_argument("--preset", default="caucasian")
    for name in PARAMETERS:
        flag = name.replace("_", "-")
        parser.add_argument(f"--{flag}", type=float, help=f"{name} (overrides the preset)")
        parser.add_argument(f"--{flag}-map", help=f"image of {name} per texel")
    parser.add_argument("--method", choices=["BURLEY", "RANDOM_WALK"], default="BURLEY")
    parser.add_argument("--out-dir", default="", help="texture folder ('//' = next to the input .blend)")
    parser.add_argument("--pack", action="store_true", help="pack the textures into the .blend")
    args = parser.parse_args(argv)
    try:
        overrides = {n: getattr(args, n) for n in PARAMETERS if getattr(args, n) is not None}
        settings = SkinSettings.from_preset(args.preset, **overrides).replace(
            method=args.method, output_dir=args.out_dir)
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(args.blend))
        maps = {n: _read_map(getattr(args, f"{n}_map"), n) for n in PARAMETERS if getattr(args, f"{n}_map")}
        settings = settings.replace(maps=maps)
        apply_to_materials(args.blend, args.material, settings, args.out_blend, pack=args.pack)
    except (spectral_skin.SpectralSkinError, ValueError, OSError) as error:
        print(f"spectral-skin batch: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
