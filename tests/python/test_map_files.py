"""The EXRs and sidecar that `spectral-skin maps` writes, opened with OpenImageIO (an independent EXR reader) and
compared with `spectral_skin.evaluate` at sample texels."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import spectral_skin

oiio = pytest.importorskip("OpenImageIO")

ROOT = Path(__file__).resolve().parents[2]
CLI = ROOT / "target" / "release" / "spectral-skin"


def read(path: Path) -> tuple[tuple[str, ...], np.ndarray]:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    return tuple(spec.channelnames), np.asarray(pixels)


@pytest.fixture(scope="module")
def maps_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not CLI.exists():
        pytest.skip("build the CLI first: cargo build --release")
    tmp = tmp_path_factory.mktemp("maps")
    params = tmp / "face.exr"
    subprocess.run([str(CLI), "example", "--out", str(params), "--size", "96"], check=True, capture_output=True)
    out = tmp / "out"
    env = {"SPECTRAL_SKIN_CACHE_DIR": str(tmp / "cache"), "PATH": "/usr/bin:/bin"}
    subprocess.run([str(CLI), "maps", "--params", str(params), "--out", str(out)], check=True, capture_output=True, env=env)
    return out


def test_outputs_open_in_openimageio(maps_dir: Path) -> None:
    sidecar = json.loads((maps_dir / "skin_maps.json").read_text())
    for name, expected in (("albedo.exr", ("R", "G", "B")), ("radius.exr", ("R", "G", "B")), ("specular.exr", ("Y",))):
        channels, pixels = read(maps_dir / name)
        assert channels == expected, name
        assert pixels.shape == (96, 96, len(expected))
        assert np.isfinite(pixels).all() and (pixels >= 0).all()
        assert sidecar["outputs"][name]["channels"] == list(expected)
    _, level = read(maps_dir / "specular.exr")
    assert 0.0 < level.min() and level.max() <= 0.5  # Specular IOR Level = oiliness / 2
    assert sidecar["outputs"]["radius.exr"]["units"] == "mm"
    assert sidecar["outputs"]["albedo.exr"]["color_space"] == "Linear Rec.709"


def test_texels_match_direct_evaluation(maps_dir: Path) -> None:
    """albedo.exr and radius.exr hold, texel for texel, what evaluate gives for the texel's parameters (the table
    strategy: within its stated bounds, 0.5 % albedo and 1 % radius)."""
    _, params = read(maps_dir.parent / "face.exr")
    names, _ = read(maps_dir.parent / "face.exr")
    index = {n: i for i, n in enumerate(names)}
    _, albedo = read(maps_dir / "albedo.exr")
    _, radius = read(maps_dir / "radius.exr")
    rng = np.random.default_rng(7)
    for y, x in rng.integers(0, 96, size=(12, 2)):
        p = params[y, x]
        ev = spectral_skin.evaluate(
            float(p[index["melanin"]]),
            float(p[index["melanin_blend"]]),
            min(float(p[index["hemoglobin"]]), 0.1),
            float(p[index["oiliness"]]),
        )
        burley = ev["methods"]["burley"]
        np.testing.assert_allclose(albedo[y, x], burley["base_color"], rtol=5e-3)
        np.testing.assert_allclose(radius[y, x], burley["subsurface_radius_mm"], rtol=1e-2)
