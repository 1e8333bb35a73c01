"""spectral_skin.fit_spectra: many spectra with one fitter, in parallel; each fit as fit_spectrum gives it, bad rows
named before any fit, progress told and able to cancel."""

from __future__ import annotations

import numpy as np
import pytest
import spectral_skin

SKINS = [(0.02, 0.6, 0.01), (0.06, 0.3, 0.02), (0.15, 0.8, 0.03)]
OPTIONS = {"free": ["melanin", "melanin_blend", "hemoglobin"], "bandpass": 0, "specular": 0.0,
           "fixed": {"epidermis_thickness_mm": 0.25, "baseline_absorption_scale": 1.0}}


def _spectra() -> tuple[np.ndarray, np.ndarray]:
    rows = []
    for melanin, blend, hemoglobin in SKINS:
        ev = spectral_skin.evaluate(melanin, blend, hemoglobin, 0.3, outputs=["spectrum"], wavelength_step_nm=10.0,
                                    wavelength_placement="uniform")
        keep = (ev["wavelengths_nm"] >= 400) & (ev["wavelengths_nm"] <= 700)
        rows.append(ev["spectral_reflectance"][keep])
    return ev["wavelengths_nm"][keep], np.array(rows)


def test_each_fit_is_fit_spectrums() -> None:
    """The batch gives, row by row, what fit_spectrum gives for that row (the same fitter's table and refinement),
    and each recovers the skin it was made from."""
    wavelengths, spectra = _spectra()
    fits = spectral_skin.fit_spectra(wavelengths, spectra, **OPTIONS)
    assert isinstance(fits, list) and len(fits) == len(SKINS)
    for fit, row, skin in zip(fits, spectra, SKINS, strict=True):
        alone = spectral_skin.fit_spectrum(wavelengths, row, **OPTIONS)
        assert fit["params"] == alone["params"] and fit["rms"] == alone["rms"]
        got = (fit["params"]["melanin"], fit["params"]["melanin_blend"], fit["params"]["hemoglobin"])
        assert got == pytest.approx(skin, rel=0.01, abs=1e-3)
    as_lists = spectral_skin.fit_spectra(list(wavelengths), [list(r) for r in spectra], **OPTIONS)
    assert [f["params"] for f in as_lists] == [f["params"] for f in fits]


def test_progress_counts_the_spectra_and_can_cancel() -> None:
    wavelengths, spectra = _spectra()
    calls: list[tuple[int, int]] = []
    spectral_skin.fit_spectra(wavelengths, spectra, progress=lambda done, total: calls.append((done, total)), **OPTIONS)
    assert calls[0] == (0, 3) and calls[-1] == (3, 3)
    assert [done for done, _ in calls] == sorted(done for done, _ in calls)
    with pytest.raises(InterruptedError, match="fit_spectra"):
        spectral_skin.fit_spectra(wavelengths, spectra, progress=lambda done, total: False, **OPTIONS)

    def boom(done: int, total: int) -> None:
        raise ValueError("stop here")

    with pytest.raises(ValueError, match="stop here"):
        spectral_skin.fit_spectra(wavelengths, spectra, progress=boom, **OPTIONS)


def test_bad_rows_are_named_before_any_fit() -> None:
    wavelengths, spectra = _spectra()
    bad = spectra.copy()
    bad[1, 4] = 1.5
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"reflectances\[1\].*value 4"):
        spectral_skin.fit_spectra(wavelengths, bad)
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"reflectances\[2\].*values for 31 wavelengths"):
        spectral_skin.fit_spectra(wavelengths, [list(spectra[0]), list(spectra[1]), [0.1, 0.2]])
    with pytest.raises(spectral_skin.SpectralSkinError, match="1 to 100000 spectra"):
        spectral_skin.fit_spectra(wavelengths, np.empty((0, 31)))
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"reflectances.*shape \(31,\)"):
        spectral_skin.fit_spectra(wavelengths, spectra[0])
    # A broadcast view of 10^9 rows is refused from its shape, before anything is copied.
    huge = np.broadcast_to(spectra[0], (10**9, 31))
    with pytest.raises(spectral_skin.SpectralSkinError, match="reflectances"):
        spectral_skin.fit_spectra(wavelengths, huge)
    with pytest.raises(TypeError, match="reflectances"):
        spectral_skin.fit_spectra(wavelengths, "0.1, 0.2")
    with pytest.raises(TypeError, match="reflectances"):
        spectral_skin.fit_spectra(wavelengths, spectra.astype(bool))
    with pytest.raises(TypeError, match="progress"):
        spectral_skin.fit_spectra(wavelengths, spectra, progress=3)  # type: ignore[arg-type]
