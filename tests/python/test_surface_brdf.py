"""spectral_skin.surface_brdf / surface_albedo: the skin surface's reflection (docs/model.md, "Surface reflection:
measured two-lobe model") against a numpy transcription of the equations written here (Beckmann D, Smith G1 for
Beckmann in its erf form, Fresnel's equations for unpolarised light at index 1.4, the lobe table), against a direct
quadrature of the BRDF over the hemisphere, and for the model's promises: dry skin reflects about F0 = 0.028 under
"measured", nothing under "paper"; broadcasting; bad input refused naming the argument."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

ETA = 1.4
F0 = ((ETA - 1.0) / (ETA + 1.0)) ** 2
OILINESS = (0.0, 0.3, 1.0)
_erfc = np.vectorize(math.erfc)


def _lobes(oiliness: float) -> list[tuple[float, float]]:
    """(weight, Beckmann m) of the broad and the sharp lobe: docs/model.md's table."""
    w_sharp = 0.15 + 0.70 * oiliness
    return [(1.0 - w_sharp, 0.5), (w_sharp, 0.25 - 0.10 * oiliness)]


def _direction(theta_deg: npt.ArrayLike, phi_deg: npt.ArrayLike) -> npt.NDArray[np.float64]:
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack(np.broadcast_arrays(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1)


def _fresnel(cos_i: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Fresnel's equations, unpolarised, air to index ETA."""
    sin_t = np.sqrt(1.0 - cos_i**2) / ETA
    cos_t = np.sqrt(1.0 - sin_t**2)
    rs = (cos_i - ETA * cos_t) / (cos_i + ETA * cos_t)
    rp = (ETA * cos_i - cos_t) / (ETA * cos_i + cos_t)
    return np.asarray(0.5 * (rs**2 + rp**2))


def _smith_g1(cos_t: npt.NDArray[np.float64], m: float) -> npt.NDArray[np.float64]:
    sin_t = np.sqrt(np.maximum(1.0 - cos_t**2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = cos_t / (m * sin_t)
        lam = 0.5 * (np.exp(-(a**2)) / (a * math.sqrt(math.pi)) - _erfc(a))
    return np.where(sin_t == 0.0, 1.0, 1.0 / (1.0 + np.nan_to_num(lam)))


def reference_brdf(
    theta_in: npt.ArrayLike, theta_out: npt.ArrayLike, phi: npt.ArrayLike, oiliness: float
) -> npt.NDArray[np.float64]:
    """F(i.h) sum_k w_k D_k(h) G1_k(i) G1_k(o) / (4 cos_i cos_o), written from the equations."""
    wi = _direction(theta_in, 0.0)
    wo = _direction(theta_out, phi)
    wi, wo = np.broadcast_arrays(wi, wo)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_i, cos_o, cos_h = wi[..., 2], wo[..., 2], h[..., 2]
    i_dot_h = np.sum(wi * h, axis=-1)
    total = np.zeros_like(cos_h)
    for w, m in _lobes(oiliness):
        tan2 = (1.0 - cos_h**2) / cos_h**2
        d = np.exp(-tan2 / m**2) / (math.pi * m**2 * cos_h**4)
        total = total + w * d * _smith_g1(cos_i, m) * _smith_g1(cos_o, m)
    return np.asarray(_fresnel(i_dot_h) * total / (4.0 * cos_i * cos_o))


def _simpson_weights(n: int, width: float) -> npt.NDArray[np.float64]:
    w = np.ones(n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    return np.asarray(w * width / (3.0 * n))


def direct_albedo(theta_in: float, oiliness: float, surface: str) -> float:
    """E = int f_r cos_o d omega_o by Simpson's rule over theta_out in [0, 89.99] and phi in [0, 180] (doubled)."""
    nt, npp = 600, 240
    t = np.linspace(0.0, 89.99, nt + 1)
    p = np.linspace(0.0, 180.0, npp + 1)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    f = spectral_skin.surface_brdf(theta_in, tt, pp, oiliness=oiliness, surface=surface)
    integrand = f * np.cos(np.radians(tt)) * np.sin(np.radians(tt))
    wt = _simpson_weights(nt, math.radians(89.99))
    wp = _simpson_weights(npp, math.pi)
    return float(2.0 * wt @ integrand @ wp)


# --- shapes -------------------------------------------------------------------------------------------------------


def test_shapes_broadcast_like_numpy() -> None:
    one = spectral_skin.surface_brdf(30.0, 30.0)
    assert isinstance(one, np.ndarray) and one.shape == () and one.dtype == np.float64
    grid = spectral_skin.surface_brdf(np.array([0.0, 20.0, 40.0]), np.array([[10.0], [30.0], [50.0], [70.0]]))
    assert grid.shape == (4, 3)
    with_phi = spectral_skin.surface_brdf(30.0, [[10.0], [30.0]], np.array([0.0, 90.0, 180.0]))
    assert with_phi.shape == (2, 3)
    assert with_phi[1, 2] == spectral_skin.surface_brdf(30.0, 30.0, 180.0)
    assert spectral_skin.surface_brdf(np.zeros((0, 2)), 10.0).shape == (0, 2)
    # Lists, ints and strided read-only arrays read as the same values.
    angles = np.linspace(0.0, 80.0, 9)
    strided = angles[::2]
    strided.setflags(write=False)
    np.testing.assert_array_equal(
        spectral_skin.surface_brdf(strided, 20), spectral_skin.surface_brdf(list(angles[::2]), 20.0)
    )
    np.testing.assert_array_equal(
        spectral_skin.surface_brdf([0, 40], 20), spectral_skin.surface_brdf([0.0, 40.0], 20.0)
    )
    albedo = spectral_skin.surface_albedo([[0.0, 30.0], [60.0, 0.0]])
    assert albedo.shape == (2, 2) and albedo[0, 0] == albedo[1, 1]
    assert spectral_skin.surface_albedo(0.0).shape == ()


# --- against the equations ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("oiliness", OILINESS)
def test_brdf_matches_the_equations_written_out(oiliness: float) -> None:
    rng = np.random.default_rng(24)
    theta_in = rng.uniform(0.0, 89.0, 400)
    theta_out = rng.uniform(0.0, 89.0, 400)
    phi = rng.uniform(-180.0, 360.0, 400)
    core = spectral_skin.surface_brdf(theta_in, theta_out, phi, oiliness=oiliness)
    np.testing.assert_allclose(core, reference_brdf(theta_in, theta_out, phi, oiliness), rtol=1e-10)


def test_normal_incidence_value() -> None:
    for oiliness in OILINESS:
        want = F0 * sum(w / (math.pi * m**2) for w, m in _lobes(oiliness)) / 4.0
        got = float(spectral_skin.surface_brdf(0.0, 0.0, oiliness=oiliness))
        assert got == pytest.approx(want, rel=1e-12)


def test_reciprocal() -> None:
    rng = np.random.default_rng(3)
    a, b, phi = rng.uniform(0.0, 89.0, (3, 200))
    for surface in ("measured", "paper"):
        forward = spectral_skin.surface_brdf(a, b, phi, oiliness=0.7, surface=surface)
        np.testing.assert_allclose(
            forward, spectral_skin.surface_brdf(b, a, phi, oiliness=0.7, surface=surface), rtol=1e-12
        )


@pytest.mark.parametrize("surface", ["measured", "paper"])
@pytest.mark.parametrize("theta_in", [0.0, 45.0, 70.0])
def test_albedo_is_the_integral_of_the_brdf(surface: str, theta_in: float) -> None:
    for oiliness in (0.3, 1.0):
        e = float(spectral_skin.surface_albedo(theta_in, oiliness=oiliness, surface=surface))
        assert e == pytest.approx(direct_albedo(theta_in, oiliness, surface), rel=1e-4)


# --- the model's promises -----------------------------------------------------------------------------------------


def test_in_plane_peak_at_the_mirror_angle() -> None:
    theta_out = np.arange(0.0, 89.5, 0.5)
    for oiliness in OILINESS:
        # At normal incidence the in-plane maximum is the mirror direction itself.
        assert theta_out[np.argmax(spectral_skin.surface_brdf(0.0, theta_out, oiliness=oiliness))] == 0.0
        # At theta_out = theta_in the azimuth of the maximum is the specular plane (phi = 180).
        phi = np.arange(0.0, 360.0, 1.0)
        for theta in (20.0, 45.0, 70.0):
            assert phi[np.argmax(spectral_skin.surface_brdf(theta, theta, phi, oiliness=oiliness))] == 180.0
    # In plane, the oily surface's highlight sits at the mirror angle, shifted a little toward grazing (the
    # off-specular peak of a rough surface: Fresnel and 1 / cos theta_out rise there).
    below_grazing = theta_out[theta_out <= 75.0]
    for theta in (15.0, 30.0):
        f = spectral_skin.surface_brdf(theta, below_grazing, oiliness=1.0)
        assert theta <= below_grazing[np.argmax(f)] <= theta + 3.0, below_grazing[np.argmax(f)]


def test_dry_skin_reflects_under_the_measured_model() -> None:
    for oiliness in OILINESS:
        e0 = float(spectral_skin.surface_albedo(0.0, oiliness=oiliness))
        assert 0.024 <= e0 <= 0.05, (oiliness, e0)
        assert 0.95 * F0 <= e0 <= F0, (oiliness, e0)
    assert float(spectral_skin.surface_brdf(30.0, 30.0, oiliness=0.0)) > 0.0


def test_oil_sharpens_the_highlight() -> None:
    peak = [float(spectral_skin.surface_brdf(30.0, 30.0, oiliness=o)) for o in OILINESS]
    assert peak[0] < peak[1] < peak[2]


def test_paper_at_zero_oiliness_reflects_nothing() -> None:
    theta = np.linspace(0.0, 85.0, 18)
    assert not spectral_skin.surface_brdf(theta, theta[:, None], oiliness=0.0, surface="paper").any()
    assert not spectral_skin.surface_albedo(theta, oiliness=0.0, surface="paper").any()
    # At oiliness 1 the paper's single lobe reflects about F0 at normal incidence, as the measured model does.
    assert float(spectral_skin.surface_albedo(0.0, oiliness=1.0, surface="paper")) == pytest.approx(F0, rel=0.01)


def test_calls_release_the_gil(assert_releases_gil: Callable[[Callable[[], object]], None]) -> None:
    assert_releases_gil(lambda: spectral_skin.surface_albedo(np.linspace(0.0, 80.0, 5)))


# --- bad input ----------------------------------------------------------------------------------------------------


def raises_naming(exception: type[Exception], name: str, call: Callable[[], object]) -> None:
    with pytest.raises(exception) as info:
        call()
    assert name in str(info.value), (name, str(info.value))


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan"), float("inf")])
def test_bad_oiliness_is_refused(bad: float) -> None:
    raises_naming(SpectralSkinError, "oiliness", lambda: spectral_skin.surface_brdf(10.0, 10.0, oiliness=bad))
    raises_naming(
        SpectralSkinError, "oiliness", lambda: spectral_skin.surface_albedo(10.0, oiliness=bad, surface="paper")
    )


@pytest.mark.parametrize("bad", [-1.0, 90.0, 120.0, float("nan"), float("-inf")])
def test_bad_angles_are_refused(bad: float) -> None:
    raises_naming(SpectralSkinError, "theta_in_deg", lambda: spectral_skin.surface_brdf([10.0, bad], 10.0))
    raises_naming(SpectralSkinError, "theta_out_deg", lambda: spectral_skin.surface_brdf(10.0, np.array([bad])))
    raises_naming(SpectralSkinError, "theta_in_deg", lambda: spectral_skin.surface_albedo(bad))
    with pytest.raises(SpectralSkinError, match=r"\[0, 90\)"):
        spectral_skin.surface_brdf(bad, 10.0)


def test_other_bad_arguments_are_refused() -> None:
    raises_naming(SpectralSkinError, "phi_deg", lambda: spectral_skin.surface_brdf(10.0, 10.0, float("nan")))
    raises_naming(SpectralSkinError, "surface", lambda: spectral_skin.surface_brdf(10.0, 10.0, surface="oily"))
    raises_naming(SpectralSkinError, "theta_out_deg", lambda: spectral_skin.surface_brdf([1.0, 2.0], [1.0, 2.0, 3.0]))
    raises_naming(TypeError, "theta_in_deg", lambda: spectral_skin.surface_brdf(np.array([True]), 10.0))
    raises_naming(TypeError, "theta_out_deg", lambda: spectral_skin.surface_brdf(10.0, "10"))
    raises_naming(TypeError, "theta_in_deg", lambda: spectral_skin.surface_albedo([10.0, None]))  # type: ignore[arg-type]
    raises_naming(TypeError, "oiliness", lambda: spectral_skin.surface_brdf(10.0, 10.0, oiliness=True))
    raises_naming(TypeError, "oiliness", lambda: spectral_skin.surface_albedo(10.0, oiliness="0.3"))  # type: ignore[arg-type]


# The Principled inputs of each surface choice (evaluate's "specular"): docs/model.md, "Principled mapping of the
# measured surface".


@pytest.mark.parametrize("engine", ["cycles", "eevee"])
def test_evaluate_surface_choice_gives_the_two_lobes_as_base_and_coat(engine: str) -> None:
    for oiliness in OILINESS:
        spec = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",),
                                      surface="measured", engine=engine)["specular"]
        (w_broad, m_broad), (w_sharp, m_sharp) = _lobes(oiliness)
        got = (spec["surface"], spec["coat_weight"], spec["coat_roughness"], spec["roughness"], spec["ior"],
               spec["coat_ior"])
        assert got == pytest.approx(("measured", w_sharp, math.sqrt(m_sharp), math.sqrt(m_broad), ETA, ETA)), got
        albedo = float(spectral_skin.surface_albedo(0.0, oiliness=oiliness))
        assert spec["directional_albedo_normal"] == pytest.approx(albedo, rel=1e-12), (spec, albedo)
        assert 0.0 < spec["specular_ior_level"] < 1.0, spec


def test_measured_surface_is_the_default_and_paper_has_no_coat() -> None:
    assert [m["name"] for m in spectral_skin.surface_models() if m["default"]] == ["measured"]
    for oiliness in OILINESS:
        default = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",))
        measured = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",),
                                          surface="measured")
        assert default["specular"] == measured["specular"], (default["specular"], measured["specular"])
        paper = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",), surface="paper")
        # DJ2006's oil layer as Principled: level 0.5 rho_s, Roughness sqrt(0.35), no coat.
        spec = paper["specular"]
        got = (spec["specular_ior_level"], spec["roughness"], spec["coat_weight"])
        assert got == pytest.approx((0.5 * oiliness, math.sqrt(0.35), 0.0)), got
        assert paper["surface"]["surface"] == "paper", paper["surface"]


def test_evaluate_refuses_an_unknown_surface_naming_the_choices() -> None:
    with pytest.raises(SpectralSkinError, match=r'surface.*"shiny".*"measured", "paper"'):
        spectral_skin.evaluate(preset="caucasian", surface="shiny")
