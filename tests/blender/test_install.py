"""Installing the extension from Python, as docs/blender-addon.md ("Installing, also headless and from scripts") says:
its two Python blocks run as written there, each in a process of its own, and the second process, which installs
nothing, applies a skin. Headless, no rendering; needs the zip of scripts/build_addon.sh."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

bpy = pytest.importorskip("bpy")
import spectral_skin  # noqa: E402
from extension_process import APPLY_AND_REPORT, run_python  # noqa: E402
from extension_process import report as applied_report  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
DOC = REPO / "docs" / "blender-addon.md"
SECTION = "## Installing, also headless and from scripts"


def _doc_blocks() -> dict[str, str]:
    """The section's Python blocks, by their first line ('# Install once ...', '# In each new process.')."""
    text = DOC.read_text()
    section = text[text.index(SECTION):]
    section = section[:section.index("\n## ", len(SECTION))]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    return {block.splitlines()[0]: block for block in blocks}


def test_the_documented_install_lasts_into_a_new_process(tmp_path, extension_zip):
    blocks = _doc_blocks()
    install = next(b for first, b in blocks.items() if first.startswith("# Install once"))
    each = next(b for first, b in blocks.items() if first.startswith("# In each new process"))
    user = tmp_path / "user"
    user.mkdir()
    first = run_python(f"ZIP = {str(extension_zip)!r}\n" + install, user, tmp_path)
    assert first.returncode == 0, first.stdout + first.stderr
    assert (user / "config" / "userpref.blend").exists(), "the preferences were not saved"
    # A process that does not enable it has no add-on (the bpy module starts from factory preferences):
    # what the doc's second block is for.
    bare = run_python("import bpy\nprint(hasattr(bpy.types, 'SPECTRAL_SKIN_OT_apply'))", user, tmp_path)
    assert bare.returncode == 0 and bare.stdout.strip().splitlines()[-1] == "False", bare.stdout + bare.stderr
    report = applied_report(run_python(each + APPLY_AND_REPORT, user, tmp_path))
    assert report["result"] == ["FINISHED"]
    assert report["module"].startswith("bl_ext.user_default.spectral_skin")
    expected = spectral_skin.evaluate(preset="caucasian")["methods"]["burley"]["base_color"]
    assert report["base_color"] == pytest.approx(expected, rel=1e-6)

