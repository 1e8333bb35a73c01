"""fit_albedo and fit_albedo_map (src/inverse/albedo.rs): parameters -> albedo by evaluate() -> fit -> the fitted
parameters' albedo by evaluate() again, within ΔE00 0.5 of the target, measured with the independent numpy CIEDE2000
of tests/python/color_difference.py (checked against Sharma et al.'s table in test_color_difference.py)."""

from __future__ import annotations

from pathlib import Path

import color_difference
import numpy as np
import pytest
import spectral_skin

TRUTH = [(0.005, 0.7, 0.005), (0.15, 0.0, 0.01), (0.5, 0.7, 0.05), (0.05, 0.3, 0.002), (0.02, 0.9, 0.08),
         (0.3, 0.5, 0.03)]


def albedo(m: float, b: float, h: float, **extended: float) -> np.ndarray:
    result = spectral_skin.evaluate(m, b, h, 0.3, outputs=["albedo"], **extended)
    return np.asarray(result["diffuse_reflectance_rgb"])


def test_texture_round_trip_is_within_half_a_delta_e() -> None:
    texture = np.array([[albedo(*p) for p in TRUTH]], dtype=np.float32)  # (1, 6, 3)
    fit = spectral_skin.fit_albedo_map(texture, epidermis_thickness_mm=0.25)
    assert isinstance(fit, spectral_skin.AlbedoMapFit) and fit.shape == (1, 6) and fit.thickness is None
    assert fit.params.shape == (1, 6, 4) and fit.params.dtype == np.float32
    assert fit.residual_delta_e00.shape == (1, 6)
    assert fit.stats["distinct_colours"] == 6 and fit.stats["outside_skin_texels"] == 0
    back = np.array([albedo(*map(float, p[:3])) for p in fit.params[0]])
    de = color_difference.delta_e00_linear_rgb(texture[0].astype(np.float64), back)
    assert np.all(de <= 0.5), de
    np.testing.assert_allclose(fit.params[0, :, 3], 0.3)


def test_the_thickness_is_chosen_by_default_and_written_into_the_parameter_map(tmp_path: Path) -> None:
    """A texture made at 0.1 mm: the default fit chooses a thin epidermis (never worse on the texture than 0.25
    held), and its parameter EXR, read back and turned into maps, reproduces the texture."""
    texture = np.array([[albedo(*p, epidermis_thickness_mm=0.1) for p in TRUTH]], dtype=np.float32)
    fit = spectral_skin.fit_albedo_map(texture)
    with pytest.warns(spectral_skin.SpectralSkinWarning, match=r"an\s+extended value held"):
        held = spectral_skin.fit_albedo_map(texture, epidermis_thickness_mm=0.25)  # the wrong thickness, held
    assert fit.thickness is not None and fit.extended["epidermis_thickness_mm"] == fit.thickness["chosen_mm"]
    assert fit.extended["epidermis_thickness_mm"] <= 0.15, fit.thickness
    assert fit.stats["mean_delta_e00"] <= held.stats["mean_delta_e00"]
    fit.write(tmp_path / "new" / "params.exr", tmp_path / "new" / "residual.exr")
    planes = spectral_skin.read_parameter_map(tmp_path / "new" / "params.exr")
    np.testing.assert_array_equal(planes["epidermis_thickness_mm"], np.float32(fit.extended["epidermis_thickness_mm"]))
    four = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
    np.testing.assert_array_equal(np.stack([planes[p] for p in four], axis=-1), fit.params)
    out = spectral_skin.maps(**planes, outputs=["albedo"])
    de = color_difference.delta_e00_linear_rgb(texture[0].astype(np.float64), out["albedo"][0].astype(np.float64))
    assert np.all(de <= fit.residual_delta_e00[0] + 0.1), (de, fit.residual_delta_e00)


def test_single_colour_and_its_ambiguity() -> None:
    target = albedo(*TRUTH[0])
    fit = spectral_skin.fit_albedo(target)
    p = fit["params"]
    back = albedo(p["melanin"], p["melanin_blend"], p["hemoglobin"])
    assert color_difference.delta_e00_linear_rgb(target, back) <= 0.5 and fit["in_gamut"]
    a = fit["ambiguity"]
    assert a["melanin_blend"][0] <= p["melanin_blend"] <= a["melanin_blend"][1]
    assert all(m[3] <= 0.5 for m in a["members"])


def test_green_is_out_of_gamut_with_finite_parameters() -> None:
    fit = spectral_skin.fit_albedo([0.05, 0.6, 0.05])
    assert not fit["in_gamut"] and fit["delta_e00"] > 20.0
    assert all(np.isfinite(v) for v in fit["params"].values())
    texture = np.array([[[0.05, 0.6, 0.05], albedo(*TRUTH[1])]], dtype=np.float64)
    with pytest.warns(spectral_skin.SpectralSkinWarning, match="1 of 2 texels"):  # half the texture is not skin
        m = spectral_skin.fit_albedo_map(texture)
    assert np.all(np.isfinite(m.params)) and m.residual_delta_e00[0, 0] > 20.0
    assert m.residual_delta_e00[0, 1] < 0.5 and m.stats["outside_skin_texels"] == 1


def test_bad_input_names_it() -> None:
    texture = np.full((3, 4, 3), 0.3, dtype=np.float32)
    texture[2, 1, 0] = np.nan
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"\(x, y\) = \(1, 2\)"):
        spectral_skin.fit_albedo_map(texture)
    with pytest.raises(spectral_skin.SpectralSkinError, match="albedo"):
        spectral_skin.fit_albedo_map(np.zeros((2, 2, 4), dtype=np.float32))
    with pytest.raises(spectral_skin.SpectralSkinError, match="epidermis_thickness_mm"):
        spectral_skin.fit_albedo([0.3, 0.2, 0.2], epidermis_thickness_mm=2.0)
    with pytest.raises(spectral_skin.SpectralSkinError, match="rgb"):
        spectral_skin.fit_albedo([0.3, 0.2])


def test_texture_size_is_bounded_before_any_copy() -> None:
    # A (100000, 100000, 3) broadcast view costs 12 bytes; gathering its planes aborted the interpreter ("memory
    # allocation of 40000000000 bytes failed"). The size rule is the one maps() and the image reader use.
    huge = np.broadcast_to(np.full(3, 0.3, dtype=np.float32), (100_000, 100_000, 3))
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"albedo.*268435456 texels.*100000 wide x 100000 high"):
        spectral_skin.fit_albedo_map(huge)
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"params.*268435456 texels"):
        spectral_skin.maps(np.broadcast_to(np.full(4, 0.1, dtype=np.float32), (100_000, 100_000, 4)))


def test_a_lit_texture_is_diagnosed_and_auto_gains_bring_it_inside() -> None:
    """The model's own albedos seen under a warm light and brighter (R x 1.6, G x 1.2, B x 0.6): the fit warns that
    the texture is not an albedo and measures gains; ``rgb_gains="auto"`` applies them, recorded in the result, and
    the texels come back inside skin's colours; gains given by hand are applied as given; bad gains are errors."""
    lit = np.array([[albedo(*p) * np.array([1.6, 1.2, 0.6]) for p in TRUTH]], dtype=np.float32)
    with pytest.warns(spectral_skin.SpectralSkinWarning, match="does not look like an albedo"):
        plain = spectral_skin.fit_albedo_map(lit)
    assert plain.diagnosis is not None and plain.gains is not None
    gained = spectral_skin.fit_albedo_map(lit, rgb_gains="auto")
    assert gained.diagnosis is None and gained.gains is not None
    assert gained.stats["options"]["rgb_gains"] == gained.gains["rgb_gains"]
    # Gains cannot tell exposure from melanin, nor a warm light from pheomelanin: they bring the texels in, not back.
    assert gained.stats["mean_delta_e00"] < 0.5 * plain.stats["mean_delta_e00"], (gained.stats, plain.stats)
    by_hand = spectral_skin.fit_albedo_map(lit, rgb_gains=[1 / 1.6, 1 / 1.2, 1 / 0.6], epidermis_thickness_mm=0.25)
    assert by_hand.stats["max_delta_e00"] < 0.5 and by_hand.gains is None
    for bad in ([1.0, 1.0], [1.0, 0.0, 1.0], "sometimes", [1.0, np.nan, 1.0]):
        with pytest.raises(spectral_skin.SpectralSkinError, match="rgb_gains"):
            spectral_skin.fit_albedo_map(lit, rgb_gains=bad)
    with pytest.raises(spectral_skin.SpectralSkinError, match="rgb_gains"):
        spectral_skin.fit_albedo([0.3, 0.2, 0.2], rgb_gains="auto")


def test_a_skin_mask_keeps_the_background_out_of_the_choice_and_the_figures() -> None:
    """Skin (made at 0.1 mm) beside a green background: unmasked, the background makes the fit warn that this is not
    an albedo; with the mask only the skin counts: no warning, the figures are the skin's, the thickness is the
    skin's, and the background texels are still fitted (finite, in range); a mask of another shape or with NaN is an
    error."""
    skin = np.array([albedo(*p, epidermis_thickness_mm=0.1) for p in TRUTH], dtype=np.float32)
    texture = np.stack([skin, np.tile(np.float32([0.05, 0.5, 0.05]), (6, 1))])  # (2, 6, 3): row 1 is background
    mask = np.array([[True] * 6, [False] * 6])
    with pytest.warns(spectral_skin.SpectralSkinWarning, match="6 of 12 texels"):
        spectral_skin.fit_albedo_map(texture)
    fit = spectral_skin.fit_albedo_map(texture, mask=mask)
    assert fit.diagnosis is None and fit.stats["masked_out_texels"] == 6 and fit.stats["max_delta_e00"] < 0.5
    assert fit.extended["epidermis_thickness_mm"] <= 0.15, fit.thickness
    assert np.all(np.isfinite(fit.params)) and fit.residual_delta_e00[1].min() > 2.0
    np.testing.assert_array_equal(spectral_skin.fit_albedo_map(texture, mask=mask.astype(np.float32)).params,
                                  fit.params)
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"mask.*\(2, 6\); got shape \(6, 2\)"):
        spectral_skin.fit_albedo_map(texture, mask=mask.T.copy())
    with pytest.raises(spectral_skin.SpectralSkinError, match="mask.*NaN"):
        spectral_skin.fit_albedo_map(texture, mask=np.full((2, 6), np.nan))
    with pytest.raises(spectral_skin.SpectralSkinError, match="marks no texel as skin"):
        spectral_skin.fit_albedo_map(texture, mask=np.zeros((2, 6), bool))


def test_write_refuses_names_it_would_not_honour(tmp_path: Path) -> None:
    """issue 38 item 5: ``write('p.<UDIM>.exr')`` without tiles wrote a file literally so named, and a .png name got
    EXR bytes; both are errors naming the path, and nothing is written."""
    texture = np.array([[albedo(*TRUTH[0], epidermis_thickness_mm=0.25)]], dtype=np.float32)
    fit = spectral_skin.fit_albedo_map(texture, epidermis_thickness_mm=0.25)
    for name, expected in [("p.<UDIM>.exr", "names a tile set"), ("p.png", "ending in .exr")]:
        with pytest.raises(spectral_skin.SpectralSkinError, match=expected):
            fit.write(tmp_path / name)
    with pytest.raises(spectral_skin.SpectralSkinError, match="ending in .exr"):
        fit.write(tmp_path / "p.exr", tmp_path / "residual.tif")
    assert list(tmp_path.iterdir()) == []


def test_progress_reaches_the_total_and_false_cancels_with_no_result() -> None:
    """``progress(done, total)`` as for maps(): (0, total) first, never backwards, the last call (total, total), and
    the fit the same as without it; returning False (at the first call, or once texels are done) cancels with
    InterruptedError naming fit_albedo_map and returns nothing; an exception in the callback is re-raised; a
    callback that is not callable is a TypeError."""
    rows = [[albedo(*p) * s for p in TRUTH] for s in (1.0, 0.9, 0.8, 1.1)]  # 4 x 6 texels, 24 distinct colours
    texture = np.array(rows, dtype=np.float32)
    total = texture.shape[0] * texture.shape[1]
    calls: list[tuple[int, int]] = []

    def record(done: int, of: int) -> None:
        calls.append((done, of))

    fit = spectral_skin.fit_albedo_map(texture, rgb_gains="auto", progress=record)
    assert calls[0] == (0, total) and calls[-1] == (total, total), calls
    assert all(of == total for _, of in calls)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:], strict=False)), calls
    assert any(0 < done < total for done, _ in calls), calls  # it moves on the way, not only at the end
    plain = spectral_skin.fit_albedo_map(texture, rgb_gains="auto")
    np.testing.assert_array_equal(fit.params, plain.params)
    np.testing.assert_array_equal(fit.residual_delta_e00, plain.residual_delta_e00)

    for stop_after in (0, 1):
        seen: list[int] = []

        def stop(done: int, of: int, stop_after: int = stop_after, seen: list[int] = seen) -> bool:
            seen.append(done)
            return len(seen) <= stop_after

        result = None
        with pytest.raises(InterruptedError, match=r"fit_albedo_map: cancelled by the progress callback"):
            result = spectral_skin.fit_albedo_map(texture, progress=stop)
        assert result is None and len(seen) == stop_after + 1, seen

    def fail(done: int, of: int) -> None:
        raise ValueError("from the callback")

    with pytest.raises(ValueError, match="from the callback"):
        spectral_skin.fit_albedo_map(texture, progress=fail)
    with pytest.raises(TypeError, match="progress must be a callable"):
        spectral_skin.fit_albedo_map(texture, progress=3)  # type: ignore[arg-type]
