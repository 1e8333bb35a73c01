"""spectral_skin.Maps, the result of spectral_skin.maps: its attributes, read-only arrays, mapping access (as the dict
it replaced), and ``write``, one image or a UDIM tile set staged and committed together, read back with OpenImageIO
(an independent EXR reader)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

# A UDIM tile set stacked top to bottom: tile 1001 rows 0-1, 1002 rows 2-4, 1011 rows 5-8.
TILES = [(1001, 2), (1002, 3), (1011, 4)]
HEIGHT, WIDTH = sum(rows for _, rows in TILES), 5
# Each map's one name (the output, the result's key and attribute, the file) and its file's channels.
# The default surface (measured) with a varying oiliness: the level and the Coat's two maps.
FILES = {"albedo": ("R", "G", "B"), "radius": ("R", "G", "B"), "specular": ("Y",), "coat_weight": ("Y",),
         "coat_roughness": ("Y",)}


def params(seed: int = 3, oiliness: float | None = None) -> np.ndarray:
    rng = np.random.default_rng(seed)
    planes = [rng.uniform(0.0, 0.5, (HEIGHT, WIDTH)), rng.uniform(0.0, 1.0, (HEIGHT, WIDTH)),
              rng.uniform(0.0, 0.1, (HEIGHT, WIDTH)),
              rng.uniform(0.0, 1.0, (HEIGHT, WIDTH)) if oiliness is None else np.full((HEIGHT, WIDTH), oiliness)]
    return np.stack(planes, axis=-1).astype(np.float32)


@pytest.fixture(scope="module")
def result() -> spectral_skin.Maps:
    return spectral_skin.maps(params(), exact=True)


def read(path: Path) -> tuple[tuple[str, ...], np.ndarray]:
    oiio = pytest.importorskip("OpenImageIO")
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    spec = inp.spec()
    pixels = np.asarray(inp.read_image(oiio.FLOAT))
    inp.close()
    return tuple(spec.channelnames), pixels


def as_half(a: np.ndarray) -> np.ndarray:
    """What a half-float file holds of ``a`` (rounded to nearest, as numpy rounds)."""
    return a.astype(np.float16).astype(np.float32)


def test_attributes_and_shapes(result: spectral_skin.Maps) -> None:
    assert isinstance(result, spectral_skin.Maps) and result.shape == (HEIGHT, WIDTH)
    for name, shape in (("albedo", (HEIGHT, WIDTH, 3)), ("radius", (HEIGHT, WIDTH, 3)),
                        ("specular", (HEIGHT, WIDTH)), ("coat_weight", (HEIGHT, WIDTH)),
                        ("coat_roughness", (HEIGHT, WIDTH))):
        a = getattr(result, name)
        assert isinstance(a, np.ndarray) and a.dtype == np.float32 and a.shape == shape, name
        assert a.flags["C_CONTIGUOUS"] and np.isfinite(a).all(), name
    # The oiliness varies: the per-texel level and Coat are maps, "specular_constants" holds the inputs that do not
    # depend on it.
    assert set(result.specular_constants or {}) == {"surface", "roughness", "ior", "coat_ior", "beckmann_m"}
    assert (result.report["width"], result.report["height"]) == (WIDTH, HEIGHT)
    assert result.report["strategy"]["name"] == "exact"
    assert repr(result).startswith(f"Maps({WIDTH} x {HEIGHT}, albedo, radius, specular, coat_weight, "
                                   "coat_roughness, specular_constants")
    # An output not asked for is None (and absent from the mapping); one oiliness everywhere: no level map.
    albedo = spectral_skin.maps(params(oiliness=0.3), outputs=["albedo", "specular"], exact=True)
    assert albedo.radius is None and albedo.specular is None and albedo.albedo is not None
    constants = albedo.specular_constants
    expected = spectral_skin.evaluate(preset="caucasian", oiliness=0.3, outputs=["specular"])["specular"]
    assert constants is not None and constants["specular_ior_level"] == pytest.approx(expected["specular_ior_level"])
    assert list(albedo.keys()) == ["albedo", "specular_constants", "report"]
    assert "radius" not in albedo and albedo.get("radius") is None
    with pytest.raises(KeyError, match="radius"):
        albedo["radius"]
    # The names of earlier releases are gone, not kept as second names.
    for old in ("base_color", "radius_mm", "specular_ior_level"):
        assert old not in result and not hasattr(result, old), old


def test_arrays_are_read_only(result: spectral_skin.Maps) -> None:
    """numpy refuses writes into the arrays, and refuses to make them (or a view of them) writeable again; the
    attributes cannot be assigned; the dicts are new on each access, so changing one changes nothing held."""
    for name in FILES:
        a = getattr(result, name)
        assert not a.flags["WRITEABLE"], name
        with pytest.raises(ValueError, match="read-only"):
            a[0, 0] = 1.0
        for array in (a, a[1:]):
            with pytest.raises(ValueError, match="WRITEABLE"):
                array.flags.writeable = True
        with pytest.raises(AttributeError):
            setattr(result, name, None)
        copy = np.array(a)
        copy[0, 0] = 1.0  # a copy is the caller's own
        assert getattr(result, name) is not copy
    report = result.report
    report["width"] = 0
    assert result.report["width"] == WIDTH
    assert result["albedo"] is result.albedo  # the one array, not a copy per access


def test_mapping_access_equals_the_attributes(result: spectral_skin.Maps) -> None:
    keys = [*FILES, "specular_constants", "report"]
    assert list(result.keys()) == list(result) == keys and len(result) == 7
    assert result.keys() == set(keys)  # a KeysView, as a dict's
    assert isinstance(result, Mapping)
    for key in keys:
        assert key in result
        value, attribute = result[key], getattr(result, key)
        if isinstance(value, np.ndarray):
            assert value is attribute and result.get(key) is attribute
        else:
            assert value == attribute == result.get(key)
    assert dict(result).keys() == dict(result.items()).keys() == set(keys)
    assert [k for k, _ in result.items()] == keys and len(result.values()) == 7
    assert "nothing" not in result and 3 not in result
    assert result.get("nothing") is None and result.get("nothing", 1) == 1
    for missing in ("nothing", 3):
        with pytest.raises(KeyError):
            result[missing]


def test_write_one_image_round_trips(result: spectral_skin.Maps, tmp_path: Path) -> None:
    written = result.write(tmp_path / "out", "scene_Skin")
    out = tmp_path / "out"
    assert written == {kind: out / f"scene_Skin_{kind}.exr" for kind in FILES}
    assert sorted(p.name for p in out.iterdir()) == sorted(f"scene_Skin_{kind}.exr" for kind in FILES)
    for kind, channels in FILES.items():
        names, pixels = read(written[kind])
        array = result[kind]
        assert names == channels, kind
        np.testing.assert_array_equal(pixels.reshape(array.shape), as_half(array), err_msg=kind)
    # write_maps takes the Maps itself (its held arrays) and writes the same files.
    again = spectral_skin.write_maps(result, tmp_path / "again", "scene_Skin")
    for kind, path in again.items():
        assert path.read_bytes() == written[kind].read_bytes(), kind


def test_write_a_tile_set_writes_each_tiles_rows(result: spectral_skin.Maps, tmp_path: Path) -> None:
    written = result.write(tmp_path, "Skin", tiles=TILES)
    assert written == {kind: tmp_path / f"Skin_{kind}.<UDIM>.exr" for kind in FILES}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"Skin_{kind}.{tile}.exr" for kind in FILES for tile, _ in TILES)
    first = 0
    for tile, rows in TILES:
        for kind in FILES:
            expected = result[kind][first:first + rows]
            _, pixels = read(tmp_path / f"Skin_{kind}.{tile}.exr")
            np.testing.assert_array_equal(pixels.reshape(expected.shape), as_half(expected), err_msg=f"{kind} {tile}")
        first += rows
    # The same tile set from a dict of the arrays (the add-on's call) gives the same files.
    by_dict = spectral_skin.write_maps(dict(result), tmp_path / "dict", "Skin", tiles=TILES)
    assert sorted(by_dict) == sorted(FILES)
    for kind in FILES:
        for tile, _ in TILES:
            name = f"Skin_{kind}.{tile}.exr"
            assert (tmp_path / "dict" / name).read_bytes() == (tmp_path / name).read_bytes(), name


@pytest.mark.parametrize(("tiles", "problem"), [
    ([(1001, 2), (1002, 3), (1011, 3)], "the rows add up to 8"),
    ([(1001, 2), (1002, 3), (1011, 5)], "the rows add up to 10"),
    ([(1000, 2), (1002, 3), (1011, 4)], "tile 1000 is not a UDIM tile"),
    ([(1001, 2), (2001, 3), (1011, 4)], "tile 2001 is not a UDIM tile"),
    ([(1001, 2), (1002, 3), (1001, 4)], "tile 1001 is given twice"),
    ([(1001, 0), (1002, 5), (1011, 4)], "tile 1001 has 0 rows"),
    ([], "the rows add up to 0"),
])
def test_a_bad_tile_list_is_refused_naming_tiles(result: spectral_skin.Maps, tmp_path: Path,
                                                 tiles: list[tuple[int, int]], problem: str) -> None:
    for write in (lambda: result.write(tmp_path / "out", tiles=tiles),
                  lambda: spectral_skin.write_maps(dict(result), tmp_path / "out", tiles=tiles)):
        with pytest.raises(SpectralSkinError, match=rf"invalid tiles: {problem}:.*1001 to 2000.*image's {HEIGHT}"):
            write()
    assert not (tmp_path / "out").exists()


def test_write_maps_tile_arguments(result: spectral_skin.Maps, tmp_path: Path) -> None:
    written = spectral_skin.write_maps(result, tmp_path, tile=1002)
    assert written == {kind: tmp_path / f"{kind}.1002.exr" for kind in FILES}
    with pytest.raises(SpectralSkinError, match="tile.*1001 to 2000; got -1"):
        spectral_skin.write_maps(result, tmp_path, tile=-1)
    with pytest.raises(SpectralSkinError, match="not both"):
        spectral_skin.write_maps(result, tmp_path, tile=1001, tiles=TILES)


def test_a_failed_tile_set_write_changes_nothing(result: spectral_skin.Maps, tmp_path: Path) -> None:
    """A tile set whose last tile cannot be written (a folder sits at its albedo's name): an I/O error naming it, and
    every earlier tile's files as they were (all tiles are staged before any is renamed into place), no temporaries
    left."""
    result.write(tmp_path, tiles=TILES)
    (tmp_path / "albedo.1011.exr").unlink()
    (tmp_path / "albedo.1011.exr").mkdir()
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
    other = spectral_skin.maps(params(seed=4), exact=True)
    with pytest.raises(spectral_skin.SpectralSkinIOError, match=r"albedo\.1011\.exr"):
        other.write(tmp_path, tiles=TILES)
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
    assert after == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"{kind}.{tile}.exr" for kind in FILES for tile, _ in TILES)


def test_write_releases_the_gil(result: spectral_skin.Maps, tmp_path: Path, assert_releases_gil) -> None:
    assert_releases_gil(lambda: result.write(tmp_path, tiles=TILES))


def test_map_kinds_name_every_map_a_result_holds_and_write_makes(result: spectral_skin.Maps, tmp_path: Path) -> None:
    kinds = spectral_skin.map_kinds()
    assert [k["name"] for k in kinds] == [k for k in result.keys() if k in FILES] == list(FILES)
    for kind in kinds:
        assert kind["file"] == f"{kind['name']}.exr" and tuple(kind["channels"]) == FILES[kind["name"]]
        assert kind["principled_input"] and kind["output"] in ("albedo", "radius", "specular")
        # Base Color is colour in the run's working space; every other map is data.
        assert kind["color_space"] == (None if kind["name"] == "albedo" else "Non-Color")
    assert {k["name"]: k["unit"] for k in kinds}["radius"] == "mm"
    # The output that asks for a map computes it: "specular" brings the level and the Coat's maps.
    only = spectral_skin.maps(params(), exact=True, outputs=["specular"])
    assert sorted(k for k in only.keys() if k in FILES) == sorted(k["name"] for k in kinds if k["output"] == "specular")
    written = result.write(tmp_path)
    assert {name: Path(path).name for name, path in written.items()} == {k["name"]: k["file"] for k in kinds}
