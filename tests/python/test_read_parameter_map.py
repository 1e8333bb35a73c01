"""spectral_skin.read_parameter_map: parameter files read by the core's reader (the CLI's rules), checked against
files written by OpenImageIO (an independent EXR/PNG writer); and maps(progress=...)."""

from __future__ import annotations

import errno
from pathlib import Path

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

oiio = pytest.importorskip("OpenImageIO")

PARAMETERS = ("melanin", "melanin_blend", "hemoglobin", "oiliness")


def write(path: Path, pixels: np.ndarray, channels: tuple[str, ...], fmt: str = "float") -> None:
    data = np.ascontiguousarray(pixels.reshape(pixels.shape[0], pixels.shape[1], -1))
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2], fmt)
    spec.channelnames = channels
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(data), out.geterror()
    out.close()


def params(height: int = 5, width: int = 7, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    highs = np.array([spectral_skin.parameter_ranges()[p][1] for p in PARAMETERS], dtype=np.float32)
    return (rng.random((height, width, 4), dtype=np.float32) * highs).astype(np.float32)


def test_four_channel_exr(tmp_path: Path) -> None:
    values = params()
    path = tmp_path / "face.exr"
    write(path, values, PARAMETERS)
    planes = spectral_skin.read_parameter_map(path)
    assert sorted(planes) == sorted(PARAMETERS)
    for c, name in enumerate(PARAMETERS):
        assert planes[name].dtype == np.float32 and planes[name].shape == (5, 7)
        np.testing.assert_array_equal(planes[name], values[:, :, c])  # row 0 at the top, as written


def test_one_channel_exr_with_any_name(tmp_path: Path) -> None:
    values = params()[:, :, 2]
    for channel in ("hemoglobin", "Y", "blood"):
        path = tmp_path / f"{channel}.exr"
        write(path, values, (channel,))
        planes = spectral_skin.read_parameter_map(str(path), "hemoglobin")
        assert list(planes) == ["hemoglobin"]
        np.testing.assert_array_equal(planes["hemoglobin"], values)


def test_named_channel_of_the_four_channel_file(tmp_path: Path) -> None:
    values = params()
    path = tmp_path / "face.exr"
    write(path, values, PARAMETERS)
    planes = spectral_skin.read_parameter_map(path, "melanin_blend")
    np.testing.assert_array_equal(planes["melanin_blend"], values[:, :, 1])


def test_png_maps_onto_the_range(tmp_path: Path) -> None:
    grey = np.array([[0, 51], [204, 255]], dtype=np.uint8)
    path = tmp_path / "melanin.png"
    write(path, grey, ("Y",), "uint8")
    low, high = spectral_skin.parameter_ranges()["melanin"]
    planes = spectral_skin.read_parameter_map(path, "melanin")
    np.testing.assert_allclose(planes["melanin"], low + (high - low) * grey / 255.0, rtol=1e-6)


def test_grey_rgb_exr_as_blender_saves_it(tmp_path: Path) -> None:
    grey = params()[:, :, 0]
    path = tmp_path / "melanin_grey.exr"
    write(path, np.stack([grey, grey, grey], axis=-1), ("R", "G", "B"))
    planes = spectral_skin.read_parameter_map(path, "melanin")
    np.testing.assert_array_equal(planes["melanin"], grey)
    # RGBA: the alpha is ignored, with a warning naming the file.
    rgba = tmp_path / "melanin_rgba.exr"
    write(rgba, np.stack([grey, grey, grey, np.ones_like(grey)], axis=-1), ("R", "G", "B", "A"))
    with pytest.warns(spectral_skin.SpectralSkinWarning, match=r"melanin_rgba\.exr.*alpha"):
        planes = spectral_skin.read_parameter_map(rgba, "melanin")
    np.testing.assert_array_equal(planes["melanin"], grey)


def test_unknown_channel_of_a_parameter_exr_warns(tmp_path: Path) -> None:
    values = params()
    path = tmp_path / "face.exr"
    write(path, np.concatenate([values, values[:, :, :1]], axis=-1), (*PARAMETERS, "hemoglobn"))
    with pytest.warns(spectral_skin.SpectralSkinWarning, match=r"face\.exr.*hemoglobn.*melanin, melanin_blend"):
        planes = spectral_skin.read_parameter_map(path)
    np.testing.assert_array_equal(planes["hemoglobin"], values[:, :, 2])


def test_errors_name_the_file_and_channels(tmp_path: Path) -> None:
    rgb = tmp_path / "rgb.exr"
    write(rgb, params()[:, :, :3], ("R", "G", "B"))
    with pytest.raises(SpectralSkinError, match=r"rgb\.exr.*missing channels melanin.*found channels: [RGB], [RGB], [RGB]"):
        spectral_skin.read_parameter_map(rgb)
    # RGB is a parameter map only when grey (R = G = B): this one is not; the accepted forms are listed.
    with pytest.raises(SpectralSkinError, match=r"melanin map.*rgb\.exr.*found channels R, G, B that differ.*not grey"
                       r".*channel named like the parameter"):
        spectral_skin.read_parameter_map(rgb, "melanin")
    with pytest.raises(OSError, match=r"missing\.exr") as info:  # an I/O failure, not bad input
        spectral_skin.read_parameter_map(tmp_path / "missing.exr", "melanin")
    assert isinstance(info.value, spectral_skin.SpectralSkinIOError) and not isinstance(info.value, ValueError)
    # The operating system's code is kept; the message is the core's alone (no "[Errno 2]" prefix).
    assert info.value.errno == errno.ENOENT and not str(info.value).startswith("[Errno")
    with pytest.raises(SpectralSkinError, match=r'name.*melanin, melanin_blend.*"blood"'):
        spectral_skin.read_parameter_map(rgb, "blood")


def test_bad_texels_error_is_structured() -> None:
    values = params(4, 4)
    values[1, 2, 0] = 0.9
    with pytest.raises(SpectralSkinError, match="clamp=True") as info:
        spectral_skin.maps(values)
    bad = info.value.bad_texels  # type: ignore[attr-defined]
    assert bad["parameter"] == "melanin" and bad["out_of_range"] == 1 and bad["nan"] == 0
    assert bad["first"] == [(2, 1)] and (bad["min"], bad["max"]) == (0.0, 0.5)


def test_progress_reports_and_cancels() -> None:
    values = params(64, 48, seed=3)  # distinct texels: a table lookup, filled row by row
    calls: list[tuple[int, int]] = []
    spectral_skin.maps(values, progress=lambda done, total: calls.append((done, total)))
    total = 64 * 48
    # The worker threads may reach the callback out of order, but what it is told never goes backwards and ends at
    # total (a front showing the last value would otherwise stop short of 100 %).
    assert calls[0] == (0, total) and calls[-1] == (total, total)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:], strict=False))
    # About once a percent of the rows, and (0, total) about once a percent of the table's nodes if it is built.
    assert all(t == total and 0 <= d <= total for d, t in calls) and 3 <= len(calls) <= 1 + 101 + 101
    with pytest.raises(InterruptedError, match="cancelled"):
        spectral_skin.maps(values, progress=lambda done, total: done == 0)  # go on at 0, cancel at the first row
    with pytest.raises(ZeroDivisionError):
        spectral_skin.maps(values, progress=lambda done, total: 1 / 0)
    with pytest.raises(TypeError, match="progress must be a callable"):
        spectral_skin.maps(values, progress=3)  # type: ignore[arg-type]


def test_extended_channels_and_maps(tmp_path: Path) -> None:
    values = params()
    thickness = np.linspace(0.02, 0.4, 35, dtype=np.float32).reshape(5, 7)
    path = tmp_path / "face.exr"
    write(path, np.concatenate([values, thickness[:, :, None]], axis=-1), (*PARAMETERS, "epidermis_thickness_mm"))
    planes = spectral_skin.read_parameter_map(path)
    # The channel present is returned; the extended ones absent are not (maps() takes their defaults).
    assert sorted(planes) == sorted((*PARAMETERS, "epidermis_thickness_mm"))
    np.testing.assert_array_equal(planes["epidermis_thickness_mm"], thickness)
    oxygen = tmp_path / "oxygen.png"
    write(oxygen, np.array([[0, 51, 255]], dtype=np.uint8), ("Y",), "uint8")
    planes = spectral_skin.read_parameter_map(oxygen, "blood_oxygenation")
    assert list(planes) == ["blood_oxygenation"]
    np.testing.assert_allclose(planes["blood_oxygenation"], [[0.0, 0.2, 1.0]], rtol=1e-7)
    with pytest.raises(SpectralSkinError, match="blood_oxygenation"):
        spectral_skin.read_parameter_map(oxygen, "oxygen")
