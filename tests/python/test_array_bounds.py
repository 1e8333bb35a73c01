"""Every array argument is bounded from its shape before anything is copied or converted (issue 38 item 1): a
broadcast or strided view of any shape and dtype, and an endless iterable, is an error naming the argument, never an
abort or an allocation of its size.

Each argument runs in a child Python whose address space is capped at 3 GiB (``RLIMIT_AS``): a copy of any of these
arrays (10^11 or more elements) cannot be allocated there, so a copy before the check aborts the child (Rust's
allocation failure), which fails the test with the child's output, instead of swapping the machine."""

import json
import subprocess
import sys
import textwrap

import pytest

# Huge views of each rank (elements: 10^11, 10^12, 3 x 10^12 and 10^11 along the channel axis), in four dtypes, plain
# (stride 0) and reversed (a negative stride).
CHILD_PRELUDE = """
import itertools
import json
import resource
import numpy as np
import spectral_skin

resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
SHAPES = {1: [(10**11,)], 2: [(10**6, 10**6), (1, 10**11)], 3: [(10**6, 10**6, 3), (1, 1, 10**11)]}
DTYPES = [np.float64, np.float32, np.int64, np.bool_]


def views(*ranks):
    for rank in ranks:
        for shape in SHAPES[rank]:
            for dtype in DTYPES:
                base = np.broadcast_to(np.zeros((), dtype=dtype), shape)
                yield f"{np.dtype(dtype).name}{shape}", base
                yield f"{np.dtype(dtype).name}{shape}[::-1]", base[::-1]


results = []


def check(label, call):
    try:
        call()
    except (spectral_skin.SpectralSkinError, TypeError) as e:
        results.append([label, type(e).__name__, str(e)])
    else:
        results.append([label, "no error", ""])
"""

SEMI = "[(float('inf'), 0.1, 1.0, 1.4)]"
ALBEDO = "np.full((2, 2, 3), 0.3, dtype=np.float32)"
WAVELENGTHS = "np.linspace(400.0, 700.0, 31)"
# The argument's name (as the message must name it), the ranks to try, and the call with the view as `a`.
ARGUMENTS = {
    "radii_mm": ([1, 2, 3], f"spectral_skin.layered_reflectance({SEMI}, a)"),
    "layers": ([1, 2], "spectral_skin.layered_reflectance(a, [1.0])"),
    "wavelengths_nm": ([1, 2], "spectral_skin.fit_spectrum(a, [0.1, 0.2, 0.3])"),
    "reflectance": ([1, 2], f"spectral_skin.fit_spectrum({WAVELENGTHS}, a)"),
    "reflectances": ([1, 2, 3], f"spectral_skin.fit_spectra({WAVELENGTHS}, a)"),
    "rgb": ([1, 2], "spectral_skin.fit_albedo(a)"),
    "rgb_gains": ([1, 2], "spectral_skin.fit_albedo([0.3, 0.2, 0.1], rgb_gains=a)"),
    "mask": ([2, 3], f"spectral_skin.fit_albedo_map({ALBEDO}, mask=a)"),
    "albedo": ([3], "spectral_skin.fit_albedo_map(a)"),
    "params": ([3], "spectral_skin.maps(a)"),
    "melanin": ([2], "spectral_skin.maps(melanin=a, melanin_blend=0.5, hemoglobin=0.01, oiliness=0.3)"),
    'result["albedo"]': ([3], "spectral_skin.write_maps({'albedo': a}, OUT)"),
    'result["specular"]': ([2], "spectral_skin.write_maps({'specular': a}, OUT)"),
    "rgb ": ([1, 2, 3], "spectral_skin.cielab(a)"),
    "reference": ([1, 2, 3], "spectral_skin.delta_e00(a, [0.3, 0.2, 0.1])"),
    "theta_in_deg": ([1, 2, 3], "spectral_skin.surface_brdf(a, 30.0)"),
}
# Endless iterables, where the argument takes a sequence: read up to the limit, then refused.
ENDLESS = {
    "radii_mm": f"spectral_skin.layered_reflectance({SEMI}, itertools.repeat(1.0))",
    "layers": "spectral_skin.layered_reflectance(itertools.repeat((float('inf'), 0.1, 1.0, 1.4)), [1.0])",
    "layers[0]": "spectral_skin.layered_reflectance([itertools.repeat(1.0)], [1.0])",
    "wavelengths_nm": "spectral_skin.fit_spectrum(itertools.count(400.0), [0.1, 0.2, 0.3])",
    "reflectances": f"spectral_skin.fit_spectra({WAVELENGTHS}, itertools.repeat([0.1, 0.2] * 15 + [0.3]))",
    "reflectances[0]": f"spectral_skin.fit_spectra({WAVELENGTHS}, [itertools.repeat(0.1)])",
    "rgb_gains": "spectral_skin.fit_albedo([0.3, 0.2, 0.1], rgb_gains=itertools.repeat(1.0))",
    "blender": "spectral_skin.evaluate(preset='asian', blender=itertools.repeat(5))",
    "table_resolution": "spectral_skin.maps(melanin=np.zeros((2, 2), np.float32), melanin_blend=0.5, "
    "hemoglobin=0.01, oiliness=0.3, table_resolution=itertools.repeat(3))",
}


def run_child(body: str, tmp_path) -> list[list[str]]:
    script = CHILD_PRELUDE + f"OUT = {str(tmp_path)!r}\n" + textwrap.dedent(body) + "\nprint(json.dumps(results))\n"
    child = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert child.returncode == 0, f"the child ended with {child.returncode}:\n{child.stderr[-3000:]}"
    return json.loads(child.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("name", list(ARGUMENTS))
def test_huge_array_views_are_refused_before_any_copy(name, tmp_path):
    ranks, call = ARGUMENTS[name]
    body = f"for label, a in views(*{ranks!r}):\n    check(label, lambda a=a: {call})\n"
    results = run_child(body, tmp_path)
    assert results, "no case ran"
    for label, kind, message in results:
        assert kind != "no error", f"{name} {label} was accepted"
        assert name.strip() in message, f"{name} {label}: {kind}: {message}"


@pytest.mark.parametrize("name", list(ENDLESS))
def test_endless_iterables_are_refused(name, tmp_path):
    results = run_child(f"check('endless', lambda: {ENDLESS[name]})\n", tmp_path)
    [[_, kind, message]] = results
    assert kind == "SpectralSkinError", (kind, message)
    assert name in message and "at most" in message, message


def test_layers_beyond_the_limit_are_refused_before_any_work():
    """issue 38 item 2: 10^6 layers took 80 s to stop after Ctrl-C; a stack has at most 16 layers
    (``accuracy::MAX_LAYERS``), and 17 is an error naming the layers and the limit, 16 is computed."""
    import spectral_skin

    layer = (1.0, 0.01, 1.0, 1.4)

    total, _ = spectral_skin.layered_reflectance([layer] * 15 + [(float("inf"), 0.01, 1.0, 1.4)], [1.0])
    assert 0.0 < total < 1.0
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"layers.*at most 16 layers"):
        spectral_skin.layered_reflectance([layer] * 16 + [(float("inf"), 0.01, 1.0, 1.4)], [1.0])


# The conversions that take an array argument in the module's source (src/python): each literal name given to one
# of them is an argument above, so a new array argument cannot arrive untested. Names built at run time (a map's
# parameter, a result's entry, a colour argument) are each tested above by one instance.
ARRAY_CONVERSIONS = ("real_vector", "real_sequence", "float_array", "check_array_size")


def test_every_array_argument_in_the_source_is_tried():
    import pathlib
    import re

    source = pathlib.Path(__file__).resolve().parents[2] / "src" / "python"
    call = re.compile(r"\b(?:" + "|".join(ARRAY_CONVERSIONS) + r")\(\s*\"([^\"]+)\"")
    names = {m.group(1) for path in source.glob("*.rs") for m in call.finditer(path.read_text(encoding="utf-8"))}
    assert len(names) >= 6, names  # the scan finds the conversions it is meant to
    tried = {name.strip() for name in ARGUMENTS} | set(ENDLESS)
    assert names <= tried, f"array arguments not tried with huge views: {sorted(names - tried)}"
