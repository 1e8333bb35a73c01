"""The EXRs and sidecar that `spectral-skin maps` writes, opened with OpenImageIO (an independent EXR reader) and
compared with `spectral_skin.evaluate` at sample texels; the same writer from Python (`spectral_skin.write_maps`),
read back with OpenImageIO and compared with the arrays it was given."""

from __future__ import annotations

import errno
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
    for name, expected in (("albedo.exr", ("R", "G", "B")), ("radius.exr", ("R", "G", "B")), ("specular.exr", ("Y",)),
                           ("coat_weight.exr", ("Y",)), ("coat_roughness.exr", ("Y",))):
        channels, pixels = read(maps_dir / name)
        assert channels == expected, name
        assert pixels.shape == (96, 96, len(expected))
        assert np.isfinite(pixels).all() and (pixels >= 0).all()
        assert sidecar["outputs"][name]["channels"] == list(expected)
    # The default (measured) surface: Coat Weight 0.15 + 0.70 oiliness, in [0.15, 0.85] (docs/model.md).
    _, weight = read(maps_dir / "coat_weight.exr")
    assert 0.15 - 1e-3 <= weight.min() < weight.max() <= 0.85 + 1e-3
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


# --- spectral_skin.write_maps: the core's writer from Python ----------------------------------------------------------


def _result(oiliness_varies: bool = True) -> dict:
    rng = np.random.default_rng(11)
    params = np.stack([rng.uniform(0.0, 0.5, (5, 7)), rng.uniform(0.0, 1.0, (5, 7)), rng.uniform(0.0, 0.1, (5, 7)),
                       rng.uniform(0.0, 1.0, (5, 7)) if oiliness_varies else np.full((5, 7), 0.3)],
                      axis=-1).astype(np.float32)
    return dict(spectral_skin.maps(params, exact=True))


def test_write_maps_writes_what_it_was_given(tmp_path: Path) -> None:
    result = _result()
    written = spectral_skin.write_maps(result, tmp_path / "out", "scene_Skin")
    out = tmp_path / "out"
    names = ("albedo", "radius", "specular", "coat_weight", "coat_roughness")  # the default, measured surface's
    assert {k: str(v) for k, v in written.items()} == {name: str(out / f"scene_Skin_{name}.exr") for name in names}
    # Exactly the maps: no sidecar, no temporaries left.
    assert sorted(p.name for p in out.iterdir()) == sorted(f"scene_Skin_{name}.exr" for name in names)
    # Each map's one name: the output, the result's key, the file.
    for name in names:
        channels = ("R", "G", "B") if name in ("albedo", "radius") else ("Y",)
        names, pixels = read(out / f"scene_Skin_{name}.exr")
        assert names == channels, name
        # Half floats by default: what maps() returned rounded to nearest half (as numpy rounds), row 0 at the top.
        expected = result[name].astype(np.float16).astype(np.float32)
        np.testing.assert_array_equal(pixels.reshape(result[name].shape), expected, err_msg=name)
    # precision="float": bit for bit what maps() returned; float64 input is rounded to float32, as maps() does with
    # its inputs. The compression names are the CLI's.
    radius64 = {"radius": result["radius"].astype(np.float64)}
    spectral_skin.write_maps(radius64, tmp_path / "f64", precision="float", compression="zips")
    np.testing.assert_array_equal(read(tmp_path / "f64" / "radius.exr")[1].reshape(result["radius"].shape),
                                  result["radius"])
    with pytest.raises(spectral_skin.SpectralSkinError, match="unknown compression"):
        spectral_skin.write_maps(radius64, tmp_path / "f64", compression="PIZ")


def test_write_maps_removes_outputs_it_no_longer_writes(tmp_path: Path) -> None:
    spectral_skin.write_maps(_result(), tmp_path, "Skin")
    spectral_skin.write_maps(_result(), tmp_path, "Other")
    constant = _result(oiliness_varies=False)
    assert "specular" not in constant
    written = spectral_skin.write_maps({"albedo": constant["albedo"], "radius": None}, tmp_path, "Skin")
    assert sorted(written) == ["albedo"]
    # This prefix's radius and specular maps are gone; another prefix's files are untouched.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Other_albedo.exr", "Other_coat_roughness.exr",
                                                          "Other_coat_weight.exr", "Other_radius.exr",
                                                          "Other_specular.exr", "Skin_albedo.exr"]


def test_write_maps_failure_leaves_existing_files(tmp_path: Path) -> None:
    result = _result()
    spectral_skin.write_maps(result, tmp_path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    other = _result(oiliness_varies=False)
    bad_shape = {"albedo": other["albedo"], "radius": other["radius"][:4]}
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"radius \(4, 7\)"):
        spectral_skin.write_maps(bad_shape, tmp_path)
    with pytest.raises(spectral_skin.SpectralSkinError, match="nothing to write"):
        spectral_skin.write_maps({"specular_constants": other["specular_constants"]}, tmp_path)
    with pytest.raises(spectral_skin.SpectralSkinError, match="prefix"):
        spectral_skin.write_maps(other, tmp_path, "../x")
    with pytest.raises(TypeError, match="albedo"):
        spectral_skin.write_maps({"albedo": other["albedo"].astype(np.float16)}, tmp_path)
    # A folder that cannot be created (a file is in the way): an error naming it, nothing written anywhere.
    blocker = tmp_path / "blocker"
    blocker.write_bytes(b"")
    with pytest.raises(OSError, match="blocker") as info:  # an I/O failure: SpectralSkinIOError
        spectral_skin.write_maps(other, blocker / "sub")
    assert isinstance(info.value, spectral_skin.SpectralSkinIOError)
    assert info.value.errno in (errno.EEXIST, errno.ENOTDIR)  # the OS's code for a file in the folder's way
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name != "blocker"}
    assert after == before


def test_write_maps_releases_the_gil(tmp_path: Path, assert_releases_gil) -> None:
    result = _result()
    assert_releases_gil(lambda: spectral_skin.write_maps(result, tmp_path))
