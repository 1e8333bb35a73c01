"""The add-on's parameter maps and texture files: read by the core (never Blender's zeros), refused where the result
would be wrong, kept apart between .blend files; the preset menu, the clamp checkbox, Remove and the worker thread.

Headless, no rendering. Parameter files are written with OpenImageIO and the reference material is
``spectral_skin.maps`` on the arrays OpenImageIO reads back (and ``spectral-skin maps`` on the same file, when the CLI
is built). Run: .venv/bin/python -m pytest tests/blender/test_addon_maps.py
"""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

bpy = pytest.importorskip("bpy")
oiio = pytest.importorskip("OpenImageIO")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]

from blender_scenes import material_snapshot, read_exr  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.apply import Job, apply_task  # noqa: E402
from blender_addon.core import ParameterMap, SkinSettings  # noqa: E402
from blender_addon.work import Work  # noqa: E402

CLI = REPO / "target" / "release" / "spectral-skin"
PARAMETERS = ("melanin", "melanin_blend", "hemoglobin", "oiliness")


def reference_maps(*args, **kwargs):
    """``spectral_skin.maps`` for this Blender and Cycles (the scenes of these tests), its images rounded to half
    floats as the add-on writes them (``write_maps``' default precision): a dict (the core's ``Maps`` is read-only)."""
    result = dict(spectral_skin.maps(*args, blender=bpy.app.version, engine="cycles", **kwargs))
    for key in ("albedo", "radius"):
        if result.get(key) is not None:
            result[key] = result[key].astype(np.float16).astype(np.float32)
    return result


def write_channels(path: pathlib.Path, pixels: np.ndarray, channels: tuple[str, ...]) -> None:
    data = np.ascontiguousarray(pixels.reshape(pixels.shape[0], pixels.shape[1], -1), dtype=np.float32)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2], "float")
    spec.channelnames = channels
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(data), out.geterror()
    out.close()


def read_channels(path: pathlib.Path) -> dict[str, np.ndarray]:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    names = list(inp.spec().channelnames)
    pixels = np.asarray(inp.read_image(0, 0, 0, len(names), oiio.FLOAT), dtype=np.float32)
    inp.close()
    return {name: pixels[:, :, c] for c, name in enumerate(names)}


def face(height: int = 6, width: int = 8) -> np.ndarray:
    """(H, W, 4) parameters with smooth variation in every channel (many distinct texels)."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    u, v = x / (width - 1), y / (height - 1)
    return np.stack([0.01 + 0.3 * u * v, 0.3 + 0.6 * v, 0.002 + 0.06 * u, 0.2 + 0.5 * u * (1 - v)], axis=2)


def saved_material(tmp_path: pathlib.Path, blend: str = "scene.blend", name: str = "Skin"):
    """A material in a scene rendered with Cycles (the references below are Cycles'), saved as ``blend``."""
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new(name)
    material.use_fake_user = True
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / blend))
    return bpy.data.materials[name]


def written(tmp_path: pathlib.Path, stem: str) -> tuple[np.ndarray, np.ndarray]:
    folder = tmp_path / "skin_maps"
    return read_exr(str(folder / f"{stem}_albedo.exr")), read_exr(str(folder / f"{stem}_radius.exr"))


def test_four_channel_parameter_exr_gives_the_cli_material(addon, tmp_path):
    params = face()
    path = tmp_path / "face.exr"
    write_channels(path, params, PARAMETERS)
    material = saved_material(tmp_path)
    material.spectral_skin.params_map = bpy.data.images.load(str(path))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    albedo, radius = written(tmp_path, "scene_Skin")
    # Reference: OpenImageIO's reading of the same file, through the core's maps().
    channels = read_channels(path)
    reference = reference_maps(np.stack([channels[p] for p in PARAMETERS], axis=2))
    np.testing.assert_array_equal(albedo, reference["albedo"])
    np.testing.assert_array_equal(radius, reference["radius"])
    assert albedo.std(axis=(0, 1)).min() > 1e-3  # the map shows through: not one colour
    if CLI.exists():  # the CLI on the same file writes the same maps
        out = tmp_path / "cli"
        subprocess.run([str(CLI), "maps", "--params", str(path), "--out", str(out)], check=True, capture_output=True)
        np.testing.assert_allclose(albedo, read_exr(str(out / "albedo.exr"))[:, :, :3], rtol=1e-6)
        np.testing.assert_allclose(radius, read_exr(str(out / "radius.exr"))[:, :, :3], rtol=1e-6)


def test_one_channel_exr_named_melanin(addon, tmp_path):
    melanin = face()[:, :, 0]
    path = tmp_path / "melanin.exr"
    write_channels(path, melanin, ("melanin",))
    material = saved_material(tmp_path)
    material.spectral_skin.preset = "ASIAN"
    material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    albedo, _ = written(tmp_path, "scene_Skin")
    asian = spectral_skin.presets()["asian"]
    reference = reference_maps(melanin=read_channels(path)["melanin"], melanin_blend=asian["melanin_blend"],
                                   hemoglobin=asian["hemoglobin"], oiliness=asian["oiliness"])
    np.testing.assert_array_equal(albedo, reference["albedo"])
    # Not the whitish material of melanin 0 everywhere.
    zero = spectral_skin.evaluate(0.0, asian["melanin_blend"], asian["hemoglobin"], asian["oiliness"])
    assert np.all(albedo.reshape(-1, 3)[:, 2] < np.asarray(zero["methods"]["burley"]["base_color"])[2])


def test_packed_parameter_map_is_read_from_its_bytes(addon, tmp_path):
    params = face()
    path = tmp_path / "face.exr"
    write_channels(path, params, PARAMETERS)
    material = saved_material(tmp_path)
    image = bpy.data.images.load(str(path))
    image.pack()
    path.unlink()
    material.spectral_skin.params_map = image
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    albedo, _ = written(tmp_path, "scene_Skin")
    np.testing.assert_array_equal(albedo, reference_maps(params)["albedo"])


def test_unusable_parameter_file_is_a_clear_error(addon, tmp_path):
    material = saved_material(tmp_path)
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    before = material_snapshot(material)
    rgb = tmp_path / "rgb.exr"
    write_channels(rgb, face()[:, :, :3], ("R", "G", "B"))
    material.spectral_skin.params_map = bpy.data.images.load(str(rgb))
    with pytest.raises(RuntimeError, match=r"rgb\.exr.*missing channels melanin.*found channels"):
        bpy.ops.spectral_skin.apply(material="Skin")
    material.spectral_skin.params_map = None
    material.spectral_skin.melanin_map = bpy.data.images.load(str(rgb))  # R, G, B that differ: not a grey image
    with pytest.raises(RuntimeError, match=r"melanin map.*rgb\.exr.*found channels R, G, B that differ.*not grey"):
        bpy.ops.spectral_skin.apply(material="Skin")
    assert material_snapshot(material) == before
    assert not (tmp_path / "skin_maps").exists()


def test_unsaved_blend_is_refused_and_nothing_written(addon, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # Blender's working folder: where "//skin_maps" used to land
    path = tmp_path / "melanin.exr"
    write_channels(path, face()[:, :, 0], ("melanin",))
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    before = material_snapshot(material)
    assert bpy.data.filepath == "" and material.spectral_skin.output_dir == "//skin_maps"
    material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
    with pytest.raises(RuntimeError, match="not saved yet.*save the .blend first"):
        bpy.ops.spectral_skin.apply(material="Skin")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["melanin.exr"]
    assert material_snapshot(material) == before
    with pytest.raises(RuntimeError, match="not saved yet"):  # as from the panel (no window here: no worker thread)
        bpy.ops.spectral_skin.apply("INVOKE_DEFAULT", material="Skin")
    material.spectral_skin.output_dir = "relative_maps"
    with pytest.raises(RuntimeError, match="must be absolute"):
        bpy.ops.spectral_skin.apply(material="Skin")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["melanin.exr"]


def test_two_blends_in_one_folder_keep_their_maps(addon, tmp_path):
    values = {}
    for blend, melanin in (("a.blend", 0.05), ("b.blend", 0.3)):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        path = tmp_path / f"melanin_{blend}.exr"
        values[blend] = np.full((2, 3), melanin, dtype=np.float32)
        values[blend][0, 0] = 0.01
        write_channels(path, values[blend], ("melanin",))
        material = saved_material(tmp_path, blend)
        material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
        assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
        bpy.ops.wm.save_mainfile()
    assert sorted(p.name for p in (tmp_path / "skin_maps").iterdir()) == [
        "a_Skin_albedo.exr", "a_Skin_radius.exr", "b_Skin_albedo.exr", "b_Skin_radius.exr"]
    a, _ = written(tmp_path, "a_Skin")
    b, _ = written(tmp_path, "b_Skin")
    assert a[0, 1, 2] > b[0, 1, 2]  # less melanin: more blue
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "a.blend"))
    images = {n.image.filepath for n in addon_nodes.tagged_nodes(bpy.data.materials["Skin"].node_tree)
              if n.type == "TEX_IMAGE"}
    assert images == {"//skin_maps/a_Skin_albedo.exr", "//skin_maps/a_Skin_radius.exr"}


def test_editing_a_slider_switches_the_preset_to_custom(addon):
    props = bpy.data.materials.new("Skin").spectral_skin
    props.preset = "AFRICAN"
    african = spectral_skin.presets()["african"]
    assert props.preset == "AFRICAN"
    assert props.melanin == pytest.approx(african["melanin"]) and props.hemoglobin == pytest.approx(african["hemoglobin"])
    props.hemoglobin = 0.02
    assert props.preset == "CUSTOM"
    assert props.melanin == pytest.approx(african["melanin"])  # the other values stay
    props.preset = "ASIAN"
    assert props.preset == "ASIAN" and props.melanin == pytest.approx(spectral_skin.presets()["asian"]["melanin"])


def test_out_of_range_texels_offer_the_clamp_checkbox(addon, tmp_path):
    melanin = face()[:, :, 0]
    melanin[1, 2] = 0.9
    path = tmp_path / "melanin.exr"
    write_channels(path, melanin, ("melanin",))
    material = saved_material(tmp_path)
    material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
    with pytest.raises(RuntimeError) as info:
        bpy.ops.spectral_skin.apply(material="Skin")
    message = str(info.value)
    assert "Melanin (C_m) map: 1 texel outside 0 to 0.5" in message and "(2, 1)" in message, message
    assert "Clamp Out-of-Range Texels" in message and "clamp=True" not in message, message
    assert not (tmp_path / "skin_maps").exists()
    material.spectral_skin.clamp = True
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert "melanin: 0 NaN, 0 infinite, 1 out-of-range texels clamped" in material.spectral_skin.result_warning
    clamped = melanin.copy()
    clamped[1, 2] = 0.5
    albedo, _ = written(tmp_path, "scene_Skin")
    presets = spectral_skin.presets()["caucasian"]
    reference = reference_maps(melanin=clamped, melanin_blend=presets["melanin_blend"],
                                   hemoglobin=presets["hemoglobin"], oiliness=presets["oiliness"])
    np.testing.assert_array_equal(albedo, reference["albedo"])


def test_remove_restores_the_previous_shader(addon):
    material = bpy.data.materials.new("Skin")
    if material.node_tree is None:  # Blender before 5.0 (from 5.0 every material has its node tree)
        material.use_nodes = True
    tree = material.node_tree
    for node in list(tree.nodes):
        if node.type != "OUTPUT_MATERIAL":
            tree.nodes.remove(node)
    output = tree.get_output_node("ALL")
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    before = material_snapshot(material)
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}  # re-applied: still the first link kept
    assert output.inputs["Surface"].links[0].from_node.name.startswith(addon_nodes.NAME_PREFIX)
    assert bpy.ops.spectral_skin.remove(material="Skin") == {"FINISHED"}
    assert not addon_nodes.tagged_nodes(tree)
    assert output.inputs["Surface"].links[0].from_node == diffuse
    assert material_snapshot(material) == before
    assert not material.spectral_skin.has_result


def test_worker_reports_progress_and_cancels_with_nothing_written(addon, tmp_path):
    params = face(64, 48)
    maps = {p: ParameterMap(np.ascontiguousarray(params[:, :, c]), normalized=False) for c, p in enumerate(PARAMETERS)}
    settings = SkinSettings(maps=maps, output_dir=str(tmp_path / "maps"), file_prefix="Skin", surface="PAPER")
    work = Work(apply_task(Job(settings, None, {})))
    work.thread.start()
    work.thread.join(120)
    assert work.error is None and work.result is not None and work.fraction == 1.0
    assert sorted(p.name for p in (tmp_path / "maps").iterdir()) == ["Skin_albedo.exr", "Skin_radius.exr",
                                                                     "Skin_specular.exr"]
    cancelled = Work(apply_task(Job(settings.replace(output_dir=str(tmp_path / "cancelled")), None, {})))
    cancelled.cancel.set()
    cancelled.thread.start()
    cancelled.thread.join(120)
    assert cancelled.result is None and isinstance(cancelled.error, InterruptedError)
    assert not (tmp_path / "cancelled").exists()
    assert os.path.isdir(tmp_path / "maps")


def test_8_bit_png_maps_onto_the_range_once(addon, tmp_path):
    grey = np.array([[0, 64, 128], [191, 230, 255]], dtype=np.uint8)
    path = tmp_path / "hemoglobin.png"
    spec = oiio.ImageSpec(3, 2, 1, "uint8")
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(np.ascontiguousarray(grey[:, :, None])), oiio.geterror()
    out.close()
    material = saved_material(tmp_path)
    material.spectral_skin.hemoglobin_map = bpy.data.images.load(str(path))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    albedo, _ = written(tmp_path, "scene_Skin")
    low, high = spectral_skin.parameter_ranges()["hemoglobin"]
    caucasian = spectral_skin.presets()["caucasian"]
    reference = reference_maps(melanin=caucasian["melanin"], melanin_blend=caucasian["melanin_blend"],
                               hemoglobin=(low + (high - low) * grey / 255.0).astype(np.float32),
                               oiliness=caucasian["oiliness"])
    np.testing.assert_allclose(albedo, reference["albedo"], rtol=1e-6)


def _save_grey_exr_from_blender(path: pathlib.Path, grey: np.ndarray, color_mode: str) -> None:
    """Save ``grey`` (H, W, row 0 at the top) as Blender saves a grey image: an OpenEXR written by Blender itself
    (``save_render``, half floats, ``color_mode`` "RGB" or "RGBA"), R = G = B."""
    height, width = grey.shape
    image = bpy.data.images.new("grey_map", width, height, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[:, :, :3] = grey[::-1, :, None]  # Blender's pixels start at the bottom row
    image.pixels.foreach_set(rgba.ravel())
    settings = bpy.context.scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = color_mode
    settings.color_depth = "16"
    image.save_render(str(path), scene=bpy.context.scene)
    bpy.data.images.remove(image)


def test_grey_rgb_exr_saved_from_blender_applies(addon, tmp_path):
    melanin = face()[:, :, 0]
    material = saved_material(tmp_path)
    path = tmp_path / "melanin_grey.exr"
    _save_grey_exr_from_blender(path, melanin, "RGB")
    channels = read_channels(path)  # OpenImageIO's reading of Blender's file: the reference
    assert sorted(channels) == ["B", "G", "R"]
    assert np.array_equal(channels["R"], channels["G"]) and np.array_equal(channels["R"], channels["B"])
    np.testing.assert_allclose(channels["R"], melanin, rtol=1e-3)  # half floats
    material.spectral_skin.preset = "ASIAN"
    material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert material.spectral_skin.result_warning == ""
    albedo, _ = written(tmp_path, "scene_Skin")
    asian = spectral_skin.presets()["asian"]
    reference = reference_maps(melanin=channels["R"], melanin_blend=asian["melanin_blend"],
                               hemoglobin=asian["hemoglobin"], oiliness=asian["oiliness"])
    np.testing.assert_array_equal(albedo, reference["albedo"])
    # RGBA: applies too, and Apply reports the ignored alpha.
    rgba = tmp_path / "melanin_rgba.exr"
    _save_grey_exr_from_blender(rgba, melanin, "RGBA")
    material.spectral_skin.melanin_map = bpy.data.images.load(str(rgba))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert "melanin_rgba.exr" in material.spectral_skin.result_warning
    assert "alpha" in material.spectral_skin.result_warning


@pytest.mark.skipif(not CLI.exists(), reason="build the CLI first: cargo build --release")
def test_the_example_files_parameter_map_gives_the_cli_material(addon, tmp_path):
    """The four-channel file `spectral-skin example` writes, through the Parameter Map slot and through the CLI."""
    path = tmp_path / "face.exr"
    subprocess.run([str(CLI), "example", "--out", str(path), "--size", "24"], check=True, capture_output=True)
    material = saved_material(tmp_path)
    material.spectral_skin.params_map = bpy.data.images.load(str(path))
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    albedo, radius = written(tmp_path, "scene_Skin")
    out = tmp_path / "cli"
    version = f"{bpy.app.version[0]}.{bpy.app.version[1]}"
    subprocess.run([str(CLI), "maps", "--params", str(path), "--out", str(out), "--blender", version,
                    "--engine", "cycles"], check=True, capture_output=True)
    np.testing.assert_allclose(albedo, read_exr(str(out / "albedo.exr"))[:, :, :3], rtol=1e-6)
    np.testing.assert_allclose(radius, read_exr(str(out / "radius.exr"))[:, :, :3], rtol=1e-6)
    assert albedo.std(axis=(0, 1)).min() > 1e-3
