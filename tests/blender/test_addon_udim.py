"""UDIM tile sets in the add-on: a tiled Base Color image (four 8-bit sRGB tiles) through From Albedo Texture (one fit
for the set: one thickness, a parameter tile set beside the .blend set as a tiled Parameter Map) and Apply in Baked
mode (the tiles computed as one texture, each texture written as a tile set and loaded as a tiled image). Each
written albedo tile is checked against the core's maps() of that tile's parameters alone (read back with
OpenImageIO) and against the texture's own colours (within the fit's residual + 0.1 ΔE00, by the independent
CIEDE2000 of tests/python/color_difference.py). Live mode's reading of a tile set is rendered in test_live_mode.py.

Headless, no rendering. Run: .venv-blender/5.3/bin/python -m pytest tests/blender/test_addon_udim.py
"""

from __future__ import annotations

import pathlib

import pytest

bpy = pytest.importorskip("bpy")
oiio = pytest.importorskip("OpenImageIO")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]

import color_difference  # noqa: E402  (tests/python/color_difference.py, on the path: conftest.py)

from blender_addon import nodes as addon_nodes  # noqa: E402

TILES = (1001, 1002, 1011, 1012)


def _srgb_decode(codes: np.ndarray) -> np.ndarray:
    c = codes / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _srgb_encode(linear: np.ndarray) -> np.ndarray:
    v = np.clip(linear, 0.0, 1.0)
    return np.round(np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055) * 255.0).astype(np.uint8)


def _tile_codes(k: int) -> np.ndarray:
    """A 6 x (3 + k % 2) tile of skin colours: the presets' albedos, scaled a little texel by texel."""
    names = ("caucasian", "asian", "african")
    h, w = 3 + k % 2, 6
    rgb = np.empty((h, w, 3))
    for y in range(h):
        for x in range(w):
            base = spectral_skin.evaluate(preset=names[(x + y + k) % 3], outputs=["albedo"])["diffuse_reflectance_rgb"]
            rgb[y, x] = np.asarray(base) * (0.9 + 0.04 * ((x * 3 + y + k) % 5))
    return _srgb_encode(rgb)


def _read_rgb(path: pathlib.Path) -> np.ndarray:
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    pixels = image.read_image("float")
    image.close()
    return np.asarray(pixels)[:, :, :3]


def _tiled_albedo_material(tmp_path: pathlib.Path) -> tuple[bpy.types.Material, dict[int, np.ndarray]]:
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "head.blend"))
    codes = {}
    for k, tile in enumerate(TILES):
        codes[tile] = _tile_codes(k)
        h, w, _ = codes[tile].shape
        image = bpy.data.images.new(f"tile{tile}", w, h, alpha=False, float_buffer=False)
        rgba = np.ones((h, w, 4), dtype=np.float32)
        rgba[:, :, :3] = codes[tile][::-1] / 255.0
        image.pixels.foreach_set(rgba.ravel())
        image.filepath_raw = str(tmp_path / f"albedo.{tile}.png")
        image.file_format = "PNG"
        image.save()
        bpy.data.images.remove(image)
    tiled = bpy.data.images.load(str(tmp_path / "albedo.1001.png"))
    tiled.source = "TILED"
    assert sorted(t.number for t in tiled.tiles) == list(TILES)
    material = bpy.data.materials.new("Skin")
    if material.node_tree is None:  # Blender < 5.0
        material.use_nodes = True
    tree = material.node_tree
    principled = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = tiled
    tree.links.new(tex.outputs["Color"], principled.inputs["Base Color"])
    return material, codes


def test_a_tile_set_goes_from_albedo_to_baked_tiled_maps(addon, tmp_path):
    material, codes = _tiled_albedo_material(tmp_path)
    assert bpy.ops.spectral_skin.from_albedo_texture(material="Skin") == {"FINISHED"}
    props = material.spectral_skin
    assert props.params_map is not None and props.params_map.source == "TILED"
    assert sorted(t.number for t in props.params_map.tiles) == list(TILES)
    thickness = props.epidermis_thickness_mm
    for tile in TILES:
        planes = spectral_skin.read_parameter_map(str(tmp_path / f"head_Skin_params.{tile}.exr"))
        assert planes["melanin"].shape == codes[tile].shape[:2]
        np.testing.assert_array_equal(planes["epidermis_thickness_mm"], np.float32(thickness))  # one for the set
    props.output_dir = str(tmp_path / "textures")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}, props.result_warning
    albedo_node = addon_nodes.tagged_nodes(material.node_tree, "albedo")[0]
    assert albedo_node.image.source == "TILED" and "<UDIM>" in albedo_node.image.filepath
    assert sorted(t.number for t in albedo_node.image.tiles) == list(TILES)
    for tile in TILES:
        written = _read_rgb(tmp_path / "textures" / f"head_Skin_albedo.{tile}.exr")
        alone = spectral_skin.maps(**spectral_skin.read_parameter_map(str(tmp_path / f"head_Skin_params.{tile}.exr")),
                                   outputs=["albedo"], blender=bpy.app.version)["albedo"]
        np.testing.assert_allclose(written, alone, rtol=2e-3, atol=1e-4)  # half-float files
        residual = _read_rgb_one(tmp_path / f"head_Skin_residual.{tile}.exr")
        de = color_difference.delta_e00_linear_rgb(_srgb_decode(codes[tile].astype(np.float64)).reshape(-1, 3),
                                                   written.astype(np.float64).reshape(-1, 3))
        assert np.all(de <= residual.ravel() + 0.1), (tile, de, residual)


def _read_rgb_one(path: pathlib.Path) -> np.ndarray:
    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    pixels = image.read_image("float")
    image.close()
    return np.asarray(pixels)[:, :, 0]
