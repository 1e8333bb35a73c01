"""The add-on's extended physiology in Blender: the Advanced sliders from the core's table, Apply with a non-default
epidermis thickness against evaluate(), presets setting the extended sliders, the albedo swatch following the sliders,
the batch flags.

Headless, no rendering. Run: .venv-blender/5.0/bin/python -m pytest tests/blender/test_addon_extended.py
"""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

bpy = pytest.importorskip("bpy")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]

from blender_addon import albedo as addon_albedo  # noqa: E402
from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.work import Work  # noqa: E402

SPECS = {p["name"]: p for p in spectral_skin.parameters()}
EXTENDED = [n for n, p in SPECS.items() if p["default"] is not None]


def _principled(material):
    found = addon_nodes.tagged_nodes(material.node_tree, "principled")
    assert len(found) == 1, [n.name for n in material.node_tree.nodes]
    return found[0]


def test_advanced_sliders_are_the_cores_parameters(addon):
    assert len(EXTENDED) == 3
    rna = bpy.types.Material.bl_rna.properties["spectral_skin"].fixed_type.bl_rna.properties
    material = bpy.data.materials.new("Skin")
    for name in EXTENDED:
        prop = rna[name]
        assert (prop.hard_min, prop.hard_max) == pytest.approx((SPECS[name]["min"], SPECS[name]["max"]), rel=1e-6)
        assert prop.default == pytest.approx(SPECS[name]["default"], rel=1e-6)
        assert getattr(material.spectral_skin, name) == pytest.approx(SPECS[name]["default"], rel=1e-6)
        assert prop.name.startswith(SPECS[name]["label"])
    assert bpy.types.SPECTRAL_SKIN_PT_advanced.bl_parent_id == "SPECTRAL_SKIN_PT_material"
    assert "DEFAULT_CLOSED" in bpy.types.SPECTRAL_SKIN_PT_advanced.bl_options


def test_apply_with_a_thin_epidermis_gives_evaluates_base_color(addon):
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new("Skin")
    props = material.spectral_skin
    props.epidermis_thickness_mm = 0.08
    props.blood_oxygenation = 0.6
    props.method = "RANDOM_WALK"
    assert props.preset == "CUSTOM"
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    node = _principled(material)
    values = {"epidermis_thickness_mm": props.epidermis_thickness_mm, "blood_oxygenation": props.blood_oxygenation}
    expected = spectral_skin.evaluate(preset="caucasian", blender=bpy.app.version, **values)["methods"]["random_walk"]
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], expected["base_color"], rtol=1e-6)
    paper = spectral_skin.evaluate(preset="caucasian", blender=bpy.app.version)["methods"]["random_walk"]
    assert np.max(np.abs(np.subtract(expected["base_color"], paper["base_color"]))) > 0.01
    np.testing.assert_allclose(props.result_radius_mm, expected["subsurface_radius_mm"], rtol=1e-6)


def test_presets_set_the_extended_sliders(addon):
    material = bpy.data.materials.new("Skin")
    props = material.spectral_skin
    for name, preset in spectral_skin.presets().items():
        for extended in EXTENDED:  # off the preset's values first
            setattr(props, extended, SPECS[extended]["min"])
        assert props.preset == "CUSTOM"
        props.preset = name.upper()
        assert props.preset == name.upper()  # setting the sliders did not switch the menu to Custom
        for param in (*[n for n in SPECS if n not in EXTENDED], *EXTENDED):
            assert getattr(props, param) == pytest.approx(preset.get(param, SPECS[param]["default"]), rel=1e-6), (
                name, param)


def test_swatch_follows_the_sliders(addon):
    material = bpy.data.materials.new("Skin")
    props = material.spectral_skin
    space = addon_nodes.scene_working_space()

    def albedo(p):
        values = {n: getattr(p, n) for n in SPECS}
        return spectral_skin.evaluate(outputs=["albedo"], working_space=space, **values)["diffuse_reflectance_rgb"]

    np.testing.assert_allclose(props.swatch, albedo(props), rtol=1e-5)  # a new material: the default preset's
    before = tuple(props.swatch)
    props.epidermis_thickness_mm = 0.05
    assert tuple(props.swatch) != pytest.approx(before, abs=1e-3)
    np.testing.assert_allclose(props.swatch, albedo(props), rtol=1e-5)
    props.hemoglobin = 0.06
    np.testing.assert_allclose(props.swatch, albedo(props), rtol=1e-5)
    props.preset = "AFRICAN"
    np.testing.assert_allclose(props.swatch, albedo(props), rtol=1e-5)
    with pytest.raises(AttributeError):
        props.swatch = (1.0, 0.0, 0.0)  # read-only: it shows the model's colour
    if hasattr(bpy.data, "colorspace"):  # Blender 5.0 on: the swatch is in the blend file's working space
        assert bpy.ops.wm.set_working_color_space(working_space="Linear Rec.2020", convert_colors=False) == {
            "FINISHED"}
        space = addon_nodes.scene_working_space()
        assert space == "Linear Rec.2020"
        props.blood_oxygenation = 0.3
        np.testing.assert_allclose(props.swatch, albedo(props), rtol=1e-5)


def test_batch_flags_and_sidecar_carry_the_extended_values(tmp_path):
    """The headless batch apply (blender_addon/batch.py, its own process as a farm runs it): one flag per extended
    parameter of the core's table; the sidecar records the values; Base Color is evaluate's for them."""
    blend = tmp_path / "in.blend"
    script = ("import bpy; bpy.ops.wm.read_factory_settings(use_empty=True); bpy.data.materials.new('Skin').use_fake_user = True; "
              "bpy.context.scene.render.engine = 'CYCLES'; "
              f"bpy.ops.wm.save_as_mainfile(filepath={str(blend)!r})")
    subprocess.run([sys.executable, "-c", script], check=True, capture_output=True)
    out = tmp_path / "out.blend"
    run = subprocess.run([sys.executable, str(REPO / "blender_addon" / "batch.py"), "apply", str(blend), str(out),
                          "--material", "Skin", "--preset", "asian", "--epidermis-thickness-mm", "0.1",
                          "--baseline-absorption-scale", "2"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    sidecar = json.loads((tmp_path / "out.spectral_skin.json").read_text())
    extended = {"epidermis_thickness_mm": 0.1, "baseline_absorption_scale": 2.0,
                "blood_oxygenation": SPECS["blood_oxygenation"]["default"]}
    assert sidecar["Skin"]["extended"] == extended
    check = (f"import bpy, json; bpy.ops.wm.open_mainfile(filepath={str(out)!r}); m = bpy.data.materials['Skin']; "
             "n = [n for n in m.node_tree.nodes if n.get('spectral_skin') == 'principled'][0]; "
             "print(json.dumps(list(n.inputs['Base Color'].default_value[:3])))")
    base_color = json.loads(subprocess.run([sys.executable, "-c", check], check=True, capture_output=True,
                                           text=True).stdout.strip().splitlines()[-1])
    expected = spectral_skin.evaluate(preset="asian", blender=bpy.app.version, **extended)["methods"]["burley"]
    np.testing.assert_allclose(base_color, expected["base_color"], rtol=1e-6)


def _albedo_material(tmp_path, codes):
    """A saved .blend with a material whose Principled Base Color is an 8-bit sRGB PNG of ``codes`` (H, W, 3 bytes,
    row 0 at the top)."""
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "head.blend"))
    h, w, _ = codes.shape
    image = bpy.data.images.new("Albedo", w, h, alpha=False, float_buffer=False)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = codes[::-1] / 255.0
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw = str(tmp_path / "albedo.png")
    image.file_format = "PNG"
    image.save()
    material = bpy.data.materials.new("Skin")
    if material.node_tree is None:  # Blender < 5.0 (use_nodes is deprecated in 5.0, where node trees always exist)
        material.use_nodes = True
    tree = material.node_tree
    principled = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tree.links.new(tex.outputs["Color"], principled.inputs["Base Color"])
    return material


def test_from_albedo_texture_is_disabled_without_the_cores_fit(addon, monkeypatch):
    monkeypatch.delattr(spectral_skin, "fit_albedo_map", raising=False)
    bpy.data.materials.new("Skin")
    assert not bpy.ops.spectral_skin.from_albedo_texture.poll()


def test_from_albedo_texture_sets_the_parameter_map(addon, tmp_path, monkeypatch):
    """The operator's glue around the core's fit (recorded as it passes): the fit gets the PNG's sRGB codes decoded
    (IEC 61966-2-1) as Linear Rec.709 and, by default, chooses the epidermis thickness; the core writes the
    parameter EXR beside the .blend (the four per texel and the extended physiology as channels), which becomes the
    material's Parameter Map; the chosen thickness goes to the Advanced slider; Apply then takes the map (its
    one-value extended channels as the material's values). Hold Epidermis Thickness fits at the slider's value."""
    codes = np.array([[[200, 150, 120], [90, 60, 40]], [[255, 0, 10], [128, 128, 128]]], dtype=np.uint8)
    material = _albedo_material(tmp_path, codes)
    calls = []
    fit_map = spectral_skin.fit_albedo_map
    fits = []

    def fit_albedo_map(rgb, *, working_space, epidermis_thickness_mm=None, **keywords):
        calls.append((rgb.copy(), working_space, epidermis_thickness_mm))
        fits.append(fit_map(rgb, working_space=working_space, epidermis_thickness_mm=epidermis_thickness_mm,
                            **keywords))
        return fits[-1]

    monkeypatch.setattr(spectral_skin, "fit_albedo_map", fit_albedo_map)
    assert bpy.ops.spectral_skin.from_albedo_texture(material="Skin") == {"FINISHED"}
    rgb, space, thickness = calls[0]
    c = codes / 255.0
    np.testing.assert_allclose(rgb, np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4), rtol=1e-5,
                               atol=1e-7)
    assert space == "Linear Rec.709" and thickness is None and fits[0].thickness is not None
    props = material.spectral_skin
    path = tmp_path / "head_Skin_params.exr"
    assert props.params_map is not None and pathlib.Path(bpy.path.abspath(props.params_map.filepath)) == path
    planes = spectral_skin.read_parameter_map(str(path))
    np.testing.assert_array_equal(np.stack([planes[n] for n in ("melanin", "melanin_blend", "hemoglobin",
                                                                 "oiliness")], axis=-1), fits[0].params)
    chosen = fits[0].extended["epidermis_thickness_mm"]
    np.testing.assert_array_equal(planes["epidermis_thickness_mm"], np.float32(chosen))
    assert props.epidermis_thickness_mm == pytest.approx(chosen, rel=1e-6)
    props.output_dir = str(tmp_path / "textures")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert "epidermis_thickness_mm" not in props.result_warning  # the slider holds the map's value
    # Hold Epidermis Thickness: the fit is made at the slider's value.
    props.epidermis_thickness_mm = 0.08
    assert bpy.ops.spectral_skin.from_albedo_texture(material="Skin", hold_thickness=True) == {"FINISHED"}
    assert calls[1][2] == pytest.approx(0.08, rel=1e-6) and fits[1].thickness is None
    assert props.epidermis_thickness_mm == pytest.approx(0.08, rel=1e-6)


def test_from_albedo_texture_with_a_skin_mask(addon, tmp_path, monkeypatch):
    """A texture that is half skin, half green paint: the fit, given the material's Skin Mask (a painted image, white
    on the skin), gets the mask (the skin texels as True), counts the others as masked out, and gives no diagnosis;
    without the mask, the half of the texture outside skin's colours is diagnosed. A mask of another size is refused
    naming both images, and the material is left as it was."""
    skin = [[200, 150, 120], [190, 140, 115], [150, 105, 80], [90, 60, 40]]
    codes = np.array([skin, [[40, 200, 40]] * 4], dtype=np.uint8)  # row 0 skin, row 1 green
    material = _albedo_material(tmp_path, codes)
    masks = []
    fit_map = spectral_skin.fit_albedo_map

    def fit_albedo_map(rgb, **keywords):
        masks.append(keywords.get("mask"))
        return fit_map(rgb, **keywords)

    monkeypatch.setattr(spectral_skin, "fit_albedo_map", fit_albedo_map)
    assert bpy.ops.spectral_skin.from_albedo_texture(material="Skin") == {"FINISHED"}
    assert masks[-1] is None
    unmasked = material.spectral_skin.params_map

    mask = bpy.data.images.new("Skin Mask", 4, 2, alpha=False, float_buffer=False)
    rgba = np.ones((2, 4, 4), dtype=np.float32)
    rgba[0, :, :3] = 0.0  # Blender's row 0 is the bottom: the green row is not skin
    mask.pixels.foreach_set(rgba.ravel())
    material.spectral_skin.skin_mask = mask
    assert bpy.ops.spectral_skin.from_albedo_texture(material="Skin") == {"FINISHED"}
    expected = np.array([[True] * 4, [False] * 4])
    print(f"mask given to the fit: {masks[-1]}")
    np.testing.assert_array_equal(masks[-1], expected)

    small = bpy.data.images.new("Small Mask", 2, 2, alpha=False, float_buffer=False)
    material.spectral_skin.skin_mask = small
    before = material.spectral_skin.params_map
    with pytest.raises(RuntimeError, match="'Small Mask' is 2x2 texels but the Base Color 'Albedo' is 4x2"):
        bpy.ops.spectral_skin.from_albedo_texture(material="Skin")
    assert material.spectral_skin.params_map == before and before is not None and unmasked is not None


def test_from_albedo_texture_worker_reports_progress_and_cancels_leaving_the_material(addon, tmp_path):
    """From Albedo Texture started from the panel runs the fit in the worker Apply uses (work.Work): cancelled before
    it starts (Esc at once) or part-way (Esc once texels are done: the core's progress callback answers False), it
    ends with InterruptedError, no result, no file written and the material as it was; run through, its progress
    reaches 1, the parameter and residual EXRs are written, and only the operator's last step (albedo.finish_albedo, on
    the main thread) sets the material's Parameter Map."""
    codes = np.array([[[200, 150, 120], [90, 60, 40], [180, 120, 100]],
                      [[150, 105, 80], [120, 90, 70], [230, 190, 170]]], dtype=np.uint8)
    material = _albedo_material(tmp_path, codes)
    props = material.spectral_skin

    def state():
        return (props.params_map, props.epidermis_thickness_mm, sorted(p.name for p in tmp_path.iterdir()))

    before = state()
    job = addon_albedo.prepare_albedo(material)
    assert job.image == "Albedo" and job.albedo.shape == (2, 3, 3) and job.epidermis_thickness_mm is None
    at_once = Work(addon_albedo.albedo_task(job))
    at_once.cancel.set()
    part_way = Work(addon_albedo.albedo_task(job))
    reported: list[tuple[int, int]] = []

    def esc_once_texels_are_done(done: int, total: int, work=part_way) -> bool:
        reported.append((done, total))
        if done > 0:
            work.cancel.set()
        return Work._progress(work, done, total)

    part_way._progress = esc_once_texels_are_done
    for work in (at_once, part_way):
        work.thread.start()
        work.thread.join(120)
        assert not work.thread.is_alive()
        assert work.result is None and isinstance(work.error, InterruptedError), work.error
        assert not work.writing and state() == before
    assert reported[0] == (0, 6) and reported[-1][0] > 0, reported

    work = Work(addon_albedo.albedo_task(job))
    work.thread.start()
    work.thread.join(120)
    assert work.error is None and work.result is not None and work.fraction == 1.0 and work.writing
    assert pathlib.Path(job.path).is_file() and pathlib.Path(job.residual_path).is_file()
    assert props.params_map == before[0]  # the worker changed no Blender data
    summary = addon_albedo.finish_albedo(material, job, work.result)
    assert props.params_map is not None and pathlib.Path(bpy.path.abspath(props.params_map.filepath)) == pathlib.Path(
        job.path)
    assert summary["image"] == "Albedo" and props.epidermis_thickness_mm == pytest.approx(
        summary["extended"]["epidermis_thickness_mm"], rel=1e-6)


def test_panels_draw_the_swatch_and_the_advanced_sliders(addon, draw_panel):
    material = bpy.data.materials.new("Skin")
    context = type("Context", (), {"material": material})()
    drawn: list[str] = []
    for panel in (bpy.types.SPECTRAL_SKIN_PT_material, bpy.types.SPECTRAL_SKIN_PT_advanced):
        assert panel.poll(context)
        drawn += draw_panel(panel, context)
    assert "swatch" in drawn and drawn[-3:] == EXTENDED
