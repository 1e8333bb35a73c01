"""scripts/check_wheels.py: its rules on small fixtures (fast), then the real artefacts of scripts/build_addon.sh
(the four zips in dist/ and the wheels they were made from), each skipped when absent.

Run: .venv/bin/python -m pytest tests/build -q (scripts/test-all.sh runs it after the extension stage).
"""

from __future__ import annotations

import hashlib
import io
import pathlib
import shutil
import struct
import subprocess
import sys
import zipfile

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "scripts"))

import check_wheels as cw  # noqa: E402

VERSION = "0.1.0"
# scripts/build_addon.sh's four zips (Blender's --split-platforms names) and the wheels they hold.
ZIPS = {suffix: REPO / "dist" / f"spectral_skin-{VERSION}-{suffix}.zip"
        for suffix in ("linux_x64", "windows_x64", "macos_x64", "macos_arm64")}
WHEEL_FOLDERS = {
    "linux_x64": REPO / "target" / "wheels",
    "windows_x64": REPO / "target" / "wheels-cross" / "x86_64-pc-windows-gnu",
    "macos_x64": REPO / "target" / "wheels-cross" / "x86_64-apple-darwin",
    "macos_arm64": REPO / "target" / "wheels-cross" / "aarch64-apple-darwin",
}
BUILD = "bash scripts/build_addon.sh"


# --- the code signature check, on signatures made here -------------------------------------------------------------


def signed(code: bytes, page_log2: int = 12, requirements: bytes = b"\xfa\xde\x0c\x01\x00\x00\x00\x0c\x00\x00\x00\x00",
           flags: int = cw.CS_ADHOC) -> tuple[bytes, int, int]:
    """`code` followed by an embedded signature as ld64 and zig write one for an ad-hoc signed binary: a superblob
    with a SHA-256 CodeDirectory (slot 0) over every page of `code` and a requirements blob (slot 2, hashed into
    special slot -2). Returns the file, the signature's offset and size."""
    page = 1 << page_log2
    pages = [code[i : i + page] for i in range(0, len(code), page)]
    identifier = b"fixture\0"
    n_special = 2
    header_size = 44  # magic .. pageSize, spare2: the version 0x20001 layout (no scatter, team, exec segment)
    hash_offset = header_size + len(identifier) + n_special * 32
    special = [b"\0" * 32, hashlib.sha256(requirements).digest()]  # slot -1 (Info.plist: none), slot -2
    hashes = b"".join(reversed(special)) + b"".join(hashlib.sha256(p).digest() for p in pages)
    length = hash_offset + len(pages) * 32
    cd = struct.pack(">IIIIIIIIIBBBBI", cw.CODEDIRECTORY, length, 0x20001, flags, hash_offset, header_size,
                     n_special, len(pages), len(code), 32, 2, 0, page_log2, 0) + identifier + hashes
    assert len(cd) == length
    blobs = [(0, cd), (2, requirements)]
    at = 12 + 8 * len(blobs)
    index, body = b"", b""
    for kind, blob in blobs:
        index += struct.pack(">II", kind, at + len(body))
        body += blob
    superblob = struct.pack(">III", cw.SUPERBLOB, 12 + len(index) + len(body), len(blobs)) + index + body
    return code + superblob, len(code), len(superblob)


CODE = bytes(range(256)) * 40  # 10 240 bytes: two whole pages and a part


def test_a_valid_ad_hoc_signature_passes():
    data, offset, size = signed(CODE)
    problems, words = cw.code_directory_problems(data, offset, size)
    assert problems == []
    assert "sha256" in words and "(adhoc)" in words


def test_a_changed_page_breaks_the_signature():
    data, offset, size = signed(CODE)
    broken = bytearray(data)
    broken[4096 + 7] ^= 1  # one bit of the second page, as stripping the binary after signing would
    problems, _ = cw.code_directory_problems(bytes(broken), offset, size)
    assert problems == ["CodeDirectory 0x0: 1 of 3 page hashes differ (first: page 1)"]


def test_a_changed_requirements_blob_breaks_the_signature():
    data, offset, size = signed(CODE)
    at = data.rindex(b"\xfa\xde\x0c\x01")
    broken = data[: at + 11] + b"\x01" + data[at + 12 :]
    problems, _ = cw.code_directory_problems(broken, offset, size)
    assert problems == ["CodeDirectory 0x0: special slot -2 does not match its blob"]


def test_a_signature_that_does_not_cover_the_file_is_refused():
    data, offset, size = signed(CODE)
    # Bytes added before the signature (as appending a section would) are outside what the CodeDirectory covers.
    moved = CODE + b"\0" * 16 + data[offset:]
    problems, _ = cw.code_directory_problems(moved, offset + 16, size)
    assert "CodeDirectory 0x0 covers 10240 bytes, the signature starts at 10256" in problems


def test_garbage_is_no_signature():
    assert cw.code_directory_problems(b"\0" * 64, 0, 64)[0] == ["signature magic 0x0, expected 0xfade0cc0"]


# --- the rules on each format ---------------------------------------------------------------------------------------

WINDOWS = cw.PLATFORMS["win_amd64"]
MAC_ARM = cw.PLATFORMS["macosx_11_0_arm64"]
MAC_X64 = cw.PLATFORMS["macosx_10_12_x86_64"]
LINUX = cw.PLATFORMS["manylinux_2_17_x86_64"]
GOOD_PE = cw.Binary("pe", "x86_64", ["python3.dll", "KERNEL32.dll", "ntdll.dll", "api-ms-win-core-synch-l1-2-0.dll",
                                     "bcryptprimitives.dll", "msvcrt.dll", "WS2_32.dll", "USERENV.dll"],
                    {"PyInit__core"}, True)
GOOD_MACHO = cw.Binary("macho", "arm64", ["/usr/lib/libSystem.B.dylib", "/usr/lib/libiconv.2.dylib",
                                          "/System/Library/Frameworks/CoreFoundation.framework/CoreFoundation"],
                       {"_PyInit__core"}, True, (11, 0), signature="")
GOOD_ELF = cw.Binary("elf", "x86_64", ["libgcc_s.so.1", "libm.so.6", "libc.so.6", "libpthread.so.0", "ld-linux-x86-64.so.2"],
                     {"PyInit__core"}, True)


def replace(binary: cw.Binary, **changes) -> cw.Binary:
    import dataclasses

    return dataclasses.replace(binary, **changes)


def test_the_good_binaries_pass():
    assert cw.binary_problems(GOOD_PE, WINDOWS) == []
    msvc = replace(GOOD_PE, libraries=["python3.dll", "VCRUNTIME140.dll", "api-ms-win-crt-runtime-l1-1-0.dll",
                                       "api-ms-win-crt-math-l1-1-0.dll", "KERNEL32.dll", "ntdll.dll"])
    assert cw.binary_problems(msvc, WINDOWS) == []  # as the release workflow's MSVC build links
    assert cw.binary_problems(GOOD_MACHO, MAC_ARM) == []
    assert cw.binary_problems(replace(GOOD_MACHO, machine="x86_64", macos_min=(10, 12), signature=None), MAC_X64) == []
    assert cw.binary_problems(GOOD_ELF, LINUX) == []


@pytest.mark.parametrize("binary, platform, problem", [
    (replace(GOOD_PE, libraries=GOOD_PE.libraries + ["libgcc_s_seh-1.dll"]), WINDOWS,
     "imports DLLs that are not Windows' own: ['libgcc_s_seh-1.dll']"),
    (replace(GOOD_PE, libraries=["python311.dll", "kernel32.dll"]), WINDOWS,
     "links a version-specific Python: ['python311.dll']"),
    (replace(GOOD_PE, libraries=["kernel32.dll"]), WINDOWS, "does not import python3.dll (the stable ABI)"),
    (replace(GOOD_PE, exports={"PyInit_core"}), WINDOWS, "does not export PyInit__core"),
    (replace(GOOD_PE, machine="arm64"), WINDOWS, "machine arm64, expected x86_64"),
    (replace(GOOD_PE, shared_library=False), WINDOWS, "not a shared library"),
    (GOOD_ELF, WINDOWS, "a elf binary, expected pe"),
    (replace(GOOD_MACHO, signature=None), MAC_ARM, "no code signature (macOS arm64 loads only signed code)"),
    (replace(GOOD_MACHO, signature="CodeDirectory 0x0: 1 of 3 page hashes differ (first: page 1)"), MAC_ARM,
     "invalid code signature: CodeDirectory 0x0: 1 of 3 page hashes differ (first: page 1)"),
    (replace(GOOD_MACHO, macos_min=(13, 0)), MAC_ARM, "needs macOS 13.0, the tag says 11.0"),
    (replace(GOOD_MACHO, libraries=["/opt/homebrew/lib/libomp.dylib"]), MAC_ARM,
     "links libraries outside macOS: ['/opt/homebrew/lib/libomp.dylib']"),
    (replace(GOOD_MACHO, libraries=["/usr/lib/libSystem.B.dylib", "@rpath/libpython3.11.dylib"]), MAC_ARM,
     "links a version-specific Python: ['@rpath/libpython3.11.dylib']"),
    (replace(GOOD_MACHO, python_bound=["_PyTuple_New"]), MAC_ARM,
     "1 Python symbols bound to a library, not looked up in the interpreter (-undefined dynamic_lookup): "
     "['_PyTuple_New']"),
    (replace(GOOD_ELF, libraries=["libc.so.6", "libssl.so.3"]), LINUX,
     "links libraries outside manylinux2014: ['libssl.so.3']"),
])
def test_each_rule_names_what_is_wrong(binary, platform, problem):
    assert problem in cw.binary_problems(binary, platform)


def fixture_wheel(tmp_path: pathlib.Path, name: str, module: str, module_bytes: bytes, tags: list[str]) -> pathlib.Path:
    path = tmp_path / name
    with zipfile.ZipFile(path, "w") as wheel:
        wheel.writestr(module, module_bytes)
        wheel.writestr("spectral_skin/__init__.py", "")
        wheel.writestr(f"spectral_skin-{VERSION}.dist-info/WHEEL", "Wheel-Version: 1.0\nGenerator: fixture\n"
                       "Root-Is-Purelib: false\n" + "".join(f"Tag: {t}\n" for t in tags))
    return path


def test_wheel_names_and_metadata(tmp_path):
    not_abi3 = fixture_wheel(tmp_path, "spectral_skin-0.1.0-cp311-cp311-win_amd64.whl", "spectral_skin/_core.pyd",
                             b"", ["cp311-cp311-win_amd64"])
    problems, _, _ = cw.wheel_problems(not_abi3)
    assert "tags ['cp311-cp311-win_amd64']: expected cp311-abi3 (CPython 3.11 and newer)" in problems
    unknown = fixture_wheel(tmp_path, "spectral_skin-0.1.0-cp311-abi3-win32.whl", "spectral_skin/_core.pyd", b"",
                            ["cp311-abi3-win32"])
    assert "expected one of" in cw.wheel_problems(unknown)[0][-1]
    misnamed = fixture_wheel(tmp_path, "spectral_skin-0.1.0-cp311-abi3-win_amd64.whl",
                             "spectral_skin/_core.cp311-win_amd64.pyd", b"", ["cp311-abi3-win_amd64"])
    assert cw.wheel_problems(misnamed)[0] == [
        "extension modules ['spectral_skin/_core.cp311-win_amd64.pyd'], expected [spectral_skin/_core.pyd] "
        "(an abi3 module's name)"]
    mistagged = fixture_wheel(tmp_path, "spectral_skin-0.1.0-cp311-abi3-win_amd64.whl", "spectral_skin/_core.pyd", b"",
                              ["cp311-abi3-win32"])
    assert "WHEEL says tags ['cp311-abi3-win32'], the name ['cp311-abi3-win_amd64']" in cw.wheel_problems(mistagged)[0]


@pytest.mark.skipif(not shutil.which("x86_64-w64-mingw32-gcc"), reason="no x86_64-w64-mingw32-gcc (apt-get install gcc-mingw-w64-x86-64)")
def test_a_real_dll_that_is_no_python_module(tmp_path):
    """LIEF reads a real PE: the bcryptprimitives stand-in of the wine test is a DLL for x86-64, but no module."""
    dll = tmp_path / "bcryptprimitives.dll"
    subprocess.run(["x86_64-w64-mingw32-gcc", "-shared", "-O2", "-o", str(dll),
                    str(REPO / "tests" / "build" / "bcryptprimitives.c"), "-ladvapi32"], check=True)
    binary = cw.read_binary(dll.read_bytes())
    assert (binary.format, binary.machine, binary.shared_library) == ("pe", "x86_64", True)
    assert "ProcessPrng" in binary.exports
    wheel = fixture_wheel(tmp_path, "spectral_skin-0.1.0-cp311-abi3-win_amd64.whl", "spectral_skin/_core.pyd",
                          dll.read_bytes(), ["cp311-abi3-win_amd64"])
    problems, _, _ = cw.wheel_problems(wheel)
    assert problems == ["spectral_skin/_core.pyd: does not export PyInit__core",
                        "spectral_skin/_core.pyd: does not import python3.dll (the stable ABI)"]


# --- the built artefacts -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", sorted(ZIPS))
def test_built_zip_passes_every_check(suffix, capsys):
    """Each of scripts/build_addon.sh's zips, with its wheel and Blender's validator."""
    path = ZIPS[suffix]
    if not path.exists():
        pytest.skip(f"no {path.relative_to(REPO)}: run {BUILD}")
    blender_ext = cw.find_blender_ext()
    assert blender_ext is not None, "bpy (with blender_ext.py) is not installed: bash scripts/setup-python.sh --test"
    assert cw.check([path], blender_ext) == []
    facts = capsys.readouterr().out
    assert "Blender's validator: ok" in facts
    if suffix == "macos_arm64":
        assert "signature valid" in facts and "(adhoc)" in facts
    if suffix == "windows_x64":
        assert "python3.dll" in facts and "libgcc" not in facts and "winpthread" not in facts


@pytest.mark.parametrize("suffix", sorted(WHEEL_FOLDERS))
def test_built_wheel_passes_every_check(suffix):
    wheels = sorted(WHEEL_FOLDERS[suffix].glob("spectral_skin-*-cp311-abi3-*.whl"))
    if not wheels:
        pytest.skip(f"no wheel in {WHEEL_FOLDERS[suffix].relative_to(REPO)}: run {BUILD}")
    assert cw.check(wheels, None) == []


def test_the_zip_check_reads_the_manifest(tmp_path):
    """A zip whose manifest names another platform than its wheel's is refused (built from the Windows zip)."""
    path = ZIPS["windows_x64"]
    if not path.exists():
        pytest.skip(f"no {path.relative_to(REPO)}: run {BUILD}")
    wrong = tmp_path / path.name
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(wrong, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "blender_manifest.toml":  # the split build's [build.generated] list
                assert b'\nplatforms = ["windows-x64"]\n' in data
                data = data.replace(b'\nplatforms = ["windows-x64"]\n', b'\nplatforms = ["linux-x64"]\n')
            target.writestr(item, data)
    problems, _ = cw.zip_problems(wrong, None)
    assert problems == ["manifest platforms ['linux-x64'], the wheel is for windows-x64"]



def test_the_arm64_signature_check_sees_a_changed_byte():
    """The macOS arm64 module as built verifies; one byte changed in its code (as stripping after linking would
    change many) no longer does."""
    path = ZIPS["macos_arm64"]
    if not path.exists():
        pytest.skip(f"no {path.relative_to(REPO)}: run {BUILD}")
    with zipfile.ZipFile(path) as archive:
        wheel = next(n for n in archive.namelist() if n.endswith(".whl"))
        with zipfile.ZipFile(io.BytesIO(archive.read(wheel))) as inner:
            module = inner.read("spectral_skin/_core.abi3.so")
    binary = cw.read_binary(module)
    assert binary.signature == "" and "(adhoc)" in binary.signature_flags
    changed = bytearray(module)
    changed[0x4000 + 123] ^= 0xFF  # in the second 4 KiB page, inside __TEXT
    broken = cw.read_binary(bytes(changed))
    assert broken.signature is not None
    assert "1 of" in broken.signature and "page hashes differ (first: page 4)" in broken.signature
