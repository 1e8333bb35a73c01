"""Tests of spectral_skin.maps: per-texel results against spectral_skin.evaluate (an independent path through the core:
one evaluation per call, no pipeline), the strategies, specular, bad texels, shapes, types and the GIL."""


import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

CHANNELS = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
RANGES = {"melanin": (0.0, 0.5), "melanin_blend": (0.0, 1.0), "hemoglobin": (0.0, 0.1), "oiliness": (0.0, 1.0)}
EXTENDED = ("epidermis_thickness_mm", "baseline_absorption_scale", "blood_oxygenation")
METHODS = ("burley", "random_walk")
# Worst relative error the lookup table is built for (docs/maps-performance.md): albedo and radius.
TABLE_ALBEDO_RTOL = 0.005
TABLE_RADIUS_RTOL = 0.01


def random_params(height, width, seed=0, dtype=np.float32):
    """(H, W, 4) parameters drawn uniformly from each parameter's range: distinct continuous values everywhere."""
    rng = np.random.default_rng(seed)
    planes = [rng.uniform(*RANGES[name], size=(height, width)) for name in CHANNELS]
    return np.stack(planes, axis=-1).astype(dtype)


def evaluate_texel(texel, method):
    """Base Color and radius of one texel by spectral_skin.evaluate, at the float32 values the map holds."""
    m, b, h, o = (float(v) for v in texel)
    ev = spectral_skin.evaluate(m, b, h, o, outputs=("radius",))["methods"][method]
    return ev["base_color"], ev["subsurface_radius_mm"]


def assert_image(a, height, width, channels=3):
    assert isinstance(a, np.ndarray), type(a)
    assert a.dtype == np.float32, a.dtype
    assert a.shape == ((height, width, channels) if channels > 1 else (height, width)), a.shape
    assert a.flags["C_CONTIGUOUS"] and not a.flags["WRITEABLE"]  # a Maps is read-only
    assert np.all(np.isfinite(a))


def relative_error(approx, exact):
    return float(np.max(np.abs(approx.astype(np.float64) - exact) / np.abs(exact)))


# --- per texel against evaluate -------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
def test_exact_map_equals_evaluate_per_texel(method):
    params = random_params(6, 7, seed=1)
    result = spectral_skin.maps(params, method=method, exact=True)
    assert_image(result["albedo"], 6, 7)
    assert_image(result["radius"], 6, 7)
    assert_image(result["specular"], 6, 7, channels=1)
    report = result["report"]
    assert report["strategy"] == {"name": "exact", "evaluations": 42}
    assert (report["width"], report["height"]) == (7, 6)
    assert report["method"] == method
    assert report["color_space"] == "Linear Rec.709"
    # The extended physiology is at its defaults, one value everywhere.
    assert report["clamped"] == [] and report["constant_parameters"] == list(EXTENDED)
    assert report["request"]["model"]["dermis_thickness_mm"] == float("inf")
    for y in range(6):
        for x in range(7):
            color, radius = evaluate_texel(params[y, x], method)
            np.testing.assert_allclose(result["albedo"][y, x], color, rtol=1e-6, err_msg=f"texel {(x, y)}")
            np.testing.assert_allclose(result["radius"][y, x], radius, rtol=1e-6, err_msg=f"texel {(x, y)}")


def test_specular_map_follows_oiliness():
    params = random_params(5, 4, seed=2)
    params[0, 0, 3] = 0.0
    params[4, 3, 3] = 1.0
    # The paper's oil layer (the measured surface's maps: test_maps_surface.py): level 0 where there is no oil.
    result = spectral_skin.maps(params, surface="paper")
    specular = result["specular"]
    assert_image(specular, 5, 4, channels=1)
    oil = params[..., 3]
    for y, x in [(0, 0), (4, 3), (2, 1)]:
        expected = spectral_skin.evaluate(0.1, 0.5, 0.01, float(oil[y, x]), outputs=("specular",),
                                          surface="paper")["specular"]
        assert specular[y, x] == pytest.approx(expected["specular_ior_level"], rel=1e-6, abs=0)
        # The constants beside the map: those of every texel (they do not depend on the oiliness).
        assert set(result["specular_constants"]) == {"surface", "roughness", "ior", "coat_ior", "beckmann_m",
                                                     "coat_weight", "coat_roughness"}
        for key, value in result["specular_constants"].items():
            assert value == (expected[key] if isinstance(value, str) else pytest.approx(expected[key], rel=1e-12)), key
    assert specular[0, 0] == 0.0


# --- strategies -----------------------------------------------------------------------------------------------------


def test_table_against_exact():
    """64 x 64 distinct values force the table; its error against direct evaluation, here on every 4th texel."""
    params = random_params(64, 64, seed=3)
    table = spectral_skin.maps(params, table_cache=False)  # built here, so its error is measured
    strategy = table["report"]["strategy"]
    assert strategy["name"] == "table", strategy
    resolution = strategy["resolution"]
    assert strategy["nodes"] == resolution["melanin"] * resolution["melanin_blend"] * resolution["hemoglobin"]
    assert strategy["measured_error"]["max_albedo_relative"] < TABLE_ALBEDO_RTOL
    assert strategy["measured_error"]["max_radius_relative"] < TABLE_RADIUS_RTOL
    # A strided (non-contiguous) view: 256 texels, few enough to be evaluated as distinct tuples.
    subset = params[::4, ::4]
    assert not subset.flags["C_CONTIGUOUS"]
    exact = spectral_skin.maps(subset, exact=True)
    assert exact["report"]["strategy"]["name"] == "exact"
    albedo_error = relative_error(table["albedo"][::4, ::4], exact["albedo"])
    radius_error = relative_error(table["radius"][::4, ::4], exact["radius"])
    assert albedo_error < TABLE_ALBEDO_RTOL, albedo_error
    assert radius_error < TABLE_RADIUS_RTOL, radius_error
    assert albedo_error > 0  # the table is interpolated, not the exact path under another name


def test_table_resolution_is_passed_through():
    params = random_params(48, 48, seed=4)  # 2304 distinct tuples: more than the 2048 evaluated one by one
    result = spectral_skin.maps(params, table_resolution=(3, 2, 3), wavelength_step_nm=20.0)
    strategy = result["report"]["strategy"]
    assert strategy["name"] == "table"
    assert strategy["resolution"] == {"melanin": 3, "melanin_blend": 2, "hemoglobin": 3}
    assert strategy["nodes"] == 18
    assert result["report"]["request"]["accuracy"]["wavelength_step_nm"] == 20.0


def test_constant_parameters():
    oil = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    result = spectral_skin.maps(melanin=0.15, melanin_blend=0.0, hemoglobin=0.01, oiliness=oil)
    report = result["report"]
    assert report["strategy"] == {"name": "constant"}
    assert report["constant_parameters"] == ["melanin", "melanin_blend", "hemoglobin", *EXTENDED]
    color, radius = evaluate_texel([0.15, 0.0, 0.01, 0.0], "burley")
    for image, expected in [(result["albedo"], color), (result["radius"], radius)]:
        assert_image(image, 3, 4)
        np.testing.assert_allclose(image, np.broadcast_to(expected, (3, 4, 3)), rtol=1e-6)
    assert_image(result["specular"], 3, 4, channels=1)


def test_few_distinct_values():
    """A mask with three regions: one evaluation per distinct (melanin, melanin_blend, hemoglobin)."""
    mask = np.zeros((16, 16), dtype=np.int64)
    mask[4:12, 4:12] = 1
    mask[6:10, 6:10] = 2
    values = np.array([[0.02, 0.7, 0.005, 0.3], [0.15, 0.0, 0.01, 0.3], [0.4, 0.9, 0.08, 0.3]], dtype=np.float32)
    params = values[mask]
    result = spectral_skin.maps(params, method="random_walk")
    assert result["report"]["strategy"] == {"name": "distinct_tuples", "tuples": 3}
    # Oiliness is 0.3 everywhere: an array holding one value counts as a constant.
    assert result["report"]["constant_parameters"] == ["oiliness", *EXTENDED]
    expected = spectral_skin.evaluate(preset="caucasian", outputs=("specular",))["specular"]  # oiliness 0.3
    assert result["specular_constants"]["specular_ior_level"] == pytest.approx(expected["specular_ior_level"],
                                                                               rel=1e-6)
    for region in range(3):
        color, radius = evaluate_texel(values[region], "random_walk")
        inside = mask == region
        np.testing.assert_allclose(result["albedo"][inside], np.tile(color, (inside.sum(), 1)), rtol=1e-6)
        np.testing.assert_allclose(result["radius"][inside], np.tile(radius, (inside.sum(), 1)), rtol=1e-6)


def test_constant_oiliness_gives_specular_constants():
    params = random_params(4, 4, seed=5)
    result = spectral_skin.maps(params, oiliness=0.3)
    specular = result["specular_constants"]
    assert isinstance(specular, dict) and "specular" not in result
    expected = spectral_skin.evaluate(preset="caucasian", outputs=("specular",))["specular"]  # oiliness 0.3
    assert set(specular) == set(expected)
    for key, value in expected.items():
        want = value if isinstance(value, str) else pytest.approx(value, rel=1e-6)  # "surface": the model's name
        assert specular[key] == want, (key, specular[key], value)
    assert "oiliness" in result["report"]["constant_parameters"]
    # Zero oiliness: the paper's oil layer is off (level 0); the measured surface, the default, still reflects.
    zero = spectral_skin.maps(params, oiliness=0.0, surface="paper")["specular_constants"]
    assert zero["specular_ior_level"] == 0.0 and zero["oiliness"] == 0.0
    dry = spectral_skin.maps(params, oiliness=0.0)["specular_constants"]
    assert dry["specular_ior_level"] > 0.4 and dry["coat_weight"] == pytest.approx(0.15), dry


def test_keywords_override_params_and_accept_float64_and_any_layout():
    params = random_params(8, 8, seed=6)
    reference = spectral_skin.maps(params, exact=True)
    # float64 input converted to the same float32 values.
    as64 = spectral_skin.maps(params.astype(np.float64), exact=True)
    np.testing.assert_array_equal(as64["albedo"], reference["albedo"])
    # Fortran order and separate keyword planes (one of them a transposed view).
    fortran = spectral_skin.maps(np.asfortranarray(params), exact=True)
    np.testing.assert_array_equal(fortran["radius"], reference["radius"])
    planes = {name: params[..., c] for c, name in enumerate(CHANNELS)}
    planes["hemoglobin"] = np.ascontiguousarray(params[..., 2].T).T
    separate = spectral_skin.maps(**planes, exact=True)
    np.testing.assert_array_equal(separate["albedo"], reference["albedo"])
    np.testing.assert_array_equal(separate["specular"], reference["specular"])
    # A keyword replaces its channel of params.
    other = random_params(8, 8, seed=7)[..., 0]
    override = spectral_skin.maps(params, melanin=other, exact=True)
    expected = spectral_skin.maps(np.stack([other, *(params[..., c] for c in (1, 2, 3))], axis=-1), exact=True)
    np.testing.assert_array_equal(override["albedo"], expected["albedo"])
    assert not np.array_equal(override["albedo"], reference["albedo"])


def test_working_space_is_passed_through():
    params = random_params(2, 2, seed=8)
    rec709 = spectral_skin.maps(params, wavelength_step_nm=10.0)
    rec2020 = spectral_skin.maps(params, wavelength_step_nm=10.0, working_space="Linear Rec.2020")
    assert rec2020["report"]["color_space"] == "Linear Rec.2020"
    assert not np.allclose(rec709["albedo"], rec2020["albedo"])
    m, b, h, o = (float(v) for v in params[1, 0])
    ev = spectral_skin.evaluate(m, b, h, o, wavelength_step_nm=10.0, working_space="Linear Rec.2020")
    np.testing.assert_allclose(rec2020["albedo"][1, 0], ev["methods"]["burley"]["base_color"], rtol=1e-6)


# --- bad texels -----------------------------------------------------------------------------------------------------


def bad_melanin_params():
    params = random_params(8, 8, seed=9)
    params[0, 7, 0] = 0.7  # (x, y) = (7, 0): out of range
    params[2, 3, 0] = np.nan  # (3, 2)
    params[5, 1, 0] = np.inf  # (1, 5)
    return params


def test_bad_texels_are_errors():
    with pytest.raises(SpectralSkinError) as info:
        spectral_skin.maps(bad_melanin_params())
    message = str(info.value)
    for fragment in ["melanin", "[0, 0.5]", "1 NaN", "1 infinite", "1 out-of-range", "(7, 0)", "(3, 2)", "(1, 5)",
                     "clamp=True"]:
        assert fragment in message, (fragment, message)


def test_bad_texels_are_clamped_and_counted():
    params = bad_melanin_params()
    result = spectral_skin.maps(params, clamp=True, exact=True)
    assert result["report"]["clamped"] == [
        {"parameter": "melanin", "nan": 1, "infinite": 1, "out_of_range": 1, "first": [[7, 0], [3, 2], [1, 5]]}
    ]
    fixed = params.copy()
    fixed[0, 7, 0], fixed[2, 3, 0], fixed[5, 1, 0] = 0.5, 0.0, 0.5  # NaN to the minimum, +inf and 0.7 to the maximum
    expected = spectral_skin.maps(fixed, exact=True)
    np.testing.assert_array_equal(result["albedo"], expected["albedo"])
    np.testing.assert_array_equal(result["radius"], expected["radius"])
    assert np.isnan(params[2, 3, 0])  # the input array is not modified


def test_bad_constants():
    params = random_params(4, 4, seed=10)
    with pytest.raises(SpectralSkinError, match=r"hemoglobin.*\[0, 0\.1\].*0\.2"):
        spectral_skin.maps(params, hemoglobin=0.2)
    with pytest.raises(SpectralSkinError, match="oiliness.*NaN"):
        spectral_skin.maps(params, oiliness=float("nan"))
    result = spectral_skin.maps(params, hemoglobin=0.2, clamp=True)
    clamped = result["report"]["clamped"]
    assert [(c["parameter"], c["out_of_range"]) for c in clamped] == [("hemoglobin", 1)]


# --- shapes and types -----------------------------------------------------------------------------------------------


SHAPE_ERRORS = [
    (lambda: spectral_skin.maps(random_params(8, 8), melanin=np.zeros((4, 4), np.float32)),
     ["params (8, 8, 4)", "melanin (4, 4)"]),
    (lambda: spectral_skin.maps(melanin=np.zeros((3, 5), np.float32), melanin_blend=0.5, hemoglobin=0.01,
                                oiliness=np.zeros((5, 3), np.float32)),
     ["melanin (3, 5)", "oiliness (5, 3)"]),
    (lambda: spectral_skin.maps(np.zeros((8, 8, 3), np.float32)), ["params", "(8, 8, 3)", "(H, W, 4)"]),
    (lambda: spectral_skin.maps(np.zeros((8, 8), np.float32)), ["params", "(8, 8)", "(H, W, 4)"]),
    (lambda: spectral_skin.maps(random_params(2, 2), melanin=np.zeros(4, np.float32)), ["melanin", "(4,)", "(H, W)"]),
    (lambda: spectral_skin.maps(np.zeros((0, 8, 4), np.float32)), ["8 wide x 0 high"]),
    (lambda: spectral_skin.maps(melanin=0.1, melanin_blend=0.5, hemoglobin=0.01, oiliness=0.3), ["at least one array"]),
    (lambda: spectral_skin.maps(melanin=np.zeros((2, 2), np.float32), melanin_blend=0.5), ["missing", "hemoglobin",
                                                                                          "oiliness"]),
    (lambda: spectral_skin.maps(), ["params", "missing"]),
    (lambda: spectral_skin.maps(random_params(2, 2), method="christensen"), ["method", "christensen", "burley",
                                                                             "random_walk"]),
    (lambda: spectral_skin.maps(random_params(2, 2), working_space="sRGB"), ["working_space", "sRGB"]),
    (lambda: spectral_skin.maps(random_params(2, 2), wavelength_step_nm=0.0), ["wavelength_step_nm"]),
    (lambda: spectral_skin.maps(random_params(2, 2), table_resolution=(1, 9, 25)), ["table_resolution", "at least 2"]),
    (lambda: spectral_skin.maps(random_params(2, 2), table_resolution=(9, 25)), ["table_resolution", "got 2 values"]),
]


@pytest.mark.parametrize("call, fragments", SHAPE_ERRORS)
def test_shape_and_setting_errors(call, fragments):
    with pytest.raises(SpectralSkinError) as info:
        call()
    assert isinstance(info.value, ValueError)
    message = str(info.value)
    assert all(f in message for f in fragments), (message, fragments)


@pytest.mark.parametrize(
    "call",
    [
        lambda: spectral_skin.maps(random_params(2, 2).astype(np.float16)),
        lambda: spectral_skin.maps(np.zeros((2, 2, 4), dtype=np.int32)),
        lambda: spectral_skin.maps(random_params(2, 2).tolist()),
        lambda: spectral_skin.maps(random_params(2, 2), melanin=[[0.1, 0.1], [0.1, 0.1]]),
        lambda: spectral_skin.maps(random_params(2, 2), melanin="0.1"),
        lambda: spectral_skin.maps(random_params(2, 2), melanin=True),
        lambda: spectral_skin.maps(random_params(2, 2), hemoglobin=np.zeros((2, 2), dtype=np.uint8)),
        lambda: spectral_skin.maps(random_params(2, 2), table_resolution="big"),
        lambda: spectral_skin.maps(random_params(2, 2), table_resolution=(9.5, 9, 9)),
    ],
)
def test_wrong_types_are_type_errors(call):
    with pytest.raises(TypeError):
        call()


def test_numpy_scalars_are_constants():
    params = random_params(3, 3, seed=11)
    a = spectral_skin.maps(params, melanin=np.float32(0.25), oiliness=np.float64(0.5), hemoglobin=0)
    b = spectral_skin.maps(params, melanin=0.25, oiliness=0.5, hemoglobin=0.0)
    np.testing.assert_array_equal(a["albedo"], b["albedo"])
    assert a["report"]["strategy"]["name"] == "distinct_tuples"


def test_exported():
    assert spectral_skin.maps is spectral_skin._core.maps
    assert "maps" in spectral_skin.__all__


# --- the GIL --------------------------------------------------------------------------------------------------------


def test_gil_is_released_during_maps(assert_releases_gil):
    """While the maps are computed, this thread keeps running Python: it could not if the call held the GIL."""
    params = random_params(8, 8, seed=12)
    assert_releases_gil(lambda: spectral_skin.maps(params, exact=True))


def test_table_cache_is_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path))
    rng = np.random.default_rng(3)
    params = np.stack([rng.uniform(0, 0.5, (48, 48)), rng.uniform(0, 1, (48, 48)), rng.uniform(0, 0.1, (48, 48)),
                       np.full((48, 48), 0.2)], axis=-1).astype(np.float32)
    small = (5, 3, 4)
    first = spectral_skin.maps(params, table_resolution=small)
    assert first["report"]["strategy"]["from_cache"] is False
    assert list(tmp_path.iterdir()), "the table was not kept"
    second = spectral_skin.maps(params, table_resolution=small)
    assert second["report"]["strategy"]["from_cache"] is True
    np.testing.assert_array_equal(first["albedo"], second["albedo"])
    fresh = spectral_skin.maps(params, table_resolution=small, table_cache=False)
    assert fresh["report"]["strategy"]["from_cache"] is False


@pytest.mark.parametrize("exact", [True, False])
def test_outputs_choice_computes_only_what_is_asked(exact):
    """outputs=...: without "radius" no radius fit (report["work"]) and Base Color is evaluate()'s albedo, whatever the
    method; without "specular" no specular input; what is kept equals the full run's."""
    size = 6 if exact else 48  # 48 x 48 random texels: more distinct tuples than the core evaluates one by one
    params = random_params(size, size, seed=3)
    kwargs = {"exact": exact, "table_cache": False, "method": "random_walk"}
    full = spectral_skin.maps(params, **kwargs)
    assert full["report"]["work"]["radius_fits"] > 0
    no_radius = spectral_skin.maps(params, outputs=("albedo", "specular"), **kwargs)
    work = no_radius["report"]["work"]
    assert work["radius_fits"] == 0 and work["outputs"]["radius"] == 0, work
    assert "radius" not in no_radius
    np.testing.assert_array_equal(no_radius["specular"], full["specular"])
    if exact:
        for y, x in [(0, 0), (2, 5), (5, 3)]:
            m, b, h, o = (float(v) for v in params[y, x])
            albedo = spectral_skin.evaluate(m, b, h, o, outputs=("albedo",))["diffuse_reflectance_rgb"]
            np.testing.assert_array_equal(no_radius["albedo"][y, x], np.float32(albedo))
    else:
        assert no_radius["report"]["strategy"]["name"] == "table"
        assert work["table_nodes_built"] == full["report"]["work"]["table_nodes_built"] > 0
    no_specular = spectral_skin.maps(params, outputs=("albedo", "radius"), **kwargs)
    assert no_specular["report"]["work"]["specular_evaluations"] == 0
    assert "specular_constants" not in no_specular and "specular" not in no_specular
    np.testing.assert_array_equal(no_specular["albedo"], full["albedo"])
    np.testing.assert_array_equal(no_specular["radius"], full["radius"])


@pytest.mark.parametrize("outputs", [(), ("profile_rgb",), ("albedo", "spectrum")])
def test_outputs_choice_rejects_what_maps_do_not_compute(outputs):
    with pytest.raises(SpectralSkinError, match="maps computes albedo, radius, specular"):
        spectral_skin.maps(random_params(2, 2), outputs=outputs)


# --- the extended physiology ----------------------------------------------------------------------------------------


def test_extended_defaults_give_identical_maps():
    params = random_params(6, 7, seed=3)
    plain = spectral_skin.maps(params, table_cache=False)
    defaults = {p["name"]: p["default"] for p in spectral_skin.parameters() if p["name"] in EXTENDED}
    assert defaults == {"epidermis_thickness_mm": 0.25, "baseline_absorption_scale": 1.0, "blood_oxygenation": 0.75}
    given = spectral_skin.maps(params, table_cache=False, **defaults)
    np.testing.assert_array_equal(plain["albedo"], given["albedo"])
    np.testing.assert_array_equal(plain["radius"], given["radius"])
    assert set(EXTENDED) <= set(given["report"]["constant_parameters"])
    assert given["report"]["constant_values"]["blood_oxygenation"] == 0.75


@pytest.mark.parametrize("exact", [False, True])
def test_extended_constant_gives_evaluates_values(exact):
    # A few distinct tuples: each evaluated directly, so the maps equal evaluate() at float32 inputs.
    params = np.zeros((2, 3, 4), np.float32)
    params[..., 0] = [[0.01, 0.2, 0.4], [0.01, 0.2, 0.4]]
    params[..., 1:] = (0.5, 0.02, 0.3)
    result = spectral_skin.maps(params, epidermis_thickness_mm=0.08, blood_oxygenation=0.9, exact=exact)
    for y, x in np.ndindex(2, 3):
        m, b, h, o = (float(v) for v in params[y, x])
        ev = spectral_skin.evaluate(m, b, h, o, epidermis_thickness_mm=0.08, blood_oxygenation=float(np.float32(0.9)))
        expected = ev["methods"]["burley"]
        np.testing.assert_allclose(result["albedo"][y, x], expected["base_color"], rtol=1e-6)
        np.testing.assert_allclose(result["radius"][y, x], expected["subsurface_radius_mm"], rtol=1e-6)
    paper = spectral_skin.maps(params)
    assert relative_error(paper["albedo"], result["albedo"].astype(np.float64)) > 0.01


def test_extended_map_varies_per_texel():
    params = np.zeros((3, 4, 4), np.float32)
    params[...] = (0.1, 0.5, 0.02, 0.3)
    thickness = np.linspace(0.02, 0.46, 12, dtype=np.float32).reshape(3, 4)
    result = spectral_skin.maps(params, epidermis_thickness_mm=thickness)
    assert result["report"]["strategy"]["name"] == "distinct_tuples"
    assert "epidermis_thickness_mm" not in result["report"]["constant_parameters"]
    for y, x in np.ndindex(3, 4):
        ev = spectral_skin.evaluate(0.1, float(np.float32(0.5)), float(np.float32(0.02)), float(np.float32(0.3)),
                                    epidermis_thickness_mm=float(thickness[y, x]))
        np.testing.assert_allclose(result["albedo"][y, x], ev["methods"]["burley"]["base_color"], rtol=1e-6)


def test_extended_bad_values_name_the_parameter():
    params = random_params(3, 3)
    with pytest.raises(SpectralSkinError, match=r"blood_oxygenation.*\[0, 1\]"):
        spectral_skin.maps(params, blood_oxygenation=1.5)
    bad = np.full((3, 3), 0.25, np.float32)
    bad[1, 2] = 0.9
    with pytest.raises(SpectralSkinError, match="epidermis_thickness_mm") as info:
        spectral_skin.maps(params, epidermis_thickness_mm=bad)
    assert info.value.bad_texels["first"] == [(2, 1)]
    clamped = spectral_skin.maps(params, epidermis_thickness_mm=bad, clamp=True)
    assert clamped["report"]["clamped"][0]["parameter"] == "epidermis_thickness_mm"
    with pytest.raises(SpectralSkinError, match="shapes"):
        spectral_skin.maps(params, baseline_absorption_scale=np.ones((2, 3), np.float32))
