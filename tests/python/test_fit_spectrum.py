"""spectral_skin.fit_spectrum (docs/measured-skin.md): a model spectrum plus an offset is fitted back; bad input is
a clear error naming the argument."""

from __future__ import annotations

import numpy as np
import pytest
import spectral_skin

TRUTH = {"melanin": 0.04, "melanin_blend": 0.4, "hemoglobin": 0.02, "epidermis_thickness_mm": 0.08,
         "baseline_absorption_scale": 2.0}


def _model_spectrum(offset: float) -> tuple[np.ndarray, np.ndarray]:
    ev = spectral_skin.evaluate(TRUTH["melanin"], TRUTH["melanin_blend"], TRUTH["hemoglobin"], 0.3,
                                epidermis_thickness_mm=TRUTH["epidermis_thickness_mm"],
                                baseline_absorption_scale=TRUTH["baseline_absorption_scale"], outputs=["spectrum"],
                                wavelength_step_nm=10.0, wavelength_placement="uniform")
    keep = (ev["wavelengths_nm"] >= 400) & (ev["wavelengths_nm"] <= 700)
    return ev["wavelengths_nm"][keep], ev["spectral_reflectance"][keep] + offset


def test_round_trip_recovers_parameters_and_offset() -> None:
    wavelengths, measured = _model_spectrum(0.03)
    # The model's spectrum is a point sample, so it is fitted as one (bandpass 0).
    fit = spectral_skin.fit_spectrum(wavelengths, measured, bandpass=0.0)
    assert fit["rms"] < 2e-5 and fit["delta_e00"] < 0.01, fit
    assert fit["bandpass"] == "fwhm" and np.all(np.asarray(fit["bandpass_nm"]) == 0.0)
    assert fit["specular"] == "free" and abs(fit["specular_offset"] - 0.03) < 1e-3
    for name, value in TRUTH.items():
        assert fit["params"][name] == pytest.approx(value, rel=0.05), name
    assert fit["params"]["blood_oxygenation"] == 0.75 and fit["params"]["oiliness"] == 0.3
    assert fit["fitted_reflectance"].shape == wavelengths.shape
    # Fixed values and a fixed offset are taken as given.
    fixed = spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin", "hemoglobin"],
                                       fixed={"melanin_blend": 0.4, "epidermis_thickness_mm": 0.08,
                                              "baseline_absorption_scale": 2.0}, specular=0.03, bandpass=0)
    assert fixed["specular_offset"] == 0.03 and fixed["params"]["melanin_blend"] == 0.4
    assert fixed["params"]["melanin"] == pytest.approx(0.04, rel=0.01) and fixed["rms"] < 1e-4


def test_epidermal_blood_is_freed_by_name_and_returned() -> None:
    """docs/measured-skin.md, Blood in the epidermis: a model option the fit frees by name; a spectrum of skin
    without it comes back without it, and the fit reports the value it used (0, the paper's, when not freed)."""
    wavelengths, measured = _model_spectrum(0.0)
    free = [*TRUTH, "epidermal_hemoglobin"]
    fit = spectral_skin.fit_spectrum(wavelengths, measured, free=free, specular=0.0, bandpass=0)
    assert fit["free"] == free and fit["epidermal_hemoglobin"] < 5e-4 and fit["rms"] < 1e-4, fit
    assert "epidermal_hemoglobin" not in fit["params"]
    assert spectral_skin.fit_spectrum(wavelengths, measured, bandpass=0)["epidermal_hemoglobin"] == 0.0
    with pytest.raises(spectral_skin.SpectralSkinError, match="epidermal_hemoglobin"):
        spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin", "carotene"])


def test_default_bandpass_is_one_and_a_half_spacings() -> None:
    """docs/measured-skin.md, Instrument bandpass: the model is averaged over a triangle 1.5 times the 10 nm spacing
    wide; fitting a point spectrum so leaves a residual the point fit does not."""
    wavelengths, measured = _model_spectrum(0.0)
    fit = spectral_skin.fit_spectrum(wavelengths, measured)
    assert fit["bandpass"] == "spacing" and np.allclose(fit["bandpass_nm"], 15.0)
    assert fit["rms"] > 1e-4
    assert spectral_skin.fit_spectrum(wavelengths, measured, bandpass="spacing")["rms"] == fit["rms"]
    assert spectral_skin.fit_spectrum(wavelengths, measured, bandpass=15)["rms"] == pytest.approx(fit["rms"])


def test_aperture_lowers_the_red_and_is_echoed() -> None:
    """docs/measured-skin.md, Instrument aperture: a contact instrument's measured disc misses the light skin carries
    out of it, most in the red; the fit models it on request and says which discs it assumed."""
    wavelengths, measured = _model_spectrum(0.0)
    fixed = {name: value for name, value in TRUTH.items() if name != "melanin"}
    total = spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin"], fixed=fixed, specular=0.0)
    sav = spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin"], fixed=fixed, specular=0.0,
                                     aperture="cm2600d-sav")
    assert total["aperture"] is None
    assert sav["aperture"] == {"illuminated_radius_mm": 3.0, "measured_radius_mm": 1.5}
    # The exact spectrum is the total: read through the aperture it needs less melanin to match the red.
    assert sav["params"]["melanin"] < total["params"]["melanin"]
    radii = spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin"], fixed=fixed, specular=0.0,
                                       aperture="3, 1.5")
    assert radii["params"]["melanin"] == sav["params"]["melanin"]
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"aperture.*cm2600d-mav"):
        spectral_skin.fit_spectrum(wavelengths, measured, aperture="mav")
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"aperture\.illuminated_radius_mm"):
        spectral_skin.fit_spectrum(wavelengths, measured, aperture="1,2")
    with pytest.raises(spectral_skin.SpectralSkinError, match="aperture.*adding_doubling"):
        spectral_skin.fit_spectrum(wavelengths, measured, aperture="cm2600d-mav", transport="diffusion")


def test_bad_input_names_the_argument() -> None:
    wavelengths, measured = _model_spectrum(0.0)
    bad = measured.copy()
    bad[3] = np.nan
    with pytest.raises(spectral_skin.SpectralSkinError, match="reflectance.*value 3 is NaN"):
        spectral_skin.fit_spectrum(wavelengths, bad)
    with pytest.raises(spectral_skin.SpectralSkinError, match="30 values for 31 wavelengths"):
        spectral_skin.fit_spectrum(wavelengths, measured[:30])
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"wavelengths_nm.*\[380, 780\]"):
        spectral_skin.fit_spectrum(wavelengths + 100.0, measured)
    with pytest.raises(spectral_skin.SpectralSkinError, match="oiliness cannot be fitted"):
        spectral_skin.fit_spectrum(wavelengths, measured, free=["melanin", "oiliness"])
    with pytest.raises(spectral_skin.SpectralSkinError, match="specular"):
        spectral_skin.fit_spectrum(wavelengths, measured, specular="glossy")
    with pytest.raises(spectral_skin.SpectralSkinError, match="bandpass.*wide"):
        spectral_skin.fit_spectrum(wavelengths, measured, bandpass="wide")
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"bandpass.*\[0, 20\].*25"):
        spectral_skin.fit_spectrum(wavelengths, measured, bandpass=25.0)
    with pytest.raises(TypeError, match="free"):
        spectral_skin.fit_spectrum(wavelengths, measured, free="melanin")


def test_starts_beyond_its_bound_or_64_bits_name_the_range() -> None:
    """issue 38 item 5: ``starts=10**12`` was accepted (no answer in minutes at 64 streams) and ``starts=2**64`` said
    "starts must be an integer; got int"."""
    wavelengths = np.linspace(400.0, 700.0, 31)
    measured = np.linspace(0.2, 0.5, 31)
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"starts.*1 to 64.*got 1000000000000"):
        spectral_skin.fit_spectrum(wavelengths, measured, starts=10**12)
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"starts.*integer in \[.*got 18446744073709551616"):
        spectral_skin.fit_spectrum(wavelengths, measured, starts=2**64)
