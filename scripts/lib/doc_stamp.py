"""The model-version stamp of the docs and figures a script writes (the core's, src/stamp.rs, through the Python
binding): a doc written whole starts with :func:`stamp`, a block of a hand-written doc is replaced by
:func:`write_blocks`, a picture gets :func:`stamp_png`. tests/physics/doc_stamps.rs fails when one is older than the
model (docs/tests.md, Stamped docs)."""

from __future__ import annotations

import os
import sys
import textwrap
from collections.abc import Iterable, Sequence
from pathlib import Path

from spectral_skin import _core

ROOT = Path(__file__).resolve().parents[2]


def command(script_file: str, *args: str, python: str = ".venv/bin/python") -> str:
    """The command that reruns the script ``script_file`` (its ``__file__``) with ``args``, as a doc names it."""
    script = Path(script_file).resolve().relative_to(ROOT).as_posix()
    return " ".join([python, script, *args])


def stamp(cmd: str) -> str:
    """The stamp line of a doc written whole by ``cmd`` (put it on the doc's first line)."""
    return _core._markdown_stamp(cmd)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    """A Markdown table of ``rows`` under ``header``."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def paragraph(text: str) -> str:
    """``text`` wrapped at the docs' 120 columns, words and hyphenated names kept whole."""
    return textwrap.fill(text, width=120, break_long_words=False, break_on_hyphens=False)


def write_blocks(path: Path, cmd: str, blocks: dict[str, str]) -> None:
    """Replaces the blocks ``{name: body}`` of the doc at ``path``, each under the stamp of ``cmd``, in one atomic
    write (the core's ``stamp::write_markdown_blocks``)."""
    _core._write_markdown_blocks(str(path), cmd, list(blocks.items()))


def write_text(path: Path, text: str) -> None:
    """``text`` written to ``path`` through a temporary file beside it, renamed over it (never half a doc)."""
    staged = path.with_name(path.name + ".tmp")
    staged.write_text(text, encoding="utf-8")
    os.replace(staged, path)


def stamp_png(path: Path, cmd: str) -> None:
    """Stamps the picture at ``path`` as written by ``cmd`` from this model (its pixels unchanged)."""
    _core._stamp_png(str(path), cmd)


if __name__ == "__main__":  # pragma: no cover - a look at a picture's stamp
    for arg in sys.argv[1:]:
        print(arg, _core._png_stamp_version(arg))
