"""`spectral_skin.shader_table` and `write_shader_table`: the images' layout checked against `evaluate` at the
table's nodes, the node group's documented lookup (emulated here in numpy from the docstring's formulas) against
`evaluate` between nodes, and the files read back with OpenImageIO (an independent EXR reader)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

SMALL = (6, 4, 5)


@pytest.fixture(scope="module")
def small() -> spectral_skin._core._ShaderTable:
    return spectral_skin.shader_table(method="burley", resolution=SMALL, table_cache=False)


def test_shapes_and_metadata(small: spectral_skin._core._ShaderTable) -> None:
    n_m, n_b, n_h = SMALL
    meta = small["metadata"]
    assert (meta["width"], meta["height"], meta["slice_width"], meta["gutter"]) == (n_b * (n_m + 2), n_h, n_m + 2, 1)
    for key in ("base_color_log", "radius_log"):
        assert small[key].shape == (n_h, n_b * (n_m + 2), 3) and small[key].dtype == np.float32, key
    assert meta["melanin"] == {"nodes": n_m, "min": 0.0, "max": 0.5, "warp": "cube_root"}
    assert meta["melanin_blend"] == {"nodes": n_b, "min": 0.0, "max": 1.0, "warp": "linear"}
    assert meta["hemoglobin"] == {"nodes": n_h, "min": 0.0, "max": 0.1, "warp": "cube_root"}
    assert (meta["method"], meta["engine"], meta["stored"]) == ("burley", "cycles", "ln")


@pytest.mark.parametrize("node", [(0, 0, 0), (5, 3, 4), (2, 1, 3), (4, 2, 0)])
def test_texels_hold_the_log_of_direct_evaluation_at_the_nodes(
    small: spectral_skin._core._ShaderTable, node: tuple[int, int, int]
) -> None:
    n_m, n_b, n_h = SMALL
    i, j, k = node
    params = {
        "melanin": 0.5 * (i / (n_m - 1)) ** 3,
        "melanin_blend": j / (n_b - 1),
        "hemoglobin": 0.1 * (k / (n_h - 1)) ** 3,
        "oiliness": 0.0,
    }
    burley = spectral_skin.evaluate(**params)["methods"]["burley"]
    # Node k on row k from the bottom; column 1 + i of slice j (column 0 is the guard).
    row, col = n_h - 1 - k, j * (n_m + 2) + 1 + i
    np.testing.assert_allclose(np.exp(small["base_color_log"][row, col]), burley["base_color"], rtol=2e-6)
    np.testing.assert_allclose(np.exp(small["radius_log"][row, col]), burley["subsurface_radius_mm"], rtol=2e-6)


def _bilinear(image: np.ndarray, x: float, y: float) -> np.ndarray:
    """Blender's Image Texture, Linear, Extend, at (x, y) in [0, 1]^2 with y = 0 the bottom row."""
    h, w, _ = image.shape
    px, py = x * w - 0.5, y * h - 0.5
    x0, y0 = int(np.floor(px)), int(np.floor(py))
    tx, ty = px - x0, py - y0
    bottom_up = image[::-1]
    at = lambda xi, yi: bottom_up[min(max(yi, 0), h - 1), min(max(xi, 0), w - 1)]  # noqa: E731
    return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) + ty * (
        (1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1)
    )


def test_the_documented_node_lookup_is_within_one_percent_of_direct_evaluation() -> None:
    table = spectral_skin.shader_table(method="random_walk")
    meta = table["metadata"]
    n_m, n_b, n_h = (meta[a]["nodes"] for a in ("melanin", "melanin_blend", "hemoglobin"))
    rng = np.random.default_rng(7)
    for c_m, beta, c_h in zip(rng.uniform(0, 0.5, 12), rng.uniform(0, 1, 12), rng.uniform(0, 0.1, 12), strict=True):
        u_m, u_h = (c_m / 0.5) ** (1 / 3), (c_h / 0.1) ** (1 / 3)
        b = beta * (n_b - 1)
        j = min(np.floor(b), n_b - 2)
        t = b - j
        x0, x1 = ((s * (n_m + 2) + 1 + u_m * (n_m - 1) + 0.5) / meta["width"] for s in (j, j + 1))
        y = (u_h * (n_h - 1) + 0.5) / n_h
        got = {
            key: np.exp((1 - t) * _bilinear(table[key], x0, y) + t * _bilinear(table[key], x1, y))
            for key in ("base_color_log", "radius_log")
        }
        rw = spectral_skin.evaluate(melanin=c_m, melanin_blend=beta, hemoglobin=c_h, oiliness=0.0)["methods"][
            "random_walk"
        ]
        # docs/shader-table.md: worst error below 1 % over the domain at the default resolution.
        np.testing.assert_allclose(got["base_color_log"], rw["base_color"], rtol=0.01)
        np.testing.assert_allclose(got["radius_log"], rw["subsurface_radius_mm"], rtol=0.01)


def test_write_shader_table_writes_what_it_was_given(small: spectral_skin._core._ShaderTable, tmp_path: Path) -> None:
    oiio = pytest.importorskip("OpenImageIO")
    written = spectral_skin.write_shader_table(small, tmp_path / "out", "Skin")
    out = tmp_path / "out"
    assert {k: Path(v) for k, v in written.items()} == {
        "base_color": out / "Skin_shader_base_color.exr",
        "radius": out / "Skin_shader_radius.exr",
        "metadata": out / "Skin_shader_table.json",
    }
    assert sorted(p.name for p in out.iterdir()) == sorted(Path(v).name for v in written.values())
    for key, file in (("base_color_log", written["base_color"]), ("radius_log", written["radius"])):
        inp = oiio.ImageInput.open(str(file))
        assert inp is not None, oiio.geterror()
        assert tuple(inp.spec().channelnames) == ("R", "G", "B")
        pixels = np.asarray(inp.read_image(oiio.FLOAT))
        inp.close()
        np.testing.assert_array_equal(pixels.reshape(small[key].shape), small[key], err_msg=key)
    sidecar = json.loads(Path(written["metadata"]).read_text())
    assert sidecar["files"]["base_color"]["file"] == "Skin_shader_base_color.exr"
    assert {k: v for k, v in sidecar.items() if k != "files"} == json.loads(json.dumps(small["metadata"]))


def test_write_shader_table_rejects_a_mismatched_result(
    small: spectral_skin._core._ShaderTable, tmp_path: Path
) -> None:
    with pytest.raises(SpectralSkinError, match="metadata says"):
        spectral_skin.write_shader_table({**small, "radius_log": small["radius_log"][:, :8]}, tmp_path)
    with pytest.raises(SpectralSkinError, match="format"):
        spectral_skin.write_shader_table({**small, "metadata": {**small["metadata"], "format": "x"}}, tmp_path)
    with pytest.raises(SpectralSkinError, match="prefix"):
        spectral_skin.write_shader_table(small, tmp_path, "a/b")
    with pytest.raises(SpectralSkinError, match="metadata"):
        spectral_skin.write_shader_table({k: v for k, v in small.items() if k != "metadata"}, tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_cli_writes_the_same_table(small: spectral_skin._core._ShaderTable, tmp_path: Path) -> None:
    oiio = pytest.importorskip("OpenImageIO")
    cli = Path(__file__).resolve().parents[2] / "target" / "release" / "spectral-skin"
    if not cli.exists():
        pytest.skip("build the CLI first: cargo build --release")
    args = [str(cli), "shader-table", "--out", str(tmp_path), "--resolution", *map(str, SMALL), "--no-cache"]
    subprocess.run(args, check=True, capture_output=True)
    sidecar = json.loads((tmp_path / "shader_table.json").read_text())
    assert {k: v for k, v in sidecar.items() if k not in ("files", "crate_version")} == {
        k: v for k, v in json.loads(json.dumps(small["metadata"])).items() if k != "crate_version"
    }
    inp = oiio.ImageInput.open(str(tmp_path / "shader_radius.exr"))
    pixels = np.asarray(inp.read_image(oiio.FLOAT))
    inp.close()
    np.testing.assert_array_equal(pixels.reshape(small["radius_log"].shape), small["radius_log"])


def test_extended_constants_are_baked_and_recorded() -> None:
    thin = spectral_skin.shader_table(resolution=SMALL, table_cache=False, epidermis_thickness_mm=0.08)
    meta = thin["metadata"]
    assert meta["extended"] == {"epidermis_thickness_mm": 0.08, "baseline_absorption_scale": 1.0,
                                "blood_oxygenation": 0.75}
    # Node (0, 0, 0): C_m = 0, beta_m = 0, C_h = 0 at the table's top-left texel past the guard column (row H - 1).
    ev = spectral_skin.evaluate(0.0, 0.0, 0.0, 0.0, epidermis_thickness_mm=0.08)
    expected = np.log(ev["methods"]["burley"]["base_color"])
    np.testing.assert_allclose(thin["base_color_log"][SMALL[2] - 1, 1], expected, rtol=1e-5, atol=1e-6)
    paper = spectral_skin.shader_table(resolution=SMALL, table_cache=False)
    assert paper["metadata"]["extended"]["epidermis_thickness_mm"] == 0.25
    assert not np.allclose(paper["base_color_log"], thin["base_color_log"])
    with pytest.raises(SpectralSkinError, match="baseline_absorption_scale"):
        spectral_skin.shader_table(resolution=SMALL, table_cache=False, baseline_absorption_scale=11.0)
    with pytest.raises(TypeError, match="blood_oxygenation"):
        spectral_skin.shader_table(resolution=SMALL, table_cache=False, blood_oxygenation=True)  # type: ignore[arg-type]
