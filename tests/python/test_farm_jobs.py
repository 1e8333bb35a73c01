"""The farm job definitions without a farm: the Flamenco job type compiled under Node against a stand-in of Flamenco
3's job-compiler API (tests/farm/flamenco_api.js), its task graph checked for two jobs; the Open Job Description
template validated by ``openjd check``. (``openjd run`` of the template renders in tests/blender/test_openjd.py.)

Needs ``node`` (Debian's nodejs: scripts/setup-python.sh --test installs it where missing) and ``openjd``
(openjd-cli, scripts/pins/requirements-dev.txt).
"""

from __future__ import annotations

import json
import pathlib
import shutil
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
JOB_TYPE = REPO / "farm" / "spectral_skin_render.js"
STANDIN = REPO / "tests" / "farm" / "flamenco_api.js"
TEMPLATE = REPO / "farm" / "spectral_skin_render.openjd.yaml"

SETTINGS = {"render_output_root": "/render", "render_output_path": "/render/shot/######", "format": "OPEN_EXR",
            "blendfile": "/jobs/shot/shot.blend", "reapply": False, "reapply_materials": "",
            "reapply_overrides": ""}


def _node() -> str:
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None:
        pytest.fail("node not found: bash scripts/setup-python.sh --test installs Debian's nodejs")
    return node


def _compile(tmp_path: pathlib.Path, **settings) -> subprocess.CompletedProcess:
    job = tmp_path / "job.json"
    job.write_text(json.dumps({"name": "shot", "created": "2026-12-02T00:00:00Z",
                               "settings": {**SETTINGS, **settings}}))
    return subprocess.run([_node(), str(STANDIN), str(JOB_TYPE), str(job)], capture_output=True, text=True,
                          timeout=60)


def _graph(tmp_path: pathlib.Path, **settings) -> dict:
    proc = _compile(tmp_path, **settings)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_frame_chunker_stand_in_matches_flamenco(tmp_path):
    """The stand-in's frameChunker against the chunks Flamenco's own unit test expects (js_globals_test.go,
    TestFrameChunkerHappyBlenderStyle): sorted unique frames, runs of three or more as A-B."""
    script = (f"const {{frameChunker}} = require({json.dumps(str(STANDIN))}); "
              "console.log(JSON.stringify([frameChunker('1..10,20..25,40,3..8', 4), frameChunker('1-3', 10), "
              "frameChunker(' 7 ', 1)]));")
    proc = subprocess.run([_node(), "-e", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == [["1-4", "5-8", "9,10,20,21", "22-25", "40"], ["1-3"], ["7"]]


def test_job_type_settings(tmp_path):
    job_type = _graph(tmp_path, frames="1", chunk_size=1)["job_type"]
    assert job_type["label"] == "Spectral Skin Render"
    keys = {s["key"]: s for s in job_type["settings"]}
    assert {"frames", "chunk_size", "blendfile", "reapply", "reapply_materials", "reapply_overrides",
            "render_output_path", "format"} <= set(keys)
    assert keys["chunk_size"]["type"] == "int32" and keys["reapply"]["type"] == "bool"
    assert keys["frames"]["eval"] == "f'{C.scene.frame_start}-{C.scene.frame_end}'"
    assert "eval" not in keys["blendfile"]  # Flamenco's add-on fills it with the path on the shared storage


def test_render_only_job(tmp_path):
    """Frames 1-10 in chunks of 4: three render tasks, each one blender-render of the .blend as saved, no
    dependency."""
    tasks = _graph(tmp_path, frames="1-10", chunk_size=4)["tasks"]
    assert [t["name"] for t in tasks] == ["render-1-4", "render-5-8", "render-9,10"]
    for task, frames in zip(tasks, ["1..4", "5..8", "9,10"], strict=True):
        assert task["type"] == "blender" and task["dependencies"] == []
        [command] = task["commands"]
        assert command["type"] == "blender-render"
        params = command["parameters"]
        assert params["exe"] == "{blender}" and params["exeArgs"] == "{blenderArgs}"
        assert params["blendfile"] == "/jobs/shot/shot.blend"
        assert params["args"] == ["--render-output", "/render/shot/######", "--render-format", "OPEN_EXR",
                                  "--render-frame", frames]


def test_reapply_job(tmp_path):
    """Re-apply on: one apply task (the extension's batch apply with the overrides, into a packed copy of the .blend),
    then render tasks of that copy, each depending on it."""
    tasks = _graph(tmp_path, frames="1..3,7", chunk_size=2, reapply=True, reapply_materials="Skin, Face",
                   reapply_overrides="--preset asian  --hemoglobin 0.02")["tasks"]
    assert [t["name"] for t in tasks] == ["spectral-skin-apply", "render-1,2", "render-3,7"]
    apply, *renders = tasks
    assert apply["dependencies"] == []
    [command] = apply["commands"]
    params = command["parameters"]
    assert command["type"] == "blender-render" and params["blendfile"] == "/jobs/shot/shot.blend"
    expr_flag, expr, separator, *batch_args = params["args"]
    assert (expr_flag, separator) == ("--python-expr", "--")
    compile(expr, "<apply expression>", "exec")  # valid Python
    assert ".batch" in expr and "os._exit(status)" in expr
    assert batch_args == ["apply", "/jobs/shot/shot.blend", "/jobs/shot/shot.spectral-skin.blend", "--pack",
                          "--material", "Skin", "--material", "Face", "--preset", "asian", "--hemoglobin", "0.02"]
    for task, frames in zip(renders, ["1,2", "3,7"], strict=True):
        assert task["dependencies"] == ["spectral-skin-apply"]
        params = task["commands"][0]["parameters"]
        assert params["blendfile"] == "/jobs/shot/shot.spectral-skin.blend"
        assert params["args"][-2:] == ["--render-frame", frames]


def test_bad_jobs_are_refused(tmp_path):
    for settings, message in [({"frames": "1-2", "chunk_size": 1, "reapply": True}, "at least one material"),
                              ({"frames": "1-2", "chunk_size": 0}, "chunk_size"),
                              ({"frames": "5-2", "chunk_size": 1}, "invalid range")]:
        proc = _compile(tmp_path, **settings)
        assert proc.returncode == 2 and message in proc.stderr, (settings, proc.stderr)


def _openjd() -> str:
    found = shutil.which("openjd", path=str(pathlib.Path(sys.executable).parent)) or shutil.which("openjd")
    if found is None:
        pytest.fail("openjd not found: scripts/pins/requirements-dev.txt pins openjd-cli (bash scripts/setup-python.sh "
                    "--test)")
    return found


def test_openjd_template_checks(tmp_path):
    proc = subprocess.run([_openjd(), "check", str(TEMPLATE)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "passes validation" in proc.stdout
    # And the check can fail: a template whose task range names an unknown parameter does not pass.
    broken = tmp_path / "broken.yaml"
    broken.write_text(TEMPLATE.read_text().replace("{{Param.Frames}}", "{{Param.NoSuch}}"))
    proc = subprocess.run([_openjd(), "check", str(broken)], capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
