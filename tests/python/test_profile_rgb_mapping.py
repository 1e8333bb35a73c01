"""profile(rgb_mapping=...): the linear RGB profile is negative where the light is out of gamut (every preset's tail);
"non_negative" never is, keeps each radius's luminance, and leaves in-gamut radii unchanged. The luminance reference
is Rec.709's published row (Lindbloom's sRGB-to-XYZ matrix, D65), independent of the core's matrices."""

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

LUMA = np.array([0.2126729, 0.7151522, 0.0721750])


@pytest.mark.parametrize("preset", ["caucasian", "asian", "african"])
def test_non_negative_mapping(preset):
    linear = spectral_skin.profile(preset=preset)["rgb_per_mm2"]
    mapped = spectral_skin.profile(preset=preset, rgb_mapping="non_negative")["rgb_per_mm2"]
    out = (linear < 0).any(axis=1)
    assert out.any(), "the default grid reaches the out-of-gamut tail"
    assert (mapped >= 0).all()
    np.testing.assert_array_equal(mapped[~out], linear[~out])
    assert (mapped[out].min(axis=1) == 0).all(), "moved only as far as the gamut boundary"
    tolerance = 2e-4 * np.abs(linear[out]).sum(axis=1)
    assert (np.abs(mapped[out] @ LUMA - linear[out] @ LUMA) <= tolerance).all()


def test_rgb_mapping_names_and_types():
    ev = spectral_skin.evaluate(preset="african", outputs=("profile_rgb",), rgb_mapping="non_negative")
    assert (ev["profile"]["rgb_per_mm2"] >= 0).all()
    with pytest.raises(SpectralSkinError, match="rgb_mapping"):
        spectral_skin.profile(preset="asian", rgb_mapping="clip")
    with pytest.raises(TypeError, match="rgb_mapping"):
        spectral_skin.profile(preset="asian", rgb_mapping=True)
