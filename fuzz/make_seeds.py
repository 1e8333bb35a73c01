"""Regenerate the committed seed corpus of the fuzz targets (fuzz/seeds/<target>/): small valid inputs written by
the project's own writers (``spectral-skin example --size 4``, ``spectral-skin maps``, the table cache of
``spectral_skin.maps``), greyscale PNG/TIFF maps (OpenImageIO: the project reads these but writes none), and byte
strings in the targets' encodings (fuzz/fuzz_targets/common.rs) for the presets' layer stacks and parameters.

    cargo build --release && .venv/bin/python fuzz/make_seeds.py

Every seed is a few hundred bytes to a few kilobytes; the whole corpus stays far under 1 MB.
"""

import math
import os
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

ROOT = Path(__file__).resolve().parent.parent
SEEDS = ROOT / "fuzz" / "seeds"
CLI = ROOT / "target" / "release" / "spectral-skin"


def write(target: str, name: str, data: bytes) -> None:
    folder = SEEDS / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data)


def run(*args: str) -> None:
    subprocess.run([str(CLI), *args], check=True, stdout=subprocess.DEVNULL)


def grey_image(path: Path, values: np.ndarray, fmt: str, channels: int = 1) -> None:
    spec = oiio.ImageSpec(values.shape[1], values.shape[0], channels, fmt)
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(values), out.geterror()
    out.close()


def param_map_seeds(tmp: Path) -> None:
    # The first byte picks the parameter: 0-3 a one-parameter file for that parameter, 4 the four-channel EXR.
    for kind in ("face", "mask", "uniform"):
        exr = tmp / f"{kind}.exr"
        run("example", "--out", str(exr), "--size", "4", "--kind", kind)
        write("param_map", f"params_{kind}.exr.seed", b"\x04" + exr.read_bytes())
    # One-channel (specular.exr: Y) and RGB (albedo.exr) EXRs from the maps writer, half/float, PIZ/ZIP/none.
    for i, (half, compression) in enumerate([(False, "piz"), (True, "zip"), (False, "none")]):
        out = tmp / f"maps{i}"
        args = ["maps", "--params", str(tmp / "face.exr"), "--out", str(out), "--compression", compression]
        run(*args, "--precision", "half" if half else "float", "--no-cache")
        write("param_map", f"specular_{compression}.exr.seed", bytes([3]) + (out / "specular.exr").read_bytes())
        if i == 0:
            write("param_map", "albedo_rgb.exr.seed", b"\x00" + (out / "albedo.exr").read_bytes())
    ramp8 = np.arange(16, dtype=np.uint8).reshape(4, 4) * 17
    ramp16 = np.arange(16, dtype=np.uint16).reshape(4, 4) * 4369
    for p, (ext, values, fmt) in enumerate(
        [("png", ramp8, "uint8"), ("png", ramp16, "uint16"), ("tif", ramp8, "uint8"), ("tif", ramp16, "uint16")]
    ):
        path = tmp / f"grey{p}.{ext}"
        grey_image(path, values, fmt)
        write("param_map", f"grey_{fmt}.{ext}.seed", bytes([p]) + path.read_bytes())
    # Greyscale + alpha (accepted) and RGB (refused).
    la = tmp / "la.png"
    grey_image(la, np.dstack([ramp8, np.full_like(ramp8, 255)]), "uint8", 2)
    write("param_map", "grey_alpha.png.seed", b"\x01" + la.read_bytes())
    rgb = tmp / "rgb.png"
    grey_image(rgb, np.dstack([ramp8] * 3), "uint8", 3)
    write("param_map", "rgb.png.seed", b"\x02" + rgb.read_bytes())


def table_cache_seeds(tmp: Path) -> None:
    # A real cache file of a 2x2x2 table (Burley, draft), from spectral_skin.maps with the cache in tmp.
    os.environ["SPECTRAL_SKIN_CACHE_DIR"] = str(tmp / "cache")
    import spectral_skin

    rng = np.random.default_rng(0)
    params = (rng.random((64, 64, 4)) * np.array([0.5, 1.0, 0.1, 1.0])).astype(np.float32)
    report = spectral_skin.maps(params, table_resolution=(2, 2, 2), accuracy="draft")["report"]
    assert report["strategy"]["name"] == "table", report["strategy"]
    (cache,) = (tmp / "cache").glob("table-*.bin")
    file = cache.read_bytes()
    # Header: mode, method (0 = burley), three axis bytes (0 -> 2 nodes), probe count (4), then 4 x 3 u16 probes.
    probes = struct.pack("<12H", *[(k * 5461) % 65536 for k in range(12)])
    write("table_cache", "table_2x2x2_file.seed", bytes([0, 0, 0, 0, 0, 4]) + probes + file)
    body = file[len(b"spectral-skin table v3\n") + 8 :]
    write("table_cache", "table_2x2x2_body.seed", bytes([1, 0, 0, 0, 0, 4]) + probes + body)
    write("table_cache", "table_2x2x2_values.seed", bytes([2, 0, 0, 0, 0, 4]) + probes + body[12:])


def log_value(v: float, lo: float, hi: float) -> bytes:
    """The encoding of Bytes::log_value (selector 0: 10^(lo + (hi - lo) u))."""
    u = round((math.log10(v) - lo) / (hi - lo) * 65535)
    return bytes([0]) + struct.pack("<H", min(max(u, 0), 65535))


def linear(v: float, lo: float, hi: float) -> bytes:
    u = round((v - lo) / (hi - lo) * 65535)
    return bytes([0]) + struct.pack("<H", min(max(u, 0), 65535))


def special(index: int) -> bytes:
    return bytes([200 + index])


def layered_seeds() -> None:
    def layer(thickness: float | None, sigma_a: float, sigma_s: float, ior: float) -> bytes:
        t = b"" if thickness is None else log_value(thickness, -14, 8)
        return t + log_value(sigma_a, -14, 8) + log_value(sigma_s, -14, 8) + linear(ior, 0.5, 4.0)

    radii = [0.001, 0.1, 1.0, 10.0]
    encoded_radii = bytes([len(radii)]) + b"".join(log_value(r, -8, 7) for r in radii)
    # Issue 10's stacks: a caucasian-like epidermis over dermis, the thin-top-layer case, the high-index case.
    stacks = {
        "two_layers": [(0.25, 0.3, 6.0, 1.4), (None, 0.2, 3.0, 1.4)],
        "holes": [(0.0134, 0.0021, 17.0, 1.39), (None, 1.64, 1.17, 1.31)],
        "one_layer": [(None, 0.01, 1.0, 1.4)],
        "three_layers": [(0.1, 1.0, 20.0, 1.45), (1.0, 0.05, 2.0, 1.38), (None, 0.2, 1.0, 1.4)],
    }
    for name, layers in stacks.items():
        data = bytes([len(layers) - 1])
        for i, (t, a, s, n) in enumerate(layers):
            last = i == len(layers) - 1
            if last:
                data += b"\x00" if t is None else b"\x01" + log_value(t, -14, 8)
                data += layer(None, a, s, n)
            else:
                data += layer(t, a, s, n)
        write("layered_reflectance", f"{name}.seed", data + encoded_radii)
    # Special values: a NaN coefficient, a subnormal one, an infinite thickness on top.
    write("layered_reflectance", "nan.seed", b"\x00\x00" + special(4) + log_value(1.0, -14, 8) + linear(1.4, 0.5, 4))
    write("layered_reflectance", "subnormal.seed", b"\x00\x00" + log_value(0.1, -14, 8) + special(5) + linear(1.4, 0.5, 4))
    write("layered_reflectance", "inf_top.seed", b"\x01" + special(2) + layer(None, 0.1, 1.0, 1.4) + b"\x00" + layer(None, 0.1, 1.0, 1.4))


def evaluate_seeds() -> None:
    presets = {"caucasian": (0.005, 0.7, 0.005, 0.3), "asian": (0.15, 0.0, 0.01, 0.3), "african": (0.5, 0.7, 0.05, 0.3)}
    for name, (m, b, h, o) in presets.items():
        params = linear(m, -0.05, 0.55) + linear(b, -0.1, 1.1) + linear(h, -0.01, 0.11) + linear(o, -0.1, 1.1)
        # Every output; the draft level; no knob overridden; Rec.709; Blender 5.3 Cycles.
        write("evaluate", f"{name}_all.seed", params + bytes([63, 0, 0, 0, 5, 3, 0]))
        # The RGB profile alone at the default level, with a profile grid of 16 radii, 1e-3 to 1e2 mm.
        grid = log_value(1e-3, -7, 5) + log_value(1e2, -7, 5) + bytes([16])
        write("evaluate", f"{name}_profile.seed", params + bytes([4, 1, 8]) + grid + bytes([0, 5, 3, 0]))
        # The same with rgb_mapping non_negative (the last byte).
        write("evaluate", f"{name}_profile_nonneg.seed", params + bytes([4, 1, 8]) + grid + bytes([0, 5, 3, 0, 1]))
    # Out of range: a melanin of NaN.
    write("evaluate", "nan_melanin.seed", special(4) + b"\x00" * 9 + bytes([1, 0, 0, 0, 5, 3, 0]))


def main() -> None:
    if not CLI.exists():
        sys.exit(f"{CLI} not found: run cargo build --release first")
    with tempfile.TemporaryDirectory() as tmp:
        param_map_seeds(Path(tmp))
        table_cache_seeds(Path(tmp))
    layered_seeds()
    evaluate_seeds()
    total = sum(f.stat().st_size for f in SEEDS.rglob("*") if f.is_file())
    print(f"{sum(1 for f in SEEDS.rglob('*') if f.is_file())} seeds, {total} bytes in {SEEDS}")


if __name__ == "__main__":
    main()
