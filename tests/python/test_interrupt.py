"""Long calls stop on Ctrl-C: a child process runs a long exact map, gets SIGINT, and must end with
KeyboardInterrupt within a few seconds (the work checks its cancel flag before each row)."""

import os
import signal
import subprocess
import sys
import time

import pytest


def child_script(side: int, call: str) -> str:
    """A child that builds a random side x side parameter map, prints "started", runs ``call`` on it and exits 3 on
    KeyboardInterrupt."""
    return f"""
import signal
import sys
import numpy as np
import spectral_skin
# A process started in the background of a non-interactive shell (CI runners, `cmd &`) inherits SIGINT ignored, and
# Python then installs no KeyboardInterrupt handler: put back the one an interactive session has.
signal.signal(signal.SIGINT, signal.default_int_handler)
rng = np.random.default_rng(0)
params = (rng.random(({side}, {side}, 4)) * np.array([0.5, 1.0, 0.1, 1.0])).astype(np.float32)
print("started", flush=True)
try:
    {call}
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
print("finished", flush=True)
"""


def interrupt_child(script: str, env: dict[str, str] | None = None) -> tuple[int, str, float]:
    """Run ``script`` in a child Python, send SIGINT 1.5 s after it printed "started" (well inside its call: the
    array is built before) and return its exit code, its output and the seconds it took to stop."""
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "started"
        time.sleep(1.5)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, _ = child.communicate(timeout=60)
        elapsed = time.monotonic() - sent
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    return child.returncode, out, elapsed


# 1024 x 1024 exact texels: minutes of work on a small machine.
CHILD = child_script(1024, "spectral_skin.maps(params, exact=True, table_cache=False)")


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_stops_a_long_maps_call():
    returncode, out, elapsed = interrupt_child(CHILD)
    assert returncode == 3, (returncode, out)
    assert "interrupted" in out
    assert elapsed < 5.0, f"the call took {elapsed:.1f} s to stop after SIGINT"


# 2 x 128 distinct texels at the reference level, exact (issue 38 item 2): each evaluation is a few tenths of a second,
# and the flag was read only between rows (the distinct tuples: not at all), so SIGINT was heard 52 s late.
REFERENCE_CHILD = child_script(128, "spectral_skin.maps(params[:2], exact=True, accuracy='reference', table_cache=False)")


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_stops_an_exact_reference_map_between_evaluations():
    returncode, out, elapsed = interrupt_child(REFERENCE_CHILD)
    assert returncode == 3, (returncode, out)
    assert elapsed < 5.0, f"the call took {elapsed:.1f} s to stop after SIGINT"


def test_table_resolution_is_bounded_before_allocation():
    import numpy as np
    import spectral_skin

    params = np.full((2, 2, 4), 0.05, dtype=np.float32)
    start = time.monotonic()
    with pytest.raises(spectral_skin.SpectralSkinError, match="table resolution"):
        spectral_skin.maps(params, table_resolution=(2000, 2000, 2000), table_cache=False)
    assert time.monotonic() - start < 5.0


# 64 x 64 distinct texels take the lookup table; 100^3 nodes are minutes of work on a small machine (nothing before
# the build takes 1.5 s for 4096 texels).
TABLE_CHILD = child_script(64, "spectral_skin.maps(params, table_resolution=(100, 100, 100))")


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_stops_a_table_build(tmp_path):
    returncode, out, elapsed = interrupt_child(TABLE_CHILD, dict(os.environ, SPECTRAL_SKIN_CACHE_DIR=str(tmp_path)))
    assert returncode == 3, (returncode, out)
    assert elapsed < 5.0, f"the table build took {elapsed:.1f} s to stop after SIGINT"
    assert list(tmp_path.iterdir()) == [], "a table stopped part-way was cached"


def test_progress_callback_cancels_a_table_build(tmp_path, monkeypatch):
    import numpy as np
    import spectral_skin

    monkeypatch.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path))
    rng = np.random.default_rng(1)
    params = (rng.random((64, 64, 4)) * np.array([0.5, 1.0, 0.1, 1.0])).astype(np.float32)
    calls = []

    def progress(done, total):
        calls.append((done, total))
        return len(calls) < 3  # the first call is before the work, the next ones are the build's

    start = time.monotonic()
    with pytest.raises(InterruptedError, match="cancelled"):
        spectral_skin.maps(params, table_resolution=(100, 100, 100), progress=progress)
    assert time.monotonic() - start < 10.0, "the build did not stop"
    assert all(c == (0, 64 * 64) for c in calls), calls
    assert list(tmp_path.iterdir()) == []


# Calls that ignored Ctrl-C (issue 23), each a child that runs far longer than the 1.5 s before the signal.
LONG_CALLS = {
    # 64 starts (the most, inverse::spectrum::MAX_STARTS) at 64 streams (a 4000-spectrum start table, then each
    # start's refinement): minutes; with 2000 starts it ran on for 13.8 s after SIGINT.
    "fit_spectrum": (1, "spectral_skin.fit_spectrum(np.arange(400.0, 701.0, 10.0), np.linspace(0.15, 0.45, 31), "
                        "starts=64, streams=64)"),
    # 2000 spectra with the oxygenation and epidermal blood freed (a 32 000-spectrum table, then the batch): minutes.
    "fit_spectra": (1, "spectral_skin.fit_spectra(np.arange(400.0, 701.0, 10.0), np.tile(np.linspace(0.15, 0.45, 31), "
                       "(2000, 1)), free=['melanin', 'melanin_blend', 'hemoglobin', 'blood_oxygenation', "
                       "'epidermal_hemoglobin'])"),
    # The thickness choice builds six albedo tables (about 20 s each on a small machine) before the texels' fit; the
    # table build ran on for 19 s.
    "fit_albedo_map": (64, "spectral_skin.fit_albedo_map(params[..., :3] * 0.5)"),
    # 10^5 radii at every nanometre: a minute and a half of profile; it ignored SIGINT for 90 s.
    "evaluate_profile": (1, "spectral_skin.evaluate(preset='caucasian', accuracy='reference', "
                            "outputs=('profile_spectral',), profile_count=100000)"),
    # 10^5 radii under two 0.1 um layers (their transforms reach far in frequency): about 16 s in one call (a million
    # radii, 27 s of one layer, are refused now: MAX_PROFILE_RADII).
    "layered_reflectance": (1, "spectral_skin.layered_reflectance([(1e-4, 0.01, 10.0, 1.4), (1e-4, 0.01, 10.0, 1.4), "
                               "(float('inf'), 0.01, 1.0, 1.4)], np.linspace(0.0, 50.0, 100000))"),
}


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
@pytest.mark.parametrize("name", LONG_CALLS)
def test_ctrl_c_stops_a_long_call(name):
    side, call = LONG_CALLS[name]
    returncode, out, elapsed = interrupt_child(child_script(side, call))
    assert returncode == 3, (name, returncode, out)
    assert elapsed < 5.0, f"{name} took {elapsed:.1f} s to stop after SIGINT"
