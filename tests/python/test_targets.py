"""The Blender target through the bindings: blender=/engine= on evaluate and maps, blender_targets(), and errors."""

import numpy as np
import pytest
import spectral_skin


def test_default_target_is_current_release_cycles():
    ev = spectral_skin.evaluate(preset="caucasian")
    targets = spectral_skin.blender_targets()
    assert ev["target"] == {"blender": targets["current_release"], "engine": "cycles", "tested": True}
    assert ev["target"] == targets["default"]
    assert list(ev["methods"]) == [m["name"] for m in targets["versions"][-1]["methods"]]


@pytest.mark.parametrize("blender", ["5.2", (5, 2), (5, 2, 3)])
def test_version_spellings(blender):
    ev = spectral_skin.evaluate(preset="asian", blender=blender, engine="eevee")
    assert ev["target"] == {"blender": "5.2", "engine": "eevee", "tested": True}
    assert set(ev["methods"]) == {"burley", "random_walk", "random_walk_legacy", "random_walk_skin"}


def test_untested_newer_version_and_methods_per_version():
    assert spectral_skin.evaluate(preset="asian", blender="5.9")["target"]["tested"] is False
    # The reason comes with the result, in the core's words (4.2's EEVEE was told it was "newer than tested").
    newer = spectral_skin.evaluate(preset="asian", blender="5.9")["target"]["untested_reason"]
    assert newer.startswith("Blender 5.9 is newer than the versions")
    old_eevee = spectral_skin.evaluate(preset="asian", blender="4.2", engine="eevee")["target"]
    assert old_eevee["tested"] is False and "newer" not in old_eevee["untested_reason"]
    assert old_eevee["untested_reason"].startswith("EEVEE in Blender 4.2 was not validated")
    assert "untested_reason" not in spectral_skin.evaluate(preset="asian", blender="5.3")["target"]
    assert "random_walk_legacy" not in spectral_skin.evaluate(preset="asian", blender="4.5")["methods"]


def test_eevee_radius_is_the_cycles_radius_times_s_of_normalised_albedo():
    cycles = spectral_skin.evaluate(preset="african", blender="4.5")
    eevee = spectral_skin.evaluate(preset="african", blender="4.5", engine="eevee")
    albedo = cycles["diffuse_reflectance_rgb"]
    a_n = albedo / albedo.max()
    s = 1.9 - a_n + 3.5 * (a_n - 0.8) ** 2  # Christensen-Burley 2015, eq. 6, by hand
    np.testing.assert_allclose(eevee["methods"]["random_walk"]["subsurface_radius_mm"],
                               cycles["methods"]["burley"]["subsurface_radius_mm"] * s, rtol=1e-12)


def test_blender_targets_describes_the_table():
    t = spectral_skin.blender_targets()
    assert t["oldest_supported"] == "4.2"
    assert t["tested_versions"] == ["4.2", "4.5", "5.0", "5.2", "5.3"]
    assert [e["name"] for e in t["engines"]] == ["cycles", "eevee"]
    ids = {v["version"]: v["engine_ids"]["eevee"] for v in t["versions"]}
    assert ids["4.2"] == "BLENDER_EEVEE_NEXT" and ids["5.0"] == "BLENDER_EEVEE"
    assert {m["name"]: m["blender_id"] for m in t["methods"]}["random_walk_legacy"] == "RANDOM_WALK_LEGACY"


def test_maps_for_a_target_equal_evaluate():
    params = np.zeros((2, 2, 4), np.float32)
    params[..., 0], params[..., 1], params[..., 2], params[..., 3] = 0.1, 0.5, 0.02, 0.3
    params[0, 0, 0] = 0.2
    for blender, engine, method in [("5.3", "cycles", "random_walk"), ("5.2", "eevee", "burley"),
                                    ("5.2", "cycles", "random_walk_legacy")]:
        result = spectral_skin.maps(params, method=method, blender=blender, engine=engine, exact=True)
        assert result["report"]["target"] == {"blender": blender, "engine": engine, "tested": True}
        ev = spectral_skin.evaluate(0.2, 0.5, 0.02, 0.3, blender=blender, engine=engine)["methods"][method]
        np.testing.assert_allclose(result["albedo"][0, 0], ev["base_color"], rtol=1e-6)
        np.testing.assert_allclose(result["radius"][0, 0], ev["subsurface_radius_mm"], rtol=1e-6)


@pytest.mark.parametrize("call, needles", [
    (lambda: spectral_skin.evaluate(preset="asian", blender="4.1"), ["4.1", "4.2 and newer"]),
    (lambda: spectral_skin.evaluate(preset="asian", blender=(3, 6)), ["3.6", "4.2 and newer"]),
    (lambda: spectral_skin.evaluate(preset="asian", blender="latest"), ["MAJOR.MINOR", "latest"]),
    (lambda: spectral_skin.evaluate(preset="asian", engine="workbench"), ["engine", "cycles, eevee", "workbench"]),
    (lambda: spectral_skin.maps(np.zeros((2, 2, 4), np.float32), method="random_walk_legacy", blender="5.0"),
     ["random_walk_legacy", "not offered by Blender 5.0"]),
])
def test_bad_targets_are_clear_errors(call, needles):
    with pytest.raises(spectral_skin.SpectralSkinError) as info:
        call()
    for needle in needles:
        assert needle in str(info.value)


def test_bad_version_type_is_a_type_error():
    with pytest.raises(TypeError, match="blender must be"):
        spectral_skin.evaluate(preset="asian", blender=5.3)
