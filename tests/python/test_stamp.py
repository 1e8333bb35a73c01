"""The model-version stamp through the bindings (src/python/stamp.rs; docs/tests.md, Stamped docs): what the doc
scripts call (scripts/lib/doc_stamp.py) and what a maps result records."""

from __future__ import annotations

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError, SpectralSkinIOError, _core

oiio = pytest.importorskip("OpenImageIO")


def test_model_version_is_public_and_in_a_maps_report() -> None:
    assert isinstance(spectral_skin.MODEL_VERSION, int) and spectral_skin.MODEL_VERSION >= 1
    maps = spectral_skin.maps(melanin=np.full((2, 2), 0.1, np.float32), melanin_blend=0.5, hemoglobin=0.01,
                              oiliness=0.2, accuracy="draft")
    assert maps["report"]["model_version"] == spectral_skin.MODEL_VERSION


def test_a_block_is_replaced_under_a_stamp_naming_the_model(tmp_path) -> None:
    path = tmp_path / "doc.md"
    path.write_text("intro\n<!-- BEGIN t -->\nold\n<!-- END t -->\nend\n")
    _core._write_markdown_blocks(path, "python make.py", [("t", "| a |\n")])
    stamp = _core._markdown_stamp("python make.py")
    expected = f"intro\n<!-- BEGIN t -->\n{stamp}\n| a |\n<!-- END t -->\nend\n"
    assert path.read_text() == expected
    assert f"model {spectral_skin.MODEL_VERSION}:" in stamp
    with pytest.raises(SpectralSkinError, match="BEGIN u"):
        _core._write_markdown_blocks(path, "python make.py", [("t", "other"), ("u", "x")])
    assert path.read_text() == expected


def test_a_png_is_stamped_without_changing_its_pixels(tmp_path) -> None:
    path = tmp_path / "figure.png"
    pixels = (np.arange(4 * 5 * 3, dtype=np.uint8) * 3).reshape(4, 5, 3)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(5, 4, 3, "uint8")) and out.write_image(pixels) and out.close()
    assert _core._png_stamp_version(str(path)) is None
    _core._stamp_png(str(path), "python make.py")
    assert _core._png_stamp_version(path) == spectral_skin.MODEL_VERSION
    np.testing.assert_array_equal(oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8), pixels)
    (tmp_path / "not.png").write_text("text")
    with pytest.raises(SpectralSkinIOError, match="not.png"):
        _core._stamp_png(str(tmp_path / "not.png"), "python make.py")
