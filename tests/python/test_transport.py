"""Issue 20: the transport (how each wavelength's total diffuse reflectance is computed) is a choice of every Python
front: ``transport=`` (the core's names, from :func:`spectral_skin.transports`) and ``streams=``, reported in every
result, part of every table cache key; bad values are errors naming the input and the allowed values."""

import inspect

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

TRANSPORTS = [t["name"] for t in spectral_skin.transports()]
DEFAULT = next(t["name"] for t in spectral_skin.transports() if t["default"])
LAYERS = [(0.25, 0.3, 6.0, 1.4), (float("inf"), 0.2, 3.0, 1.4)]
# Every function that computes the model.
FRONTS = ("evaluate", "profile", "maps", "shader_table", "layered_reflectance", "fit_spectrum", "fit_albedo",
          "fit_albedo_map")


def test_catalog():
    catalog = spectral_skin.transports()
    assert TRANSPORTS == ["adding_doubling", "adding_doubling_diffusion_shape", "diffusion"]
    assert [t["default"] for t in catalog] == [True, False, False], "exactly one default, listed first"
    assert all(isinstance(t["description"], str) and t["description"] for t in catalog)


@pytest.mark.parametrize("name", FRONTS)
def test_every_front_takes_transport_and_streams_with_the_core_default(name):
    parameters = inspect.signature(getattr(spectral_skin, name)).parameters
    assert parameters["transport"].default == DEFAULT
    assert parameters["transport"].kind is inspect.Parameter.KEYWORD_ONLY
    assert parameters["streams"].default is None


def test_evaluate_reports_the_transport_and_streams():
    default = spectral_skin.evaluate(preset="african")
    assert default["transport"] == DEFAULT
    assert default["accuracy"]["streams"] == spectral_skin.evaluate(preset="african", accuracy="default")["accuracy"][
        "streams"]
    assert default["work"]["transport_table_lookups"] == default["work"]["wavelengths"]
    assert default["work"]["transport_solves"] == 0  # the shipped table holds every skin total
    solved = spectral_skin.evaluate(preset="african", streams=16)
    assert solved["work"]["transport_solves"] == solved["work"]["wavelengths"]  # streams given: solved at them
    assert solved["accuracy"]["exact_totals"] == "solve" and default["accuracy"]["exact_totals"] == "table"
    diffusion = spectral_skin.evaluate(preset="african", transport="diffusion", streams=16)
    assert diffusion["transport"] == "diffusion" and diffusion["accuracy"]["streams"] == 16
    assert diffusion["work"]["transport_solves"] == 0
    levels = {a: spectral_skin.evaluate(preset="african", accuracy=a, outputs=["albedo"])["accuracy"]["streams"]
              for a in ("draft", "default", "reference")}
    assert levels["draft"] < levels["default"] < levels["reference"]


def test_diffusion_shape_is_the_multipole_scaled_to_the_total():
    """Per wavelength: the diffusion-shape transport's profile is the diffusion profile times (exact total / diffusion
    total); the default's has the exact shape (tests/physics/exact_profile.rs) and the same total."""
    kwargs = {"preset": "african", "profile_count": 9}
    spectra = {t: spectral_skin.evaluate(outputs=["spectrum"], transport=t, preset="african")["spectral_reflectance"]
               for t in TRANSPORTS}
    profiles = {t: spectral_skin.profile(spectral=True, transport=t, **kwargs)["spectral_per_mm2"] for t in TRANSPORTS}
    scale = spectra["adding_doubling_diffusion_shape"] / spectra["diffusion"]
    np.testing.assert_allclose(profiles["adding_doubling_diffusion_shape"], profiles["diffusion"] * scale[:, None],
                               rtol=1e-14, atol=0)
    np.testing.assert_array_equal(spectra["adding_doubling"], spectra["adding_doubling_diffusion_shape"])
    assert not np.allclose(profiles["adding_doubling"], profiles["adding_doubling_diffusion_shape"], rtol=0.05)
    rgb = {t: spectral_skin.profile(transport=t, **kwargs)["rgb_per_mm2"] for t in TRANSPORTS}
    assert rgb["adding_doubling"].shape == rgb["diffusion"].shape == (9, 3)


def test_layered_reflectance_takes_the_transport():
    radii = [0.0, 0.5, 2.0]
    exact, exact_profile = spectral_skin.layered_reflectance(LAYERS, radii)
    assert (exact, list(exact_profile)) == (lambda r: (r[0], list(r[1])))(
        spectral_skin.layered_reflectance(LAYERS, radii, transport="adding_doubling"))
    multipole, multipole_profile = spectral_skin.layered_reflectance(LAYERS, radii, transport="diffusion")
    scaled, scaled_profile = spectral_skin.layered_reflectance(LAYERS, radii, transport="adding_doubling_diffusion_shape")
    assert scaled == exact
    np.testing.assert_allclose(scaled_profile, multipole_profile * (exact / multipole), rtol=1e-14, atol=0)
    assert 0 < exact < 1 and 0 < multipole < 1
    assert spectral_skin.layered_reflectance(LAYERS, radii, streams=16)[0] > 0
    # The exact transport needs one index for every layer; an index step is refused, pointing at diffusion.
    steps = [(0.25, 0.3, 6.0, 1.4), (float("inf"), 0.2, 3.0, 1.3)]
    with pytest.raises(SpectralSkinError, match=r"layer 1.*index of refraction.*diffusion"):
        spectral_skin.layered_reflectance(steps, radii)
    assert 0 < spectral_skin.layered_reflectance(steps, radii, transport="diffusion")[0] < 1


def test_maps_and_shader_table_name_the_transport_and_cache_one_table_each(tmp_path, monkeypatch):
    monkeypatch.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path))
    rng = np.random.default_rng(20)
    params = np.stack([rng.uniform(0, 0.05, (48, 48)), rng.uniform(0, 1, (48, 48)), rng.uniform(0, 0.05, (48, 48)),
                       np.zeros((48, 48))], axis=-1).astype(np.float32)
    small = (3, 3, 3)
    runs = [("adding_doubling", None), ("diffusion", None), ("adding_doubling", 16)]
    for count, (transport, streams) in enumerate(runs, start=1):
        result = spectral_skin.maps(params, table_resolution=small, transport=transport, streams=streams)
        request = result["report"]["request"]
        assert request["transport"] == transport
        assert request["accuracy"]["streams"] == (streams or spectral_skin.evaluate(preset="asian")["accuracy"]["streams"])
        assert result["report"]["strategy"]["from_cache"] is False, f"{transport} {streams} took another's table"
        assert len(list(tmp_path.iterdir())) == count
    again = spectral_skin.maps(params, table_resolution=small, transport="diffusion")
    assert again["report"]["strategy"]["from_cache"] is True
    for transport in TRANSPORTS:
        table = spectral_skin.shader_table(resolution=(2, 2, 2), transport=transport, streams=4)
        assert table["metadata"]["request"]["transport"] == transport
        assert table["metadata"]["request"]["accuracy"]["streams"] == 4


def test_fits_report_their_transport():
    wavelengths = np.arange(400.0, 701.0, 25.0)
    truth = spectral_skin.evaluate(preset="asian", outputs=["spectrum"], wavelength_placement="uniform",
                                   wavelength_step_nm=1.0, transport="diffusion")
    reflectance = np.interp(wavelengths, truth["wavelengths_nm"], truth["spectral_reflectance"])
    for transport in TRANSPORTS:
        fit = spectral_skin.fit_spectrum(wavelengths, reflectance, transport=transport, starts=1)
        assert fit["transport"] == transport and fit["streams"] > 0
    rgb = spectral_skin.evaluate(preset="asian", outputs=["albedo"])["diffuse_reflectance_rgb"]
    fit = spectral_skin.fit_albedo(rgb)
    assert fit["transport"] == DEFAULT and fit["delta_e00"] < 0.5
    fitted = spectral_skin.fit_albedo_map(np.tile(np.asarray(rgb, np.float32), (2, 2, 1)))
    assert fitted.stats["options"]["transport"] == DEFAULT
    assert fitted.stats["options"]["streams"] == fit["streams"]


@pytest.mark.parametrize("call", [
    lambda **k: spectral_skin.evaluate(preset="asian", **k),
    lambda **k: spectral_skin.profile(preset="asian", **k),
    lambda **k: spectral_skin.layered_reflectance(LAYERS, [1.0], **k),
    lambda **k: spectral_skin.maps(np.zeros((1, 1, 4), np.float32), **k),
    lambda **k: spectral_skin.shader_table(resolution=(2, 2, 2), **k),
    lambda **k: spectral_skin.fit_spectrum([400.0, 450.0, 500.0, 550.0, 600.0, 650.0],
                                           [0.2, 0.25, 0.3, 0.35, 0.4, 0.45], **k),
    lambda **k: spectral_skin.fit_albedo([0.3, 0.2, 0.1], **k),
    lambda **k: spectral_skin.fit_albedo_map(np.full((1, 1, 3), 0.2, np.float32), **k),
])
def test_bad_transport_and_streams_are_clear_errors(call):
    with pytest.raises(SpectralSkinError, match=r'transport.*"adding_doubling", "adding_doubling_diffusion_shape", "diffusion"'):
        call(transport="monte_carlo")
    # 2 streams are refused too: 12-47 % off at every index above 1 (tests/physics/transport_limits.rs).
    for bad in (0, 1, 2, 7, 65, -1, 2**40):
        with pytest.raises(SpectralSkinError, match=r"streams.*\[4, 64\]"):
            call(streams=bad)
    with pytest.raises(TypeError, match="streams"):
        call(streams="8")
    with pytest.raises(TypeError, match="streams"):
        call(streams=8.5)
