"""help() shows each function's real documentation: it lives once, in the Rust doc comment of the #[pyfunction]
(pyo3's __doc__ and __text_signature__), and the stub (_core.pyi) holds only types and a one-line pointer."""

from __future__ import annotations

import ast
import inspect
import pydoc
from pathlib import Path

import pytest
import spectral_skin

STUB = Path(spectral_skin.__file__).resolve().parent / "_core.pyi"
FUNCTIONS = sorted(name for name in spectral_skin.__all__ if inspect.isroutine(getattr(spectral_skin, name)))
# Functions without arguments have nothing to raise on.
NO_RAISES = {"accuracy_levels", "blender_targets", "map_kinds", "parameter_ranges", "parameters", "presets",
             "surface_models",
             "transports"}


def test_every_public_function_is_checked() -> None:
    assert FUNCTIONS == ["accuracy_levels", "blender_targets", "cielab", "delta_e00", "evaluate", "fit_albedo", "fit_albedo_map",
                         "fit_spectra", "fit_spectrum", "layered_reflectance", "map_kinds", "maps",
                         "parameter_ranges", "parameters", "presets", "profile", "read_parameter_map", "shader_table",
                         "surface_albedo", "surface_brdf", "surface_input_nodes", "surface_models", "transports",
                         "write_maps", "write_shader_table"]


@pytest.mark.parametrize("name", FUNCTIONS)
def test_help_shows_the_signature_and_the_full_documentation(name: str) -> None:
    function = getattr(spectral_skin, name)
    parameters = list(inspect.signature(function).parameters)
    text = pydoc.render_doc(function, renderer=pydoc.plaintext)
    # The signature line, with every argument.
    assert f"{name}(" in text and all(p in text.split("\n\n")[1] for p in parameters), text[:400]
    doc = function.__doc__ or ""
    assert "Returns:" in doc, name
    if parameters:
        assert "Arguments:" in doc, name
        # Every argument is described (its name, then a colon, in the Arguments section).
        arguments = doc.split("Arguments:")[1].split("Returns:")[0]
        missing = [p for p in parameters if f"{p}:" not in arguments and f"{p}," not in arguments]
        assert not missing, (name, missing)
    if name not in NO_RAISES:
        assert "Raises:" in doc and "SpectralSkinError" in doc.split("Raises:")[1], name


def test_stub_holds_no_second_copy_of_the_documentation() -> None:
    tree = ast.parse(STUB.read_text())
    # The public functions (the private ``_cli_main``, the console script's entry, has its own line).
    stubs = {node.name: ast.get_docstring(node) or "" for node in tree.body
             if isinstance(node, ast.FunctionDef) and not node.name.startswith("_")}
    assert sorted(stubs) == FUNCTIONS
    for name, doc in stubs.items():
        assert "\n" not in doc and f"help(spectral_skin.{name})" in doc, (name, doc)
