"""The surface model in texture maps (``maps(surface=...)``): under ``measured`` a varying oiliness gives Coat Weight
and Coat Roughness maps beside the Specular IOR Level, each texel what ``evaluate`` gives for its oiliness; a constant
oiliness gives constants only; ``paper`` keeps the one-lobe maps; the files are written, read back with OpenImageIO
(an independent EXR reader), and a later write without a Coat removes the stale Coat files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import spectral_skin

SURFACE_MAPS = ("specular", "coat_weight", "coat_roughness")


def oily_params(height: int = 4, width: int = 6) -> np.ndarray:
    """Constant physiology (one evaluation) and an oiliness ramp over [0, 1], corners included."""
    oiliness = np.linspace(0.0, 1.0, height * width, dtype=np.float32).reshape(height, width)
    planes = [np.full_like(oiliness, v) for v in (0.1, 0.5, 0.05)] + [oiliness]
    return np.stack(planes, axis=-1)


@pytest.mark.parametrize("engine", ["cycles", "eevee"])
def test_measured_maps_hold_each_texels_inputs(engine: str) -> None:
    params = oily_params()
    result = spectral_skin.maps(params, outputs=["specular"], surface="measured", engine=engine)
    assert list(result.keys()) == [*SURFACE_MAPS, "specular_constants", "report"]
    assert result.report["request"]["surface"] == "measured"
    for texel, oiliness in enumerate(params[..., 3].ravel()):
        expected = spectral_skin.evaluate(0.1, 0.5, 0.05, float(oiliness), outputs=["specular"],
                                          surface="measured", engine=engine)["specular"]
        y, x = divmod(texel, params.shape[1])
        for name, key in (("specular", "specular_ior_level"), ("coat_weight", "coat_weight"),
                          ("coat_roughness", "coat_roughness")):
            assert result[name][y, x] == pytest.approx(expected[key], rel=1e-6), (name, oiliness)
    # Oil sharpens the Coat and weights it up; the dielectric's reflection is kept by the level.
    weight, roughness = result.coat_weight, result.coat_roughness
    assert weight is not None and roughness is not None
    assert weight[-1, -1] > weight[0, 0] and roughness[-1, -1] < roughness[0, 0]
    constants = result.specular_constants
    assert constants is not None and constants["surface"] == "measured"
    assert set(constants) == {"surface", "roughness", "ior", "coat_ior", "beckmann_m"}
    assert (constants["ior"], constants["coat_ior"]) == (pytest.approx(1.4), pytest.approx(1.4))


def test_constant_oiliness_gives_constants_only() -> None:
    params = oily_params()
    params[..., 3] = 0.0
    result = spectral_skin.maps(params, outputs=["specular"], surface="measured")
    assert [getattr(result, name) for name in SURFACE_MAPS] == [None, None, None]
    constants = dict(result.specular_constants or {})
    expected = spectral_skin.evaluate(0.1, 0.5, 0.05, 0.0, outputs=["specular"], surface="measured")["specular"]
    for key in ("specular_ior_level", "coat_weight", "coat_roughness", "roughness", "coat_ior"):
        assert constants[key] == pytest.approx(expected[key]), key
    # Dry skin still reflects: the Coat and the level are on (the paper's surface has no reflection at zero oil).
    assert constants["coat_weight"] > 0.1 and constants["specular_ior_level"] > 0.4
    assert result.report["work"]["specular_evaluations"] == 1


def test_paper_maps_have_no_coat() -> None:
    result = spectral_skin.maps(oily_params(), outputs=["specular"], surface="paper")
    assert list(result.keys()) == ["specular", "specular_constants", "report"]
    specular = result.specular
    assert specular is not None
    np.testing.assert_allclose(specular, 0.5 * oily_params()[..., 3], rtol=1e-6)
    constants = result.specular_constants
    assert constants is not None and constants["surface"] == "paper" and constants.get("coat_weight") == 0.0


def test_coat_files_are_written_and_removed_when_stale(tmp_path: Path) -> None:
    oiio = pytest.importorskip("OpenImageIO")
    measured = spectral_skin.maps(oily_params(), outputs=["specular"], surface="measured")
    written = measured.write(tmp_path, "Skin", precision="float")
    assert written == {name: tmp_path / f"Skin_{name}.exr" for name in SURFACE_MAPS}
    for name in SURFACE_MAPS:
        image = oiio.ImageInput.open(str(written[name]))
        assert image is not None, oiio.geterror()
        assert tuple(image.spec().channelnames) == ("Y",), name
        pixels = np.asarray(image.read_image(oiio.FLOAT)).reshape(measured[name].shape)
        image.close()
        np.testing.assert_array_equal(pixels, measured[name], err_msg=name)
    # write_maps reads the Coat maps from a plain mapping too.
    again = spectral_skin.write_maps(dict(measured), tmp_path / "dict", "Skin", precision="float")
    assert sorted(again) == sorted(SURFACE_MAPS)
    # The paper's maps of the same prefix: the Coat files of the earlier write are gone.
    spectral_skin.maps(oily_params(), outputs=["specular"], surface="paper").write(tmp_path, "Skin")
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_file()) == ["Skin_specular.exr"]


def test_an_unknown_surface_is_refused_naming_the_choices() -> None:
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"surface.*measured.*paper|surface.*paper.*measured"):
        spectral_skin.maps(oily_params(), surface="glossy")
