#!/usr/bin/env python3
"""Map pipeline performance report: wall time and peak memory per strategy and size, the lookup table's build time
and measured error, and the ratio to the memory-bandwidth floor. Writes docs/maps-performance.md.

    .venv/bin/python scripts/reports/maps_report.py                 # 512, 2048, 4096, then the scale runs
    .venv/bin/python scripts/reports/maps_report.py --quick --out /tmp/report.md   # 64, 128: what CI runs

The scale runs (not with --quick): the face example at 4096² and 8192² and a UDIM set of ten 8192² tiles, wall time,
CPU time and peak memory, and `examples/maps_floor.rs` (the maps against copying the same data through the same
reader and writer) when it is built. About 15 minutes on 2 cores.

Needs the release CLI (cargo build --release; for the floor, cargo build --release --example maps_floor) and numpy (to
measure copy bandwidth). The sections of docs/maps-performance.md after the generated ones (from SECTIONS_KEPT on)
are kept as they are.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
# Cargo's target folder ($CARGO_TARGET_DIR when set, as cargo itself reads it).
TARGET = Path(os.environ.get("CARGO_TARGET_DIR") or ROOT / "target")
CLI = TARGET / "release" / "spectral-skin"
FLOOR = TARGET / "release" / "examples" / "maps_floor"
# The first heading of the hand-written sections the report keeps when it rewrites the file.
SECTIONS_KEPT = "\n## A varying epidermis thickness"


def copy_bandwidth_gb_per_s(megabytes: int = 256, repeats: int = 7) -> float:
    """Median bytes moved (read + write) per second by a large numpy copy."""
    src = np.ones(megabytes * 2**20 // 4, dtype=np.float32)
    dst = np.empty_like(src)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        np.copyto(dst, src)
        times.append(time.perf_counter() - t)
    moved = 2 * src.nbytes
    del src, dst
    return moved / statistics.median(times) / 1e9


GNU_TIME = Path("/usr/bin/time")


def run(args: list[str], env: dict[str, str]) -> tuple[float, float, float]:
    """Wall seconds, peak resident memory (MiB) and CPU seconds (user + system) of one CLI run; the last two are NaN
    without GNU time. The peak comes from GNU time's %M: a child forked from this Python process would count the
    parent's pages until it execs."""
    with tempfile.NamedTemporaryFile("r") as stats_file:
        wrapper = [str(GNU_TIME), "-f", "%M %U %S", "-o", stats_file.name] if GNU_TIME.exists() else []
        t = time.perf_counter()
        proc = subprocess.run([*wrapper, str(CLI), *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        wall = time.perf_counter() - t
        if proc.returncode != 0:
            raise SystemExit(f"spectral-skin {' '.join(args)} failed: {proc.stderr.decode()}")
        text = stats_file.read().strip()
    if not text:
        return wall, float("nan"), float("nan")
    peak_kib, user, system = text.splitlines()[-1].split()
    return wall, int(peak_kib) / 1024, float(user) + float(system)


def write_noise_params(path: Path, size: int, seed: int = 1) -> None:
    """A parameter map whose four parameters vary everywhere (uniform noise over each allowed range), written as an
    uncompressed scan-line EXR by hand (OpenEXR file layout: header attributes, offset table, one chunk per line of
    `y, size, channels in name order`), so the report needs nothing beyond numpy to make it."""
    rng = np.random.default_rng(seed)
    ranges = {"hemoglobin": 0.1, "melanin": 0.5, "melanin_blend": 1.0, "oiliness": 1.0}  # skin::params, name order

    def attribute(name: str, kind: str, value: bytes) -> bytes:
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value

    channels = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for n in ranges) + b"\0"  # 2: FLOAT
    window = struct.pack("<iiii", 0, 0, size - 1, size - 1)
    header = b"".join(
        [
            b"\x76\x2f\x31\x01" + struct.pack("<i", 2),
            attribute("channels", "chlist", channels),
            attribute("compression", "compression", b"\0"),
            attribute("dataWindow", "box2i", window),
            attribute("displayWindow", "box2i", window),
            attribute("lineOrder", "lineOrder", b"\0"),
            attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
            attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
            attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
            b"\0",
        ]
    )
    line_bytes = 4 * size * len(ranges)
    offsets = np.arange(size, dtype="<u8") * (8 + line_bytes) + len(header) + 8 * size
    rows = np.empty((size, 2 + size * len(ranges)), dtype="<f4")
    rows.view("<i4")[:, 0] = np.arange(size)
    rows.view("<i4")[:, 1] = line_bytes
    for k, top in enumerate(ranges.values()):
        rows[:, 2 + k * size : 2 + (k + 1) * size] = rng.uniform(0.0, top, (size, size))
    with path.open("wb") as f:
        f.write(header + offsets.tobytes() + rows.tobytes())


def scale_runs(tmp: Path, env: dict[str, str]) -> tuple[list[tuple], str]:
    """The face example (table cached) at 4096² and 8192² (median of 3) and a UDIM set of ten 8192² tiles (one run):
    (name, texels, wall, CPU, peak MiB, seconds) each; and the maps_floor example's table, if it is built."""
    rows = []
    for size in (4096, 8192):
        path = tmp / f"scale-{size}.exr"
        subprocess.run([str(CLI), "example", "--size", str(size), "--out", str(path)], check=True, capture_output=True)
        results = [run(["maps", "--params", str(path), "--out", str(tmp / "scale-out")], env) for _ in range(3)]
        report = json.loads((tmp / "scale-out" / "skin_maps.json").read_text())["report"]
        rows.append((f"{size}²", size * size, statistics.median(r[0] for r in results),
                     statistics.median(r[2] for r in results), max(r[1] for r in results), report["seconds"]))
    tiles = tmp / "tiles"
    tiles.mkdir()
    for tile in range(1001, 1011):
        os.link(tmp / "scale-8192.exr", tiles / f"face.{tile}.exr")
    wall, peak, cpu = run(["maps", "--params", str(tiles / "face.<UDIM>.exr"), "--out", str(tmp / "udim-out")], env)
    report = json.loads((tmp / "udim-out" / "skin_maps.json").read_text())["report"]
    rows.append(("ten 8192² UDIM tiles", 10 * 8192 * 8192, wall, cpu, peak, report["seconds"]))
    print(f"scale: {rows}", file=sys.stderr)
    floor = ""
    if FLOOR.exists():
        floor = subprocess.run([str(FLOOR), "5", "4096", "8192"], check=True, capture_output=True, text=True, env=env).stdout
    return rows, floor


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes and one repeat (CI)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "maps-performance.md")
    opts = ap.parse_args()
    sizes = [64, 128] if opts.quick else [512, 2048, 4096]
    repeats = 1 if opts.quick else 3
    exact_size = sizes[0] if opts.quick else 256
    check_samples = 200 if opts.quick else 2000
    if not CLI.exists():
        raise SystemExit(f"{CLI} is missing: run cargo build --release first")

    load_before = os.getloadavg()[0]
    bandwidth = copy_bandwidth_gb_per_s(64 if opts.quick else 256)
    gc.collect()  # children are forked from this process: keep it small so their peak memory is their own
    rows = []
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        env = dict(os.environ, SPECTRAL_SKIN_CACHE_DIR=str(tmp / "cache"))
        # Cold table: built and checked against direct evaluation at many points (64² texels, more than the
        # distinct-tuple limit, so the table strategy is used).
        subprocess.run(
            [str(CLI), "example", "--out", str(tmp / "cold.exr"), "--size", "64"],
            check=True,
            capture_output=True,
            env=env,
        )
        run(
            [
                "maps",
                "--params",
                str(tmp / "cold.exr"),
                "--out",
                str(tmp / "cold"),
                "--table-check",
                str(check_samples),
            ],
            env,
        )
        cold = json.loads((tmp / "cold" / "skin_maps.json").read_text())["report"]["strategy"]

        for size in sorted(set(sizes) | {exact_size}):
            inputs = {}
            for kind in ("uniform", "mask", "face"):
                path = tmp / f"{kind}-{size}.exr"
                subprocess.run(
                    [str(CLI), "example", "--kind", kind, "--size", str(size), "--out", str(path)],
                    check=True,
                    capture_output=True,
                )
                inputs[kind] = path
            # The face example as float samples (the example files are half floats): what a float input costs.
            inputs["face (float)"] = tmp / f"face-float-{size}.exr"
            subprocess.run(
                [
                    str(CLI),
                    "example",
                    "--size",
                    str(size),
                    "--precision",
                    "float",
                    "--out",
                    str(inputs["face (float)"]),
                ],
                check=True,
                capture_output=True,
            )
            inputs["noise"] = tmp / f"noise-{size}.exr"
            write_noise_params(inputs["noise"], size)
            # (row name, input, options, environment): the default encoding (half, auto compression) first, then the
            # previous default (float, PIZ) and the other choices that trade file size or precision for time.
            float_piz = ["--precision", "float", "--compression", "piz"]
            cases = [
                ("constant", "uniform", [], env),
                ("distinct tuples", "mask", [], env),
                ("table (cached)", "face", [], env),
                ("table (cached)", "face (float)", [], env),
                ("table (cached)", "face", ["--compression", "piz"], env),
                ("table (cached)", "face", ["--precision", "float"], env),
                ("table (cached)", "face", float_piz, env),
                ("table (cached)", "noise", [], env),
                ("table (cached)", "noise", ["--compression", "piz"], env),
                ("table (cached)", "noise", ["--precision", "float"], env),
                ("table (cached)", "noise", float_piz, env),
            ]
            if size not in sizes:
                cases = []
            if size == max(sizes):
                # Cold: an empty cache folder, so the table is built and checked as on a first run.
                for kind in ("face", "face (float)", "noise"):
                    cold_env = dict(env, SPECTRAL_SKIN_CACHE_DIR=str(tmp / f"cold-{size}-{kind}"))
                    cases.append(("table (built)", kind, [], cold_env))
            if size == exact_size:
                cases.append(("exact", "face", ["--exact"], env))
            for name, kind, extra, case_env in cases:
                out = tmp / f"out-{size}-{kind.replace(' (float)', '-float')}"
                once = name in ("exact", "table (built)")
                results = [
                    run(["maps", "--params", str(inputs[kind]), "--out", str(out), *extra], case_env)
                    for _ in range(1 if once else repeats)
                ]
                wall = statistics.median(r[0] for r in results)
                peak = max(r[1] for r in results)
                cpu = statistics.median(r[2] for r in results)
                sidecar = json.loads((out / "skin_maps.json").read_text())
                report = sidecar["report"]
                texels = size * size
                out_channels = 6 + (1 if (out / "specular.exr").exists() else 0)
                half = sidecar["encoding"]["precision"] == "half"
                out_bytes = 2 if half else 4
                moved = texels * (4 * 4 + out_bytes * out_channels)  # f32 input planes read, output planes written
                floor = moved / (bandwidth * 1e9)
                megabytes = sum(f.stat().st_size for f in out.glob("*.exr")) / 1e6
                chosen = sorted({o["compression"] for o in sidecar["outputs"].values() if "compression" in o})
                asked = sidecar["encoding"]["compression"]
                written = "/".join(c.upper() for c in chosen)
                encoding = f"{asked} ({written})" if asked == "auto" else written
                encoding += f", {sidecar['encoding']['precision']}"
                rows.append((size, kind, name, encoding, wall, cpu, peak, report["seconds"], megabytes, floor))
                print(
                    f"{size:>5} {kind:<8} {name:<16} {encoding:<12} {wall:7.2f} s  cpu {cpu:6.2f} s  {peak:5.0f} MiB  {megabytes:6.1f} MB  ratio {wall / floor:6.0f}",
                    file=sys.stderr,
                )
        scale, floor_table = ([], "") if opts.quick else scale_runs(tmp, env)
    load_after = os.getloadavg()[0]

    lines = [
        "# Map pipeline performance",
        "",
        f"Regenerate: `.venv/bin/python scripts/reports/maps_report.py` (after `cargo build --release`). Generated {time.strftime('%Y-%m-%d')} "
        f"on {os.cpu_count()} cores, load average {load_before:.1f} before and {load_after:.1f} after (other jobs share the "
        f"machine: CPU seconds, user + system, are steadier than wall times); medians of {repeats} runs of `spectral-skin "
        "maps` on the built-in examples (`spectral-skin example --kind uniform|mask|face`: half-float PIZ files), on the "
        "face example in float samples (`--precision float`, input `face (float)`) and on a noise map (all four "
        "parameters uniform random over their ranges, written by this script: nothing to compress, no two texels alike), "
        "wall time, CPU time and peak resident memory of the whole process, total size of the written EXRs.",
        "",
        f"Memory-bandwidth floor: the input (4 float planes) read once and the outputs (Base Color and Radius, 3 planes each, "
        f"plus the specular plane when oiliness varies; 4 bytes a sample, 2 in half) written once at the measured copy "
        f"bandwidth, **{bandwidth:.1f} GB/s** (numpy copy, read + write). The ratio says how far from that floor the "
        "pipeline runs (EXR decoding, compression and the model itself are on top).",
        "",
        "| size | input | strategy | encoding | wall (s) | CPU (s) | peak memory (MiB) | read / compute / write (s) | EXRs (MB) | floor (s) | wall / floor |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def find(size: int, kind: str, name: str, encoding: str) -> tuple:
        return next(r for r in rows if r[:3] == (size, kind, name) and r[3].startswith(encoding))

    for size, kind, name, encoding, wall, cpu, peak, sec, megabytes, floor in rows:
        lines.append(
            f"| {size}² | {kind} | {name} | {encoding} | {wall:.2f} | {cpu:.2f} | {peak:.0f} | {sec['read']:.2f} / "
            f"{sec['compute']:.2f} / {sec['write']:.2f} | {megabytes:.1f} | {floor:.3f} | {wall / floor:.0f} |"
        )
    err = cold.get("measured_error") or {}
    res = cold["resolution"]
    big = max(sizes)
    face, noise = find(big, "face", "table (cached)", "auto"), find(big, "noise", "table (cached)", "auto")
    face_float = find(big, "face (float)", "table (cached)", "auto")
    face_old = find(big, "face", "table (cached)", "PIZ, float")
    noise_old = find(big, "noise", "table (cached)", "PIZ, float")
    face_piz = find(big, "face", "table (cached)", "PIZ, half")
    noise_piz = find(big, "noise", "table (cached)", "PIZ, half")
    smaller, cheaper = face[8] < face_piz[8], face[5] < face_piz[5]
    zips_vs_piz = {
        (True, True): "ZIPS is smaller and cheaper",
        (True, False): "ZIPS is smaller, PIZ cheaper",
        (False, True): "ZIPS is cheaper, PIZ smaller",
        (False, False): "PIZ is smaller and cheaper in this run",
    }[(smaller, cheaper)]
    lines += [
        "",
        "## The defaults and why",
        "",
        "`spectral-skin maps` (and Python's `write_maps`) write **half floats** (`--precision half`; `float` opts out) "
        "with **automatic compression** (`--compression auto`; `piz`, `zip`, `zips`, `rle`, `none` choose one): each "
        "file's blocks are sampled (32 blocks, spread over the image) and compressed with the precision's candidate, "
        "ZIPS for half and PIZ for float; the file is written with it if the sample shrinks by at least 25 %, else "
        "uncompressed. The sidecar records the choice per file (`outputs.<file>.compression`).",
        "",
        f"At {big}²: the face example (a half-float PIZ file, as `spectral-skin example` writes it) takes {face[4]:.2f} s "
        f"wall ({face[5]:.2f} s CPU) with the table cached and {face[8]:.1f} MB of maps; the same map in float samples "
        f"(`example --precision float`, the `face (float)` rows) takes {face_float[4]:.2f} s ({face_float[5]:.2f} s CPU), "
        f"its PIZ decode and its lookup of every texel being the difference; float PIZ output, the previous default, "
        f"{face_old[4]:.2f} s ({face_old[5]:.2f} s CPU) and {face_old[8]:.1f} MB; "
        f"PIZ on half samples gives {face_piz[8]:.1f} MB in {face_piz[5]:.2f} s CPU ({zips_vs_piz}). Noise takes {noise[4]:.2f} s wall ({noise[5]:.2f} s CPU) and {noise[8]:.1f} MB, written uncompressed, "
        f"against {noise_old[4]:.2f} s ({noise_old[5]:.2f} s CPU) and {noise_old[8]:.1f} MB for float PIZ; PIZ on its "
        f"half samples would save {100 * (1 - noise_piz[8] / noise[8]):.0f} % of the size for "
        f"{noise_piz[5] - noise[5]:.2f} s more CPU, which the 25 % threshold declines. Half's rounding error (below) is "
        "a quarter of the 0.2 % the Blender render tests allow and 8 times below the table's own error; float remains "
        "for pipelines that post-process the maps.",
        "",
        "Where the time goes (`perf record -F 999 target/release/spectral-skin maps --params face.exr --out out` on the "
        "4096² face with the table cached, 2026-12-01, on the shared machine: CPU shares, not times; the read / compute / "
        "write column above gives the phases of every run). Before this round (float example, the exr crate's ZIPS "
        "encoder; 7.04 s of CPU in the previous report): decoding the float PIZ input 23 %, the lookup 27 %, ZIPS's deflate "
        "(miniz_oxide, level 4) 18 %, building the blocks for it (f16 conversion, copies) 13 %. What changed: ZIP and "
        "ZIPS blocks are built straight from the planes (f16 a row at a time) and deflated with zlib-rs at level 4 "
        "(`encode.rs`, `zip_block`: half the CPU of miniz_oxide's level 4 for about 8 % more bytes; level 1 would be a "
        "third faster again but 45 % larger); the lookup works on 64 texels of a row at a time, so the cube roots, the "
        "interpolation and the exponentials are vector loops, and a texel equal to its left neighbour is not looked up "
        "again (the same values, bit for bit: `tests/maps/maps_lookup_rows.rs`); the parameter check runs in parallel; half "
        "input is converted a row at a time; and the example is written in half floats: its PIZ decode takes about a third "
        "of the float file's CPU (the float samples' low mantissa bits are noise to PIZ's Huffman coder) and its rows repeat "
        "each tuple over about a dozen texels, so the lookup runs on a fraction of them. Now the half example's CPU goes "
        "to deflate 25 %, the PIZ decode 21 %, page faults and other kernel work (the ~700 MB of planes) 21 %, the "
        "lookup 14 %; the float input's to the PIZ decode 34 %, the lookup 24 %, the kernel 14 %, deflate 13 %.",
    ]
    lines += [
        "",
        "## Lookup table",
        "",
        f"Resolution {res['melanin']} × {res['melanin_blend']} × {res['hemoglobin']} (C_m, β_m, C_h; cube-root axes for the "
        f"concentrations), {cold['nodes']} nodes. Cold build (every node evaluated directly, in parallel): "
        f"**{cold['build_seconds']:.2f} s**; later runs read it from the cache folder (`table (cached)` rows).",
        "",
        f"Measured error against direct evaluation at {err.get('samples', 0)} points (half at cell centres, half a "
        f"low-discrepancy sequence over the whole domain): max relative **{100 * err.get('max_albedo_relative', float('nan')):.3f} %** "
        f"in albedo, **{100 * err.get('max_radius_relative', float('nan')):.3f} %** in radius, "
        f"{100 * err.get('max_base_color_relative', float('nan')):.3f} % in the method's Base Color "
        "(bounds: 0.5 % and 1 %).",
        "",
        "Half floats (`--precision half`, the default) round each sample to the nearest of 11 significant bits: a relative error of at most "
        f"2^-11 = {100 * 2.0**-11:.3f} % for values in half's normal range (6.1e-5 to 65504, where Base Color and Radius lie: "
        "reflectances of a few per cent and more, radii of tenths of a millimetre and more), "
        f"{err.get('max_albedo_relative', float('nan')) / 2.0**-11:.0f} times below the table's own albedo error above; "
        "a Specular IOR Level below 6.1e-5 (oiliness near zero) is kept to within 3e-8.",
        "",
        f"Exact mode evaluates every texel directly, as the table's cold build evaluates every node: it is run at "
        f"{exact_size}² only ({exact_size * exact_size} evaluations); time scales with the texel count.",
    ]
    if scale:
        lines += [
            "",
            "## Scale: bounded memory, flat time per texel",
            "",
            "`spectral-skin maps` decides the strategy once for the whole texture, then fills the outputs 256 rows at a "
            "time and streams each block to a writer thread per file (`src/maps/plan.rs`, `src/maps/io/encode.rs`, "
            "`ExrStream`): it holds the input planes (4 bytes a texel per varying parameter) and a few blocks of "
            "outputs, not the whole maps. A UDIM set is read a tile at a time, once for the set's summary (so it is "
            "decided as one texture) and once to write each tile: its memory is one tile's, whatever the number of "
            "tiles. Face example, table cached, default encoding:",
            "",
            "| input | texels | wall (s) | CPU (s) | peak memory (MiB) | read / compute / write (s) | CPU ns per texel |",
            "|---|---|---|---|---|---|---|",
        ]
        for name, texels, wall, cpu, peak, sec in scale:
            lines.append(f"| {name} | {texels} | {wall:.2f} | {cpu:.2f} | {peak:.0f} | {sec['read']:.2f} / "
                         f"{sec['compute']:.2f} / {sec['write']:.2f} | {1e9 * cpu / texels:.1f} |")
        if floor_table:
            lines += [
                "",
                "The maps against their copy floor (`cargo run --release --example maps_floor -- 5 4096 8192`: the same "
                "input read and checked and the same files written through the same writer, without the model; medians "
                "of 5 in one process):",
                "",
                floor_table.strip(),
            ]
    kept = ""
    if opts.out.exists() and SECTIONS_KEPT in opts.out.read_text():
        text = opts.out.read_text()
        kept = text[text.index(SECTIONS_KEPT):]
    opts.out.write_text("\n".join(lines) + "\n" + kept)
    print(f"wrote {opts.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
