#!/usr/bin/env python3
"""Check the core's wheels and the Blender extension zips made from them, whatever platform they are for.

    .venv/bin/python scripts/check_wheels.py ARTEFACT...    # .whl and .zip files (scripts/build_addon.sh runs it)

A wheel: its name is `spectral_skin-<version>-cp311-abi3-<platform>.whl` for a known platform (below) and its WHEEL
file says the same tags; it holds one extension module, named as abi3 modules are (`_core.abi3.so`, `_core.pyd`);
and the module's binary is for that platform: the CPU, the libraries it links (the manylinux2014 list of auditwheel's
policy on Linux, where `auditwheel show` must also find it consistent with manylinux2014; python3.dll and Windows'
own DLLs on Windows, so no MinGW runtime DLL and no version-specific python3XY.dll; only /usr/lib and /System on
macOS, so no libpython), the export `PyInit__core`, the lowest macOS it loads on (not above the tag's), and on macOS
arm64 a valid ad-hoc code signature (arm64 macOS refuses to load unsigned code).
A zip: Blender's `--split-platforms` name for one platform, the add-on's tracked Python files, the manifest whose
`platforms` is that one platform and whose `wheels` names the one wheel inside (as [build.generated], which the split
build adds and Blender reads in place of the source's lists), which passes the wheel checks; and
Blender's own validator (blender_ext.py, shipped with bpy) accepts the zip.

Prints one line of facts per artefact, or its problems; exits 1 if any artefact has a problem.

The binaries are read with LIEF (ELF, PE and Mach-O alike: one maintained parser for the three formats). LIEF reads
the Mach-O code signature's bytes but does not verify them, so `code_directory_problems` below checks the ad-hoc
signature itself, as the macOS kernel does when it maps the pages: every page hash of the CodeDirectory against the
file, and the hashes of the blobs in the special slots. A maintained verifier exists (`rcodesign verify`, the
apple-codesign crate), but it is no pip package, and `cargo install` compiles some 300 crates, a quarter of an hour on
the 2-core CI machine, for a few dozen lines of hashing; tests/build/test_check_wheels.py tests this function on
signatures it makes and breaks.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import importlib.resources
import io
import json
import pathlib
import re
import struct
import subprocess
import sys
import tempfile
import tomllib
import zipfile

from packaging.utils import parse_wheel_filename

try:
    import lief
except ImportError:  # scripts/pins/requirements-dev.txt
    sys.exit("check_wheels: no lief (the binaries' reader) in this Python: bash scripts/setup-python.sh --test")
lief.logging.disable()  # its parser's notes on stderr; what the checks need is read and reported below

ROOT = pathlib.Path(__file__).resolve().parents[1]
PROJECT = "spectral_skin"
INIT = "PyInit__core"


@dataclasses.dataclass(frozen=True)
class Platform:
    blender: str  # the manifest's platform name (blender_ext.py's list)
    zip_suffix: str  # `--split-platforms` zip name: spectral_skin-<version>-<zip_suffix>.zip
    binary: str  # "elf", "pe" or "macho"
    machine: str
    macos_min: tuple[int, int] | None = None  # the tag's macOS version: the module must load there


# Wheel platform tag -> platform. A manylinux wheel carries two tags of one platform (manylinux2014 is
# manylinux_2_17).
PLATFORMS = {
    "manylinux2014_x86_64": Platform("linux-x64", "linux_x64", "elf", "x86_64"),
    "manylinux_2_17_x86_64": Platform("linux-x64", "linux_x64", "elf", "x86_64"),
    "manylinux2014_aarch64": Platform("linux-arm64", "linux_arm64", "elf", "aarch64"),
    "manylinux_2_17_aarch64": Platform("linux-arm64", "linux_arm64", "elf", "aarch64"),
    "win_amd64": Platform("windows-x64", "windows_x64", "pe", "x86_64"),
    "macosx_10_12_x86_64": Platform("macos-x64", "macos_x64", "macho", "x86_64", (10, 12)),
    "macosx_11_0_arm64": Platform("macos-arm64", "macos_arm64", "macho", "arm64", (11, 0)),
}

# DLLs every 64-bit Windows (8 and newer) has, that a Rust cdylib built by MinGW may import (kernel32, ntdll, the CRT
# msvcrt.dll, Rust std's bcryptprimitives, ws2_32 and userenv, the dirs crate's shell32 and combase ...) and the API
# sets; and the Visual C++ runtime that a wheel built by MSVC (the release workflow's) imports: CPython for Windows
# and Blender ship it beside python.exe and blender.exe, so the process that imports the module has it. Anything else,
# such as libgcc_s_seh-1.dll or libwinpthread-1.dll (the MinGW runtime, which must be linked statically), is not on
# a user's machine.
WINDOWS_SYSTEM_DLLS = {
    "advapi32.dll", "bcrypt.dll", "bcryptprimitives.dll", "combase.dll", "crypt32.dll", "gdi32.dll", "kernel32.dll",
    "msvcrt.dll", "ntdll.dll", "ole32.dll", "oleaut32.dll", "secur32.dll", "shell32.dll", "ucrtbase.dll", "user32.dll",
    "userenv.dll", "ws2_32.dll", "vcruntime140.dll", "vcruntime140_1.dll",
}
MACOS_SYSTEM_PREFIXES = ("/usr/lib/", "/System/Library/")


@dataclasses.dataclass
class Binary:
    """What the checks read from an extension module, whatever its format."""

    format: str  # "elf", "pe", "macho"
    machine: str
    libraries: list[str]
    exports: set[str]
    shared_library: bool
    macos_min: tuple[int, int] | None = None
    signature: str | None = None  # Mach-O: None unsigned, "" valid, else what is wrong with it
    signature_flags: str = ""
    # Mach-O: Python's symbols bound to a library rather than looked up in the process that loads the module
    python_bound: list[str] = dataclasses.field(default_factory=list)


# --- reading binaries (LIEF) ---------------------------------------------------------------------------------------


def text(name: str | bytes) -> str:
    """LIEF gives a name as bytes where it is not valid UTF-8."""
    return name if isinstance(name, str) else name.decode("utf-8", "replace")


def read_binary(data: bytes) -> Binary:
    with tempfile.NamedTemporaryFile(suffix=".bin") as f:
        f.write(data)
        f.flush()
        if lief.is_macho(f.name):
            fat = lief.MachO.parse(f.name)
            if fat is None or fat.size != 1:
                raise ValueError("a universal (fat) Mach-O, expected one architecture")
            macho = fat.at(0)
            assert macho is not None
            return macho_binary(macho, data)
        parsed = lief.parse(f.name)
    if isinstance(parsed, lief.ELF.Binary):
        machine = {lief.ELF.ARCH.X86_64: "x86_64", lief.ELF.ARCH.AARCH64: "aarch64"}.get(
            parsed.header.machine_type, str(parsed.header.machine_type))
        return Binary("elf", machine, [text(lib) for lib in parsed.libraries],
                      {text(f.name) for f in parsed.exported_functions},
                      parsed.header.file_type == lief.ELF.Header.FILE_TYPE.DYN)
    if isinstance(parsed, lief.PE.Binary):
        machine = {lief.PE.Header.MACHINE_TYPES.AMD64: "x86_64", lief.PE.Header.MACHINE_TYPES.ARM64: "arm64"}.get(
            parsed.header.machine, str(parsed.header.machine))
        dll = parsed.header.has_characteristic(lief.PE.Header.CHARACTERISTICS.DLL)
        return Binary("pe", machine, [text(i.name) for i in parsed.imports],
                      {text(f.name) for f in parsed.exported_functions}, dll)
    raise ValueError("not an ELF, PE or Mach-O binary")


def macho_binary(parsed: lief.MachO.Binary, data: bytes) -> Binary:
    header = parsed.header
    machine = {lief.MachO.Header.CPU_TYPE.X86_64: "x86_64", lief.MachO.Header.CPU_TYPE.ARM64: "arm64"}.get(
        header.cpu_type, str(header.cpu_type))
    # The lowest macOS: LC_BUILD_VERSION (arm64, newer linkers) or LC_VERSION_MIN_MACOSX.
    if (build := parsed.build_version) is not None:
        minos = tuple(build.minos)
    elif (version_min := parsed.version_min) is not None:
        minos = tuple(version_min.version)
    else:
        minos = (99, 0)
    shared = header.file_type in (lief.MachO.Header.FILE_TYPE.DYLIB, lief.MachO.Header.FILE_TYPE.BUNDLE)
    # The dylibs it loads (LC_LOAD_DYLIB and the like), not its own install name (LC_ID_DYLIB).
    linked = [text(lib.name) for lib in parsed.libraries if lib.command != lief.MachO.LoadCommand.TYPE.ID_DYLIB]
    binary = Binary("macho", machine, linked,
                    {text(s.name) for s in parsed.exported_symbols}, shared, (int(minos[0]), int(minos[1])))
    # An extension module finds Python's C API in the interpreter that loads it (linked with -undefined
    # dynamic_lookup: bound with the flat-lookup ordinal, -2), never in a library it names. (An undefined symbol
    # that nothing binds is never looked up.)
    two_level = lief.MachO.Header.FLAGS.TWOLEVEL in header.flags_list
    for symbol in parsed.imported_symbols:
        name = text(symbol.name)
        bound = symbol.binding_info if symbol.has_binding_info else None
        if two_level and name.lstrip("_").startswith("Py") and bound is not None and bound.library_ordinal != -2:
            binary.python_bound.append(name)
    if (sig := parsed.code_signature) is not None:
        problems, flags = code_directory_problems(data, sig.data_offset, sig.data_size)
        binary.signature = "; ".join(problems)
        binary.signature_flags = flags
    return binary


# --- the Mach-O code signature -------------------------------------------------------------------------------------

SUPERBLOB = 0xFADE0CC0  # CSMAGIC_EMBEDDED_SIGNATURE
CODEDIRECTORY = 0xFADE0C02  # CSMAGIC_CODEDIRECTORY
CS_ADHOC = 0x2
HASHES = {1: ("sha1", 20), 2: ("sha256", 32), 3: ("sha256", 20), 4: ("sha384", 48)}  # CS_HASHTYPE_*


def code_directory_problems(data: bytes, offset: int, size: int) -> tuple[list[str], str]:
    """Verify the embedded signature at data[offset:offset+size] against the file, as the kernel checks a page when
    it maps it: every CodeDirectory (the primary, slot 0, and alternates, slots 0x1000+) must hash each page of the
    file before the signature to the value stored in its code slots, and each blob of the superblob named by a
    special slot (requirements, entitlements ...) to that slot's value; an empty special slot must be all zeros.
    Returns the problems (none: valid) and the first CodeDirectory's flags in words."""
    blob = data[offset : offset + size]
    if len(blob) < 12:
        return ["signature blob truncated"], ""
    magic, length, count = struct.unpack_from(">III", blob, 0)
    if magic != SUPERBLOB:
        return [f"signature magic {magic:#x}, expected {SUPERBLOB:#x}"], ""
    if length > len(blob) or 12 + 8 * count > length:
        return [f"superblob length {length} / {count} entries past its {len(blob)} bytes"], ""
    slots = {}
    for i in range(count):
        kind, at = struct.unpack_from(">II", blob, 12 + 8 * i)
        if at + 8 > length:
            return [f"blob {kind:#x} at {at} past the superblob"], ""
        _, blob_len = struct.unpack_from(">II", blob, at)
        slots[kind] = blob[at : at + blob_len]
    directories = [kind for kind in slots if kind == 0 or 0x1000 <= kind < 0x1005]
    if not directories:
        return ["no CodeDirectory"], ""
    problems: list[str] = []
    words = ""
    for kind in sorted(directories):
        cd = slots[kind]
        if len(cd) < 44:
            problems.append(f"CodeDirectory {kind:#x} truncated")
            continue
        (cd_magic, _, version, flags, hash_offset, _ident, n_special, n_code, code_limit, hash_size, hash_type, _,
         page_log2) = struct.unpack_from(">IIIIIIIIIBBBB", cd, 0)
        if cd_magic != CODEDIRECTORY:
            problems.append(f"CodeDirectory {kind:#x}: magic {cd_magic:#x}")
            continue
        if hash_type not in HASHES or HASHES[hash_type][1] != hash_size:
            problems.append(f"CodeDirectory {kind:#x}: hash type {hash_type} of {hash_size} bytes")
            continue
        algorithm, _ = HASHES[hash_type]
        if not words:
            words = f"CodeDirectory v{version:#x}, {algorithm}, flags {flags:#x}" + (" (adhoc)" if flags & CS_ADHOC else "")
        if code_limit != offset:
            problems.append(f"CodeDirectory {kind:#x} covers {code_limit} bytes, the signature starts at {offset}")
        page = 1 << page_log2 if page_log2 else code_limit
        expected_pages = -(-code_limit // page) if page else 0
        if n_code != expected_pages:
            problems.append(f"CodeDirectory {kind:#x}: {n_code} code slots for {expected_pages} pages")
        if hash_offset + n_code * hash_size > len(cd) or hash_offset < n_special * hash_size:
            problems.append(f"CodeDirectory {kind:#x}: hash slots outside the blob")
            continue
        bad = [i for i in range(n_code)
               if hashlib.new(algorithm, data[i * page : min((i + 1) * page, code_limit)]).digest()[:hash_size]
               != cd[hash_offset + i * hash_size : hash_offset + (i + 1) * hash_size]]
        if bad:
            problems.append(f"CodeDirectory {kind:#x}: {len(bad)} of {n_code} page hashes differ (first: page {bad[0]})")
        for special in range(1, n_special + 1):
            stored = cd[hash_offset - special * hash_size : hash_offset - (special - 1) * hash_size]
            if special in slots:
                actual = hashlib.new(algorithm, slots[special]).digest()[:hash_size]
            else:
                actual = bytes(hash_size)
            if stored != actual:
                problems.append(f"CodeDirectory {kind:#x}: special slot -{special} does not match its blob")
    return problems, words


# --- the rules -----------------------------------------------------------------------------------------------------


def manylinux_libraries() -> set[str]:
    """The libraries a manylinux2014 wheel may link without shipping them: auditwheel's own policy."""
    policies = json.loads((importlib.resources.files("auditwheel.policy") / "manylinux-policy.json").read_text())
    return set(next(p for p in policies if p["name"] == "manylinux_2_17")["lib_whitelist"])


def binary_problems(binary: Binary, platform: Platform) -> list[str]:
    """What is wrong with the extension module `binary` of a wheel for `platform` (nothing: an empty list)."""
    problems = []
    if binary.format != platform.binary:
        problems.append(f"a {binary.format} binary, expected {platform.binary}")
        return problems
    if binary.machine != platform.machine:
        problems.append(f"machine {binary.machine}, expected {platform.machine}")
    if not binary.shared_library:
        problems.append("not a shared library")
    if INIT not in binary.exports and "_" + INIT not in binary.exports:
        problems.append(f"does not export {INIT}")
    libraries = [lib.lower() for lib in binary.libraries] if binary.format == "pe" else binary.libraries
    if any("python" in pathlib.PurePosixPath(lib).name and lib != "python3.dll" for lib in libraries):
        problems.append(f"links a version-specific Python: {[lib for lib in libraries if 'python' in lib]}")
    if binary.format == "elf":
        # glibc's dynamic loader (ld-linux-x86-64.so.2, which zig's glibc 2.17 link names for __tls_get_addr) is
        # part of glibc to auditwheel too, as libc.so.6 is.
        allowed = manylinux_libraries()
        other = [lib for lib in libraries if lib not in allowed and not lib.startswith("ld-linux-")]
        if other:
            problems.append(f"links libraries outside manylinux2014: {other}")
    elif binary.format == "pe":
        if "python3.dll" not in libraries:
            problems.append("does not import python3.dll (the stable ABI)")
        other = [lib for lib in libraries
                 if lib != "python3.dll" and lib not in WINDOWS_SYSTEM_DLLS and not lib.startswith(("api-ms-win-", "ext-ms-win-"))]
        if other:
            problems.append(f"imports DLLs that are not Windows' own: {other}")
    else:
        other = [lib for lib in libraries if not lib.startswith(MACOS_SYSTEM_PREFIXES)]
        if other:
            problems.append(f"links libraries outside macOS: {other}")
        if platform.macos_min is not None and binary.macos_min is not None and binary.macos_min > platform.macos_min:
            problems.append(f"needs macOS {binary.macos_min[0]}.{binary.macos_min[1]}, the tag says "
                            f"{platform.macos_min[0]}.{platform.macos_min[1]}")
        if binary.python_bound:
            problems.append(f"{len(binary.python_bound)} Python symbols bound to a library, not looked up in the "
                            f"interpreter (-undefined dynamic_lookup): {binary.python_bound[:3]}")
        if binary.signature:
            problems.append(f"invalid code signature: {binary.signature}")
        elif binary.signature is None and platform.machine == "arm64":
            problems.append("no code signature (macOS arm64 loads only signed code)")
    return problems


def describe(binary: Binary) -> str:
    shown = sorted(binary.libraries, key=str.lower)
    text = f"{binary.format} {binary.machine}, links {', '.join(shown) or 'nothing'}"
    if binary.macos_min:
        text += f", macOS >= {binary.macos_min[0]}.{binary.macos_min[1]}"
    if binary.format == "macho":
        text += ", " + ("unsigned" if binary.signature is None else f"signature valid ({binary.signature_flags})")
    return text


def wheel_problems(path: pathlib.Path, data: bytes | None = None) -> tuple[list[str], str, Platform | None]:
    """Problems of the wheel at `path` (or of `data`, a wheel named `path` read from a zip), its facts and platform."""
    try:
        name, version, _, tags = parse_wheel_filename(path.name)
    except Exception as e:  # packaging's InvalidWheelFilename and friends
        return [f"not a wheel name: {e}"], "", None
    problems = []
    if name != "spectral-skin":
        problems.append(f"project {name}")
    if {(t.interpreter, t.abi) for t in tags} != {("cp311", "abi3")}:
        problems.append(f"tags {sorted(map(str, tags))}: expected cp311-abi3 (CPython 3.11 and newer)")
    platforms = {PLATFORMS.get(t.platform) for t in tags}
    if None in platforms or len(platforms) != 1:
        return problems + [f"platform tags {sorted(t.platform for t in tags)}: expected one of {sorted(PLATFORMS)}"], "", None
    platform = platforms.pop()
    assert platform is not None
    with zipfile.ZipFile(path if data is None else io.BytesIO(data)) as wheel:
        names = wheel.namelist()
        info = f"spectral_skin-{version}.dist-info/WHEEL"
        if info not in names:
            return problems + [f"no {info}"], "", platform
        meta = wheel.read(info).decode()
        declared = set(re.findall(r"^Tag: (\S+)$", meta, re.M))
        if declared != {str(t) for t in tags}:
            problems.append(f"WHEEL says tags {sorted(declared)}, the name {sorted(map(str, tags))}")
        if "Root-Is-Purelib: false" not in meta:
            problems.append("WHEEL does not say Root-Is-Purelib: false")
        module = "spectral_skin/_core.pyd" if platform.binary == "pe" else "spectral_skin/_core.abi3.so"
        modules = [n for n in names if re.fullmatch(r"spectral_skin/_core\..*(so|pyd|dylib)", n)]
        if modules != [module]:
            problems.append(f"extension modules {modules}, expected [{module}] (an abi3 module's name)")
            return problems, "", platform
        binary_data = wheel.read(module)
    try:
        binary = read_binary(binary_data)
    except Exception as e:
        return problems + [f"{module}: cannot read: {e}"], "", platform
    problems += [f"{module}: {p}" for p in binary_problems(binary, platform)]
    if platform.binary == "elf":
        problems += auditwheel_problems(path, data)
    return problems, f"{platform.blender}: {describe(binary)}; exports {INIT}", platform


def auditwheel_problems(path: pathlib.Path, data: bytes | None) -> list[str]:
    """`auditwheel show` (symbol versions, libraries) must find the wheel consistent with manylinux2014."""
    with tempfile.TemporaryDirectory() as tmp:
        if data is not None:
            path = pathlib.Path(tmp) / path.name
            path.write_bytes(data)
        auditwheel = pathlib.Path(sys.executable).parent / "auditwheel"
        show = subprocess.run([str(auditwheel), "show", str(path)], capture_output=True, text=True)
    if show.returncode != 0:
        return [f"auditwheel show failed: {show.stderr.strip() or show.stdout.strip()}"]
    match = re.search(r'consistent with the following platform tag:\s*"manylinux_(\d+)_(\d+)_', show.stdout)
    if not match:
        return [f"auditwheel show names no manylinux tag: {' '.join(show.stdout.split())}"]
    if (int(match.group(1)), int(match.group(2))) > (2, 17):
        return [f"auditwheel: consistent only with manylinux_{match.group(1)}_{match.group(2)}, not manylinux2014"]
    return []


def tracked_addon_python() -> set[str]:
    tracked = subprocess.run(["git", "ls-files", "blender_addon/*.py"], capture_output=True, text=True, check=True,
                             cwd=ROOT).stdout
    return {p.removeprefix("blender_addon/") for p in tracked.split()}


def zip_problems(path: pathlib.Path, blender_ext: pathlib.Path | None) -> tuple[list[str], str]:
    problems = []
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
        wheels = [n for n in names if n.startswith("wheels/") and n.endswith(".whl")]
        if "blender_manifest.toml" not in names or len(wheels) != 1:
            return [f"expected blender_manifest.toml and one wheel, got {sorted(names)}"], ""
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        wheel_name = wheels[0]
        wheel_data = archive.read(wheel_name)
        python = {n for n in names if n.endswith(".py")}
    expected = tracked_addon_python()
    if expected - python:
        problems.append(f"missing the add-on's {sorted(expected - python)}")
    if python - expected:
        problems.append(f"Python files the add-on does not track: {sorted(python - expected)}")
    inner, facts, platform = wheel_problems(pathlib.Path(wheel_name), wheel_data)
    problems += [f"{wheel_name}: {p}" for p in inner]
    # `build --split-platforms` keeps the source manifest's lists and appends the zip's own as [build.generated],
    # which Blender reads in their place.
    generated = manifest.get("build", {}).get("generated", {})
    wheels, platforms = generated.get("wheels", manifest.get("wheels")), generated.get("platforms", manifest.get("platforms"))
    if wheels != [f"./{wheel_name}"]:
        problems.append(f"manifest wheels {wheels}, the zip holds {wheel_name}")
    if platform is not None:
        if platforms != [platform.blender]:
            problems.append(f"manifest platforms {platforms}, the wheel is for {platform.blender}")
        expected_name = f"{manifest.get('id')}-{manifest.get('version')}-{platform.zip_suffix}.zip"
        if path.name != expected_name:
            problems.append(f"named {path.name}, expected {expected_name}")
    if blender_ext is not None:
        validate = subprocess.run([sys.executable, str(blender_ext), "validate", str(path)], capture_output=True,
                                  text=True)
        if validate.returncode != 0:
            problems.append(f"Blender's validator: {' '.join((validate.stdout + validate.stderr).split())}")
        facts += "; Blender's validator: ok"
    return problems, f"{len(python)} Python files, {pathlib.PurePosixPath(wheel_name).name} ({facts})"


def find_blender_ext() -> pathlib.Path | None:
    """Blender's extension command line, shipped inside the bpy package (scripts/pins/requirements-dev.txt)."""
    import importlib.util

    spec = importlib.util.find_spec("bpy")
    for folder in (spec.submodule_search_locations or []) if spec else []:
        hits = sorted(pathlib.Path(folder).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
        if hits:
            return hits[-1]
    return None


def check(paths: list[pathlib.Path], blender_ext: pathlib.Path | None) -> list[str]:
    """Check each artefact, print a line per artefact; return every problem, prefixed with its artefact."""
    failures = []
    for path in paths:
        if not path.is_file():
            failures.append(f"{path}: no such file")
            continue
        if path.suffix == ".whl":
            problems, facts, _ = wheel_problems(path)
        elif path.suffix == ".zip":
            problems, facts = zip_problems(path, blender_ext)
        else:
            problems, facts = ["neither a .whl nor a .zip"], ""
        if problems:
            failures += [f"{path}: {p}" for p in problems]
            for p in problems:
                print(f"check_wheels: {path}: {p}", file=sys.stderr)
        else:
            print(f"check_wheels: {path}: ok: {facts}")
    return failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("artefacts", nargs="+", type=pathlib.Path, help=".whl and .zip files")
    parser.add_argument("--blender-ext", type=pathlib.Path,
                        help="Blender's blender_ext.py for the zips (default: the one in the bpy package)")
    parser.add_argument("--no-validator", action="store_true", help="do not run Blender's validator on the zips")
    args = parser.parse_args(argv)
    blender_ext = None
    if not args.no_validator and any(p.suffix == ".zip" for p in args.artefacts):
        blender_ext = args.blender_ext or find_blender_ext()
        if blender_ext is None:
            print("check_wheels: Blender's blender_ext.py not found: is bpy installed? "
                  "(bash scripts/setup-python.sh --test)", file=sys.stderr)
            return 2
    failures = check(args.artefacts, blender_ext)
    if failures:
        print(f"check_wheels: {len(failures)} problem(s)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
