"""The Blender add-on (blender_addon/): registration, Apply on a material, re-apply, errors, the installable zip.

Headless, no rendering: each test starts from an empty factory scene. Run: .venv/bin/python -m pytest tests/blender/test_addon.py
"""

from __future__ import annotations

import pathlib
import subprocess
import sys

import pytest

bpy = pytest.importorskip("bpy")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]

import extension_process  # noqa: E402
from blender_scenes import material_snapshot  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.apply import apply_skin, apply_skins  # noqa: E402
from blender_addon.core import ParameterMap, SkinSettings  # noqa: E402

BLENDER_EXT = pathlib.Path(bpy.utils.system_resource("SCRIPTS")) / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"


def _registered() -> bool:
    return hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply")


def _principled(material):
    found = addon_nodes.tagged_nodes(material.node_tree, "principled")
    assert len(found) == 1, [n.name for n in material.node_tree.nodes]
    return found[0]


def test_register_unregister_leaves_no_trace(addon):
    assert _registered()
    assert "spectral_skin" in bpy.types.Material.bl_rna.properties
    addon.unregister()
    try:
        assert not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply")
        assert not hasattr(bpy.types, "SPECTRAL_SKIN_PT_material")
        assert not hasattr(bpy.types.Material, "spectral_skin")
        assert "spectral_skin" not in bpy.types.Material.bl_rna.properties
        assert not hasattr(bpy.ops.spectral_skin, "apply") or "apply" not in dir(bpy.ops.spectral_skin)
    finally:
        addon.register()
    assert _registered()


def test_apply_preset_sets_principled_from_core(addon):
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    node = _principled(material)
    expected = spectral_skin.evaluate(preset="caucasian", blender=bpy.app.version)
    burley = expected["methods"]["burley"]
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], burley["base_color"], rtol=1e-6)
    scale_length = bpy.context.scene.unit_settings.scale_length
    radius_times_scale = np.array(node.inputs["Subsurface Radius"].default_value) * node.inputs["Subsurface Scale"].default_value
    np.testing.assert_allclose(radius_times_scale, burley["subsurface_radius_mm"] * 0.001 / scale_length, rtol=1e-6)
    assert node.subsurface_method == "BURLEY"
    assert node.inputs["Subsurface Weight"].default_value == 1.0
    assert node.inputs["IOR"].default_value == pytest.approx(1.4)
    assert node.inputs["Specular IOR Level"].default_value == pytest.approx(expected["specular"]["specular_ior_level"])
    assert node.inputs["Roughness"].default_value == pytest.approx(expected["specular"]["roughness"], rel=1e-6)
    output = material.node_tree.get_output_node("ALL")
    assert any(link.from_node == node for link in output.inputs["Surface"].links)
    result = material.spectral_skin
    assert result.has_result and result.result_computed
    np.testing.assert_allclose(result.result_radius_mm, burley["subsurface_radius_mm"], rtol=1e-6)


def test_scale_follows_scene_unit_scale(addon):
    bpy.context.scene.unit_settings.scale_length = 0.01  # one scene unit is a centimetre
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    node = _principled(material)
    assert node.inputs["Subsurface Scale"].default_value == pytest.approx(0.001 / 0.01, rel=1e-6)


def test_reapply_updates_own_nodes_and_leaves_user_nodes(addon):
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    user_node = material.node_tree.nodes.new("ShaderNodeRGB")
    user_node.name = "UserColour"
    user_node.outputs[0].default_value = (0.1, 0.2, 0.3, 1.0)
    count = len(material.node_tree.nodes)
    before = material_snapshot(material)

    props = material.spectral_skin
    props.preset = "AFRICAN"
    props.method = "RANDOM_WALK"
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}

    assert len(material.node_tree.nodes) == count
    node = _principled(material)
    expected = spectral_skin.evaluate(preset="african", blender=bpy.app.version)["methods"]["random_walk"]
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], expected["base_color"], rtol=1e-6)
    assert node.subsurface_method == "RANDOM_WALK"
    assert tuple(material.node_tree.nodes["UserColour"].outputs[0].default_value) == pytest.approx((0.1, 0.2, 0.3, 1.0))
    after = material_snapshot(material)
    others = lambda snap: {k: v for k, v in snap["values"].items() if not k[0].startswith(addon_nodes.NAME_PREFIX)}  # noqa: E731
    assert others(after) == others(before)


def test_invalid_parameter_changes_nothing(addon):
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    before = material_snapshot(material)
    with pytest.raises(spectral_skin.SpectralSkinError, match="melanin"):
        apply_skin(material, SkinSettings.from_preset("caucasian", melanin=0.9))
    assert material_snapshot(material) == before


def test_apply_writes_nothing_until_every_plan_is_computed(addon, tmp_path):
    """apply_skins (the operator's and the batch apply's path): a material whose plan fails leaves the others
    unchanged and no map written, though theirs were computed first."""
    first, second = bpy.data.materials.new("First"), bpy.data.materials.new("Second")
    for material in (first, second):
        assert bpy.ops.spectral_skin.apply(material=material.name) == {"FINISHED"}
    before = material_snapshot(first)
    melanin = np.linspace(0.0, 0.3, 12, dtype=np.float32).reshape(3, 4)
    good = SkinSettings.from_preset("asian", maps={"melanin": ParameterMap(melanin, normalized=False)},
                                    output_dir=str(tmp_path), file_prefix="First")
    with pytest.raises(spectral_skin.SpectralSkinError, match="melanin"):
        apply_skins([(first, good), (second, SkinSettings.from_preset("caucasian", melanin=0.9))])
    assert material_snapshot(first) == before
    assert list(tmp_path.iterdir()) == []
    plans = apply_skins([(first, good), (second, SkinSettings.from_preset("caucasian"))])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["First_albedo.exr", "First_radius.exr"]
    assert [first.spectral_skin.result_computed, second.spectral_skin.result_computed] == [
        plan.summary.computed for plan in plans]


def test_operator_reports_error_and_changes_nothing(addon, tmp_path):
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    before = material_snapshot(material)
    props = material.spectral_skin
    props.melanin_map = bpy.data.images.new("m", 4, 4, float_buffer=True)
    props.hemoglobin_map = bpy.data.images.new("h", 5, 4, float_buffer=True)  # sizes differ: the core rejects it
    props.output_dir = str(tmp_path)
    with pytest.raises(RuntimeError, match="Spectral Skin"):  # bpy turns an ERROR report into RuntimeError
        bpy.ops.spectral_skin.apply(material="Skin")
    assert material_snapshot(material) == before
    assert list(tmp_path.iterdir()) == []


def test_maps_write_textures_and_link_them(addon, tmp_path):
    material = bpy.data.materials.new("Skin")
    melanin = np.linspace(0.0, 0.3, 12, dtype=np.float32).reshape(3, 4)
    settings = SkinSettings.from_preset("asian", maps={"melanin": ParameterMap(melanin, normalized=False)},
                                        output_dir=str(tmp_path), file_prefix="Skin")
    plan = apply_skin(material, settings)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Skin_albedo.exr", "Skin_radius.exr"]
    node = _principled(material)
    albedo = addon_nodes.tagged_nodes(material.node_tree, "albedo")[0]
    radius = addon_nodes.tagged_nodes(material.node_tree, "radius")[0]
    assert albedo.image.colorspace_settings.name == "Linear Rec.709"
    assert radius.image.colorspace_settings.name == "Non-Color"
    assert node.inputs["Base Color"].links[0].from_node == albedo
    assert node.inputs["Subsurface Radius"].links[0].from_node == radius
    assert tuple(albedo.image.size) == (4, 3)
    assert plan.summary.computed
    # Back to constants: the texture nodes go, the values come back.
    apply_skin(material, SkinSettings.from_preset("asian"))
    assert not addon_nodes.tagged_nodes(material.node_tree, "albedo")
    assert not node.inputs["Base Color"].links


def test_batch_saves_relative_texture_paths(addon, tmp_path):
    from blender_addon.batch import apply_to_materials

    bpy.data.materials.new("Skin").use_fake_user = True
    source = tmp_path / "in.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(source))
    melanin = np.full((2, 2), 0.1, dtype=np.float32)
    melanin[0, 0] = 0.2
    settings = SkinSettings.from_preset("caucasian", maps={"melanin": ParameterMap(melanin, normalized=False)})
    out = tmp_path / "out" / "out.blend"
    apply_to_materials(str(source), ["Skin"], settings, str(out))
    bpy.ops.wm.open_mainfile(filepath=str(out))
    paths = sorted(image.filepath for image in bpy.data.images)
    # Named after the input .blend and the material, next to the input .blend.
    assert paths == ["//../skin_maps/in_Skin_albedo.exr", "//../skin_maps/in_Skin_radius.exr"]
    assert len(addon_nodes.tagged_nodes(bpy.data.materials["Skin"].node_tree, "principled")) == 1


def test_built_zip_validates_and_installs(tmp_path, extension_zip):
    # The add-on's own files, without the render-only script (scripts/tools/render_blend.py needs no add-on).
    import zipfile

    with zipfile.ZipFile(extension_zip) as archive:
        sources = {name: archive.read(name) for name in archive.namelist() if name.endswith(".py")}
    assert {"batch.py", "ops.py", "frame_values.py", "scene_facts.py", "core/scene.py"} <= set(sources)
    assert not [name for name, text in sources.items() if b"bpy.ops.render.render" in text]
    validate = subprocess.run([sys.executable, str(BLENDER_EXT), "validate", str(extension_zip)],
                              capture_output=True, text=True)
    assert validate.returncode == 0, validate.stdout + validate.stderr
    user = tmp_path / "user"
    user.mkdir()
    install = ("import bpy\nbpy.ops.extensions.package_install_files("
               f"filepath={str(extension_zip)!r}, repo='user_default', enable_on_install=True)")
    report = extension_process.report(extension_process.run_python(install + extension_process.APPLY_AND_REPORT,
                                                                   user, tmp_path))
    assert report["result"] == ["FINISHED"]
    assert report["module"].startswith("bl_ext.user_default.spectral_skin")
    unpacked = list((user / "extensions" / ".local").glob("lib/python3*/site-packages/spectral_skin/__init__.py"))
    assert unpacked, "the extension's wheel was not unpacked into the user's extensions"
    expected = spectral_skin.evaluate(preset="caucasian")["methods"]["burley"]["base_color"]
    np.testing.assert_allclose(report["base_color"], expected, rtol=1e-6)


def test_accuracy_level_reaches_the_core(addon):
    """The material's Accuracy setting is the core's named level; an unknown one changes nothing."""
    material = bpy.data.materials.new("Skin")
    material.spectral_skin.accuracy = "DRAFT"
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    draft = spectral_skin.evaluate(preset="caucasian", accuracy="draft", blender=bpy.app.version,
                                   engine="eevee")["methods"]["burley"]  # the factory scene renders with EEVEE
    node = _principled(material)
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], draft["base_color"], rtol=1e-6)
    assert "21 wavelengths" in material.spectral_skin.result_computed
    with pytest.raises(spectral_skin.SpectralSkinError, match="accuracy"):
        apply_skin(material, SkinSettings.from_preset("caucasian").replace(accuracy="FAST"))
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], draft["base_color"], rtol=1e-6)
