"""The add-on's portable scene analysis (blender_addon/core/scene.py), loaded without bpy: pixel footprints from
hand-computed camera geometry, the decisions and their overrides, and the plan they change (against the core's own
evaluate() for the albedo)."""

from __future__ import annotations

import numpy as np
import pytest
import spectral_skin
from addon_helpers import (
    BOX_AT_ORIGIN,
    animation_facts,
    camera_facts,
    core,
    effect_entry,
    scene,
    scene_facts,
    with_changes,
)


def test_perspective_footprint_by_hand():
    # 36 mm sensor over a 50 mm lens spans 0.72 m at 1 m; 1920 px wide: 0.375 mm per pixel at 1 m.
    cam = camera_facts(3.0)
    assert scene.footprint_mm(scene_facts(3.0), cam, 1.0) == pytest.approx(0.375)
    # Half the resolution percentage doubles it.
    assert scene.footprint_mm(scene_facts(3.0, pct=50), cam, 1.0) == pytest.approx(0.75)
    # Portrait frame with AUTO: the sensor width spans the taller side (1920 px).
    assert scene.footprint_mm(scene_facts(3.0, x=1080, y=1920), cam, 1.0) == pytest.approx(0.375)
    # VERTICAL: the 24 mm sensor height spans the 1080 px height: 24/50/1080 m per pixel at 1 m.
    vertical = camera_facts(3.0, sensor_fit="VERTICAL")
    assert scene.footprint_mm(scene_facts(3.0), vertical, 1.0) == pytest.approx(24 / 50 / 1080 * 1000)
    # HORIZONTAL on a portrait frame: the width (1080 px) takes the sensor width.
    horizontal = camera_facts(3.0, sensor_fit="HORIZONTAL")
    assert scene.footprint_mm(scene_facts(3.0, x=1080, y=1920), horizontal, 1.0) == pytest.approx(36 / 50 / 1080 * 1000)


def test_orthographic_footprint_and_scene_units():
    cam = camera_facts(5.0, type="ORTHO", ortho_scale=2.0)
    facts = scene.SceneFacts(resolution_x=1000, resolution_y=500, scale_length=0.01)
    # 2 scene units of 1 cm over 1000 px: 0.02 mm per pixel, whatever the depth.
    assert scene.footprint_mm(facts, cam, 1.0) == pytest.approx(0.02)
    assert scene.footprint_mm(facts, cam, 50.0) == pytest.approx(0.02)
    with pytest.raises(ValueError, match="PANO"):
        scene.footprint_mm(facts, camera_facts(5.0, type="PANO"), 1.0)


def test_nearest_depth_of_a_box():
    # The box's near face is 0.1 in front of the origin.
    assert scene.nearest_depth(camera_facts(2.0), BOX_AT_ORIGIN) == pytest.approx(1.9)
    # Camera inside the box: the clip start.
    assert scene.nearest_depth(camera_facts(0.0, clip_start=0.05), BOX_AT_ORIGIN) == pytest.approx(0.05)
    # Box behind the camera: not seen.
    behind = scene.CameraFacts("Back", "PERSP", (0.0, -2.0, 0.0), (0.0, -1.0, 0.0))
    assert scene.nearest_depth(behind, BOX_AT_ORIGIN) is None


def _constant_plan(**kw):
    return core.compute(core.SkinSettings.from_preset("caucasian", **kw))


def test_far_object_drops_subsurface_close_keeps_it():
    plan = _constant_plan()
    largest = max(plan.radius)  # mm
    # Footprint at depth d: 0.375 mm per metre; choose d so the largest radius is 0.1 px (far) and 5 px (close).
    far_depth = largest / 0.1 / 0.375
    close_depth = largest / 5 / 0.375
    settings = core.SkinSettings.from_preset("caucasian")
    far = scene.decide(plan, settings, scene_facts(far_depth + 0.1, frame=7, name="Far Cam"))
    entry = next(e for e in far if e["effect"] == "subsurface")
    assert entry["enabled"] is False
    assert entry["figures"]["largest_radius_px"] == pytest.approx(0.1, rel=1e-6)
    assert "frame 7" in entry["reason"] and "Far Cam" in entry["reason"] and "0.1 px" in entry["reason"]
    close = scene.decide(plan, settings, scene_facts(close_depth + 0.1))
    assert scene.enabled(close, "subsurface")
    assert next(e for e in close if e["effect"] == "subsurface")["figures"]["largest_radius_px"] == pytest.approx(5)
    # The smallest footprint over views wins: a far and a close view keep subsurface.
    both = scene.SceneFacts(1920, 1080, views=(*scene_facts(far_depth).views, *scene_facts(close_depth).views))
    assert scene.enabled(scene.decide(plan, settings, both), "subsurface")


def test_no_view_keeps_subsurface_with_the_reason():
    plan = _constant_plan()
    facts = scene.SceneFacts(1920, 1080, note="the scene has no camera")
    entry = next(e for e in scene.decide(plan, core.SkinSettings(), facts) if e["effect"] == "subsurface")
    assert entry["enabled"] and "no camera" in entry["reason"]


def test_overrides_win_and_bad_override_is_refused():
    plan = _constant_plan()
    settings = core.SkinSettings.from_preset("caucasian")
    far = scene_facts(1e4)
    forced = scene.decide(plan, settings, far, {"subsurface": "ON"})
    entry = next(e for e in forced if e["effect"] == "subsurface")
    assert entry["enabled"] and entry["override"] == "ON" and "automatic" in entry["reason"]
    off = scene.decide(plan, settings, scene_facts(0.5), {"subsurface": "OFF", "specular": "OFF"})
    assert not scene.enabled(off, "subsurface") and not scene.enabled(off, "specular")
    with pytest.raises(ValueError, match="AUTO, ON, OFF"):
        scene.decide(plan, settings, far, {"subsurface": "MAYBE"})


def test_scene_plan_far_is_plain_diffuse_with_the_cores_albedo():
    far = scene_facts(1e4)
    expected = spectral_skin.evaluate(preset="caucasian")["methods"]["burley"]["base_color"]
    for method in ("BURLEY", "RANDOM_WALK"):
        plan = scene.scene_plan(core.SkinSettings.from_preset("caucasian", method=method), far)
        assert plan.subsurface_weight == 0.0
        np.testing.assert_allclose(plan.base_color, expected, rtol=1e-6)
    close = scene.scene_plan(core.SkinSettings.from_preset("caucasian"), scene_facts(0.5))
    assert close.subsurface_weight == 1.0


def test_zero_oiliness_means_no_specular(tmp_path):
    """The paper's oil layer (the measured surface reflects dry skin too: test_addon_surface.py)."""
    plan = scene.scene_plan(core.SkinSettings.from_preset("caucasian", surface="PAPER", oiliness=0.0), None)
    entry = next(e for e in plan.effects if e["effect"] == "specular")
    assert not entry["enabled"] and "oil" in entry["reason"] and plan.specular_ior_level == 0.0
    # A map of zero oiliness beside a varying haemoglobin map: no specular texture, the albedo is a texture.
    hemoglobin = np.linspace(0.001, 0.05, 16, dtype=np.float32).reshape(4, 4)
    maps = {"hemoglobin": core.ParameterMap(hemoglobin, False), "oiliness": core.ParameterMap(np.zeros((4, 4), np.float32), False)}
    settings = core.SkinSettings.from_preset("caucasian", surface="PAPER", maps=maps, output_dir=str(tmp_path))
    plan = scene.scene_plan(settings, None)
    assert "specular" not in plan.textures and plan.specular_ior_level == 0.0
    assert "albedo" in plan.textures
    oily = settings.replace(maps={**maps, "oiliness": core.ParameterMap(np.full((4, 4), 0.3, np.float32), False)})
    assert scene.enabled(scene.scene_plan(oily, None).effects, "specular")


def test_constant_maps_become_values(tmp_path):
    maps = {"melanin": core.ParameterMap(np.full((4, 4), 0.02, np.float32), False)}
    settings = core.SkinSettings.from_preset("caucasian", maps=maps, output_dir=str(tmp_path))
    plan = scene.scene_plan(settings, None)
    assert plan.textures == {}
    expected = spectral_skin.evaluate(0.02, 0.7, 0.005, 0.3)["methods"]["burley"]
    np.testing.assert_allclose(plan.base_color, expected["base_color"], rtol=1e-5)
    np.testing.assert_allclose(plan.radius, expected["subsurface_radius_mm"], rtol=1e-5)
    entry = next(e for e in plan.effects if e["effect"] == "constant maps")
    # A constant oiliness gives specular values already (the core's constant detection): only two images were made.
    assert entry["figures"]["constant"] == ("albedo", "radius")


def test_frames_and_camera_switching():
    assert scene.sample_frames(1, 250, count=3) == [1, 63, 125, 188, 250]
    assert scene.sample_frames(1, 1) == [1]
    assert scene.sample_frames(1, 10, count=0, extra=[5, 40]) == [1, 5, 10]
    markers = [(10, "B"), (20, "C")]
    assert scene.active_camera(5, "A", markers) == "B"  # before the first marker: the earliest marker's camera
    assert scene.active_camera(15, "A", markers) == "B"
    assert scene.active_camera(20, "A", markers) == "C"
    assert scene.active_camera(5, "A", []) == "A"


def test_constant_maps_override_off_keeps_the_textures(tmp_path):
    maps = {"melanin": core.ParameterMap(np.full((4, 4), 0.02, np.float32), False)}
    settings = core.SkinSettings.from_preset("caucasian", maps=maps, output_dir=str(tmp_path))
    plan = scene.scene_plan(settings, None, {"constant maps": "OFF"})
    assert sorted(plan.textures) == ["albedo", "radius"] and plan.base_color is None


def test_thin_closed_object_gets_a_random_walk_open_one_burley():
    plan = _constant_plan()
    largest = max(plan.radius)  # mm
    settings = core.SkinSettings.from_preset("caucasian")
    shapes = (scene.ShapeFacts("Ear", 2.9 * largest, True), scene.ShapeFacts("Head", 3.1 * largest, True),
              scene.ShapeFacts("Scalp", 50 * largest, False, 12))
    effects = scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=shapes))
    entry = effect_entry(effects, "subsurface method")
    objects = entry["figures"]["objects"]
    assert objects["Ear"]["recommended"] == "RANDOM_WALK"
    assert objects["Ear"]["thickness_radii"] == pytest.approx(2.9)
    assert objects["Head"]["recommended"] is None  # 3.1 radii: thick enough for Burley
    assert objects["Scalp"]["recommended"] == "BURLEY" and "leaks" in objects["Scalp"]["reason"]
    assert "12 edges" in objects["Scalp"]["reason"]
    # Burley does not suit the thin ear: the entry says so, and only about the ear.
    assert entry["enabled"] is False and "Ear" in entry["reason"] and "Scalp" not in entry["reason"]
    # A random walk suits the ear but leaks out of the open scalp.
    walk = effect_entry(scene.decide(plan, settings.replace(method="RANDOM_WALK"), with_changes(scene_facts(0.5), shapes=shapes)),
                  "subsurface method")
    assert walk["enabled"] is False and "Scalp" in walk["reason"] and "Ear" not in walk["reason"]
    # Thin and open: Burley, and the advice to close the mesh for a walk.
    thin_open = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=(
        scene.ShapeFacts("Lid", largest, False, 3),))), "subsurface method")
    assert thin_open["enabled"] and "close the mesh, then a random walk" in thin_open["reason"]


def test_no_method_advice_where_subsurface_is_off_or_in_eevee():
    plan = _constant_plan()
    shapes = (scene.ShapeFacts("Ear", 1.0, True),)
    settings = core.SkinSettings.from_preset("caucasian")
    off = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=shapes), {"subsurface": "OFF"}),
                 "subsurface method")
    assert off["enabled"] and "subsurface is off" in off["reason"]
    eevee = core.compute(settings.replace(engine="eevee"))
    entry = effect_entry(scene.decide(eevee, settings, with_changes(scene_facts(0.5), shapes=shapes)), "subsurface method")
    assert entry["enabled"] and "EEVEE" in entry["reason"] and entry["figures"]["objects"] == {}


def test_animated_constant_material_gets_the_cores_values_per_frame():
    hemoglobin = (0.005, 0.02, 0.02, 0.05)
    facts = with_changes(scene_facts(0.5), animation=animation_facts({"hemoglobin": hemoglobin}, current=3, first=10))
    settings = core.SkinSettings.from_preset("caucasian")
    plan = scene.scene_plan(settings, facts)
    assert plan.animation["frames"] == (10, 11, 12, 13)
    for index, value in enumerate(hemoglobin):
        burley = spectral_skin.evaluate(settings.melanin, settings.melanin_blend, value, settings.oiliness)
        burley = burley["methods"]["burley"]
        np.testing.assert_allclose(plan.animation["base_color"][index], burley["base_color"], rtol=1e-9)
        np.testing.assert_allclose(plan.animation["radius"][index], burley["subsurface_radius_mm"], rtol=1e-9)
    # The current frame (3, before the range) takes the first frame's values.
    np.testing.assert_allclose(plan.base_color, plan.animation["base_color"][0])
    entry = effect_entry(plan.effects, "animation")
    assert entry["enabled"] and entry["figures"]["evaluations"] == 3 and "hemoglobin keyframed" in entry["reason"]
    # The plan's work: the three distinct parameter sets, each once (the current frame's is one of them).
    assert (plan.work["radius_fits"], plan.work["specular_evaluations"]) == (9, 3)
    assert entry["figures"]["first_frame"] == 10 and entry["figures"]["last_frame"] == 13


def test_animated_decisions_hold_over_every_frame():
    settings = core.SkinSettings.from_preset("caucasian", surface="PAPER")
    radius = {v: max(spectral_skin.evaluate(settings.melanin, settings.melanin_blend, v, 0.3)["methods"]["burley"][
        "subsurface_radius_mm"]) for v in (0.001, 0.1)}
    big, small = max(radius, key=radius.get), min(radius, key=radius.get)
    # A camera where the small radius is 0.2 px and the big one above 0.25 px: subsurface stays for the animation.
    assert radius[big] / radius[small] > 0.25 / 0.2
    depth = radius[small] / 0.2 / 0.375
    facts = with_changes(scene_facts(depth + 0.1), animation=animation_facts({"hemoglobin": (small, big)}, current=1))
    assert not scene.enabled(scene.scene_plan(settings.replace(hemoglobin=small), with_changes(facts, animation=None)).effects, "subsurface")
    plan = scene.scene_plan(settings, facts)
    entry = effect_entry(plan.effects, "subsurface")
    assert entry["enabled"] and entry["figures"]["largest_radius_mm"] == pytest.approx(radius[big], rel=1e-9)
    # Oiliness zero at one frame only: the specular lobe stays, with each frame's level.
    oily = scene.scene_plan(settings, with_changes(scene_facts(0.5), animation=animation_facts({"oiliness": (0.0, 0.5)})))
    assert scene.enabled(oily.effects, "specular")
    assert oily.animation["specular_ior_level"][0] == 0.0 < oily.animation["specular_ior_level"][1]
    dry = scene.scene_plan(settings, with_changes(scene_facts(0.5), animation=animation_facts({"oiliness": (0.0, 0.0)})))
    assert not scene.enabled(dry.effects, "specular")


def test_animation_with_parameter_maps_is_reported_not_applied(tmp_path):
    maps = {"melanin": core.ParameterMap(np.linspace(0.01, 0.2, 16, dtype=np.float32).reshape(4, 4), False)}
    settings = core.SkinSettings.from_preset("caucasian", maps=maps, output_dir=str(tmp_path))
    facts = with_changes(scene_facts(0.5), animation=animation_facts({"hemoglobin": (0.005, 0.05)}, current=2))
    plan = scene.scene_plan(settings, facts)
    assert plan.animation is None
    entry = effect_entry(plan.effects, "animation")
    assert not entry["enabled"] and "per-frame maps or the live shader" in entry["reason"]
    # The maps are computed with the current frame's haemoglobin.
    expected = spectral_skin.evaluate(0.01, settings.melanin_blend, 0.05, settings.oiliness)["methods"]["burley"]
    np.testing.assert_allclose(np.asarray(plan.textures["albedo"])[0, 0], expected["base_color"], rtol=1e-4)
    # Without animation: an entry that says so.
    still = effect_entry(scene.scene_plan(core.SkinSettings(), None).effects, "animation")
    assert not still["enabled"] and "no keyframed or driven" in still["reason"]


def test_plan_textures_written_by_the_core_and_specular_constants_from_maps(tmp_path):
    """The add-on writes its textures with spectral_skin.write_maps (no writer of its own) and takes Roughness and
    IOR from maps() (no second evaluate): the files hold the plan's images, a texture the plan drops is removed."""
    melanin = np.linspace(0.01, 0.4, 16, dtype=np.float32).reshape(4, 4)
    oiliness = np.linspace(0.1, 0.9, 16, dtype=np.float32).reshape(4, 4)
    maps = {"melanin": core.ParameterMap(melanin, False), "oiliness": core.ParameterMap(oiliness, False)}
    settings = core.SkinSettings.from_preset("caucasian", surface="PAPER", maps=maps, output_dir=str(tmp_path), file_prefix="Skin")
    plan = scene.scene_plan(settings, None)
    assert sorted(plan.textures) == ["albedo", "radius", "specular"] and plan.specular_ior_level is None
    expected = spectral_skin.evaluate(preset="caucasian", outputs=("specular",), surface="paper")["specular"]
    assert plan.roughness == pytest.approx(expected["roughness"], rel=1e-12)
    assert plan.ior == pytest.approx(expected["ior"], rel=1e-12)
    core.write_textures(plan)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Skin_albedo.exr", "Skin_radius.exr", "Skin_specular.exr"]
    level = spectral_skin.read_parameter_map(tmp_path / "Skin_specular.exr", "oiliness")["oiliness"]
    # The file holds the plan's values as half floats (write_maps' default precision).
    np.testing.assert_array_equal(level, plan.textures["specular"].astype(np.float16).astype(np.float32))
    np.testing.assert_allclose(plan.textures["specular"], oiliness / 2, rtol=1e-6)  # Specular IOR Level = oil / 2
    # Specular forced off: no specular texture, and the previous one is gone.
    off = scene.scene_plan(settings, None, {"specular": "OFF"})
    core.write_textures(off)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Skin_albedo.exr", "Skin_radius.exr"]


@pytest.mark.parametrize("extended", [{}, {"epidermis_thickness_mm": 0.05, "baseline_absorption_scale": 0.3}],
                         ids=["paper", "thin-epidermis-low-baseline"])
def test_bound_grid_bounds_the_radius(extended: dict[str, float]):
    """The bound the analysis drops subsurface by before computing (scene.radius_bound_mm) is at least the radius of
    every parameter set on a denser grid, offset from the bound's, over all three fractions, per method and engine,
    for the paper's model and for a material whose extended physiology widens the radius (the bound follows the
    material). The least absorbing skin alone is no bound: a little melanin widens the random walk's radius."""
    ranges = spectral_skin.parameter_ranges()
    melanin = np.concatenate([np.linspace(0, 0.05, 6)[1:] + 0.003, np.linspace(0.05, 0.5, 9) + 0.011])
    grid = [np.clip(melanin, *ranges["melanin"]), (0.0, 0.25, 0.75, 1.0), (0.0, 0.004, 0.03, 0.1)]
    for engine in ("cycles", "eevee"):
        for method in ("BURLEY", "RANDOM_WALK", "RANDOM_WALK_SKIN"):
            settings = core.SkinSettings(method=method, engine=engine, **extended)
            bound_mm, work = scene.radius_bound_mm(settings)
            assert work["radius_fits"] == 3 * (1 + (len(scene.BOUND_MELANIN_FRACTIONS) - 1) *
                                               len(scene.BOUND_MELANIN_BLENDS))
            name = core.method_name(method)
            largest = max(float(np.max(spectral_skin.evaluate(m, b, h, 0.0, outputs=["radius"], engine=engine,
                                                              **extended)["methods"][name]["subsurface_radius_mm"]))
                          for m in grid[0] for b in grid[1] for h in grid[2])
            assert largest <= bound_mm * (1 + 1e-9), (engine, method, largest, bound_mm)
    # The case the grid is for: the least absorbing skin's radius is exceeded (by 22 % with a thin epidermis).
    if extended:
        least = spectral_skin.evaluate(0.0, 0.0, 0.0, 0.0, outputs=["radius"], **extended)["methods"]["random_walk"]
        wide = spectral_skin.evaluate(0.125, 1.0, 0.0, 0.0, outputs=["radius"], **extended)["methods"]["random_walk"]
        assert max(wide["subsurface_radius_mm"]) > 1.1 * max(least["subsurface_radius_mm"])


def test_dropped_effects_are_not_computed():
    """A far object with zero oiliness: the core's work for the material has no radius fit, no profile and no
    specular evaluation (the decisions were taken before computing); close and oily, it has them."""
    settings = core.SkinSettings.from_preset("caucasian", surface="PAPER", oiliness=0.0, method="RANDOM_WALK")
    plan = scene.scene_plan(settings, scene_facts(1e4))
    work = plan.work
    assert (work["radius_fits"], work["radial_profiles"], work["specular_evaluations"]) == (0, 0, 0), work
    assert work["transform_samples"] == work["wavelengths"] > 0  # the albedo alone: one value per wavelength
    entry = effect_entry(plan.effects, "subsurface")
    assert not entry["enabled"] and "not computed" in entry["reason"]
    assert entry["figures"]["largest_radius_bound_px"] < scene.SUBSURFACE_MIN_RADIUS_PX
    assert not scene.enabled(plan.effects, "specular") and plan.specular_ior_level == 0.0
    albedo = spectral_skin.evaluate(preset="caucasian", outputs=["albedo"])["diffuse_reflectance_rgb"]
    np.testing.assert_allclose(plan.base_color, albedo, rtol=1e-12)
    assert plan.subsurface_weight == 0.0 and plan.radius is None
    assert plan.ior == plan.subsurface_ior == spectral_skin.evaluate(preset="caucasian")["specular"]["ior"]
    close = scene.scene_plan(settings.replace(oiliness=0.3), scene_facts(0.5))
    work = close.work
    assert (work["radius_fits"], work["radial_profiles"], work["specular_evaluations"]) == (3, 0, 1), work
    # Forced off: not computed either, whatever the distance.
    forced = scene.scene_plan(settings.replace(oiliness=0.3), scene_facts(0.5), {"subsurface": "OFF", "specular": "OFF"})
    assert (forced.work["radius_fits"], forced.work["specular_evaluations"]) == (0, 0)
    assert not scene.enabled(forced.effects, "subsurface") and "forced off" in effect_entry(
        forced.effects, "subsurface")["reason"]


@pytest.mark.parametrize("method", ["BURLEY", "RANDOM_WALK"])
def test_dropped_effects_with_maps_are_not_kept(tmp_path, method):
    """With maps, effects dropped before computing are not computed: a far map-based material gets no radius fit and
    no specular input from the core (``spectral_skin.maps(outputs=["albedo"])``), keeps no radius and no specular
    texture, and its Base Color texture is the albedo whatever the method (evaluate()'s, texel by texel)."""
    levels = np.linspace(0.001, 0.05, 16, dtype=np.float32).reshape(4, 4)
    hemoglobin = core.ParameterMap(levels, False)
    settings = core.SkinSettings.from_preset("caucasian", surface="PAPER", maps={"hemoglobin": hemoglobin}, oiliness=0.0,
                                             output_dir=str(tmp_path), method=method)
    plan = scene.scene_plan(settings, scene_facts(1e4))
    assert set(plan.textures) == {"albedo"} and plan.radius is None
    work = plan.work
    assert work["texels"] == 16 and work["evaluations"] == 16
    assert work["radius_fits"] == 0 and work["specular_evaluations"] == 0, work
    assert work["outputs"] == {"albedo": 16, "radius": 0, "specular": 0}, work
    assert plan.specular_ior_level == 0.0 and plan.roughness > 0.0
    c = settings.constants()
    # A map run holds every parameter as float32, the constants too: evaluate() gets the same float32 values.
    as_map = [float(np.float32(v)) for v in (c["melanin"], c["melanin_blend"], levels.flat[5])]
    albedo = spectral_skin.evaluate(*as_map, 0.0, outputs=("albedo",))["diffuse_reflectance_rgb"]
    np.testing.assert_array_equal(np.asarray(plan.textures["albedo"]).reshape(-1, 3)[5], np.float32(albedo))


def test_thin_parts_of_a_thick_object_by_area():
    """Per-part thickness decides over the bounding box: 5 % of the area at 2 mm in a 160 mm thick object is thin
    (a random walk, the reason naming the parts); 0.5 % is not (under THIN_AREA_FRACTION); no samples: the bounds."""
    plan = _constant_plan()
    largest = max(plan.radius)
    settings = core.SkinSettings.from_preset("caucasian")

    def head(thin_area: float) -> scene.ShapeFacts:
        parts = ((2.0, thin_area, (0.1, 0.0, 0.0)), (160.0, 100.0 - thin_area, (0.0, 0.0, 0.08)))
        return scene.ShapeFacts("Head", 160.0, True, parts=parts, sampled_faces=2)

    entry = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=(head(5.0),))), "subsurface method")
    figures = entry["figures"]["objects"]["Head"]
    assert figures["recommended"] == "RANDOM_WALK" and not entry["enabled"]
    assert figures["parts"]["thin_area_fraction"] == pytest.approx(0.05)
    assert figures["parts"]["thin_median_mm"] == 2.0 and figures["parts"]["thin_centre"] == (0.1, 0.0, 0.0)
    assert "5 % of its surface" in figures["reason"] and "2 mm thick" in figures["reason"]
    assert "(0.1, 0, 0)" in figures["reason"]
    entry = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=(head(0.5),))), "subsurface method")
    assert entry["enabled"] and entry["figures"]["objects"]["Head"]["recommended"] is None
    # The fallback: without samples, the bounds' 2 mm make the object thin.
    bounds = scene.ShapeFacts("Plate", 2.0, True)
    entry = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(0.5), shapes=(bounds,))), "subsurface method")
    assert entry["figures"]["objects"]["Plate"]["recommended"] == "RANDOM_WALK"
    assert entry["figures"]["objects"]["Plate"]["parts"] is None
    assert 2.0 < scene.THIN_RADII * largest


def test_dropped_after_computing_the_radius_costs_one_evaluation():
    """A material whose own radius is under the threshold while the bound on every skin's is not: the radius is
    computed (three fits) and then dropped; a random walk's Base Color becomes the albedo that came with that one
    evaluation (no second one)."""
    settings = core.SkinSettings.from_preset("african", method="RANDOM_WALK")
    own_mm = max(core.compute(settings).extent_radius_mm)  # compared as Burley's radius, whatever the method
    bound_mm, _work = scene.radius_bound_mm(settings)
    depth = own_mm / 0.2 / 0.375  # the material's largest extent at 0.2 px
    assert bound_mm / own_mm > scene.SUBSURFACE_MIN_RADIUS_PX / 0.2  # the bound alone does not drop it
    plan = scene.scene_plan(settings, scene_facts(depth + 0.1))
    assert plan.subsurface_weight == 0.0
    assert "not computed" not in effect_entry(plan.effects, "subsurface")["reason"]
    assert plan.work["radius_fits"] == 3
    albedo = spectral_skin.evaluate(preset="african", outputs=["albedo"])["diffuse_reflectance_rgb"]
    np.testing.assert_allclose(plan.base_color, albedo, rtol=1e-12)


def test_thin_parts_keep_subsurface_however_far():
    """Far away a thick object drops subsurface; one with thin parts (by the part-by-part measure or, without
    samples, its bounds) keeps it, the reason naming the object, and the radius is computed (no early drop)."""
    plan = _constant_plan()
    largest = max(plan.radius)
    settings = core.SkinSettings.from_preset("caucasian")
    parts = ((2.0, 5.0, (0.1, 0.0, 0.0)), (160.0, 95.0, (0.0, 0.0, 0.08)))
    thick = scene.ShapeFacts("Ball", 160.0, True, parts=((160.0, 1.0, (0.0, 0.0, 0.0)),), sampled_faces=1)
    for shapes, kept in (((thick,), False), ((thick, scene.ShapeFacts("Head", 160.0, True, parts=parts,
                                                                       sampled_faces=2)), True),
                         ((scene.ShapeFacts("Plate", 0.5 * largest, True),), True)):
        entry = effect_entry(scene.decide(plan, settings, with_changes(scene_facts(1e4), shapes=shapes)), "subsurface")
        assert entry["figures"]["largest_radius_px"] < scene.SUBSURFACE_MIN_RADIUS_PX
        assert entry["enabled"] is kept, entry["reason"]
        if kept:
            assert list(entry["figures"]["thin_objects"]) == [shapes[-1].object_name]
            assert shapes[-1].object_name in entry["reason"] and "thinner than 3 radii" in entry["reason"]
        planned = scene.scene_plan(settings, with_changes(scene_facts(1e4), shapes=shapes))
        assert (planned.work["radius_fits"] > 0) is kept, planned.work
        assert scene.enabled(planned.effects, "subsurface") is kept


@pytest.mark.parametrize("preset", ["caucasian", "asian", "african"])
def test_every_method_decides_alike_on_the_same_scene(preset):
    """The decision compares the same physical extent whatever the method (the skin's Burley radius, which the
    threshold was measured with), so Burley and the random walks keep or drop subsurface alike at every distance;
    among the distances is one where a random walk's own radius (a mean free path in 5.2+, issue 21: 0.223 px against
    Burley's 1.72 px) is under the threshold while Burley's is well over it."""
    settings = core.SkinSettings.from_preset(preset)
    ev = spectral_skin.evaluate(preset=preset, outputs=["radius"], blender=settings.blender)
    burley = max(ev["methods"]["burley"]["subsurface_radius_mm"])
    walk = max(ev["methods"]["random_walk"]["subsurface_radius_mm"])
    # The caucasian skin's Burley radius at 1.5 px: the random walk's own radius is under 0.25 px there (5.2+),
    # where comparing a method's own radius dropped subsurface for the random walk only.
    if preset == "caucasian" and ev["target"]["blender"] >= "5.2":
        assert walk / (burley / 1.5) < scene.SUBSURFACE_MIN_RADIUS_PX
    for radius_px in (0.1, 0.2, 0.3, 1.5, 5.0):
        depth = burley / radius_px / 0.375
        decided = {}
        for method in ("BURLEY", "RANDOM_WALK", "RANDOM_WALK_SKIN"):
            plan = scene.scene_plan(settings.replace(method=method), scene_facts(depth + 0.1))
            decided[method] = plan.subsurface_weight == 1.0
        assert len(set(decided.values())) == 1, (preset, radius_px, decided)
        assert decided["BURLEY"] == (radius_px * depth / (depth + 0.1) >= scene.SUBSURFACE_MIN_RADIUS_PX), radius_px


def test_the_plan_is_read_only(tmp_path):
    """Issue 23: operators, batch, panels and node glue only read the plan: its fields cannot be set, its mappings
    cannot be changed and its texels cannot be written."""
    import dataclasses

    maps = {"melanin": core.ParameterMap(np.linspace(0.01, 0.2, 16, dtype=np.float32).reshape(4, 4), False)}
    plan = scene.scene_plan(core.SkinSettings.from_preset("caucasian", maps=maps, output_dir=str(tmp_path)), None)
    assert sorted(plan.textures) == ["albedo", "radius"], sorted(plan.textures)
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.roughness = 0.1  # type: ignore[misc]
    with pytest.raises(TypeError):
        plan.textures["albedo"] = "elsewhere.exr"  # type: ignore[index]
    with pytest.raises(TypeError):
        plan.target["blender"] = "4.2"  # type: ignore[index]
    for name, image in plan.textures.items():
        assert not image.flags.writeable, name
        with pytest.raises(ValueError):
            image[0, 0] = 0.0
    assert isinstance(plan.effects, tuple), type(plan.effects)
