"""Ctrl-C stops a frame (the engine's cancellation) and raises KeyboardInterrupt; a
progress callback is called while the frame draws, and an exception it raises stops it."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import volux

SLOW = textwrap.dedent(
    """
    import sys, time, numpy as np, volux
    rng = np.random.default_rng(1)
    vol = volux.Volume(rng.random((96, 96, 96), dtype=np.float32))
    print("ready", flush=True)
    t = time.time()
    try:
        volux.render(vol, size=(1024, 1024), integrator="adaptive-simpson", tol=1e-4,
                     hmin=1e-3, shade=True, tf="viridis", progress=False)
        print("finished", time.time() - t, flush=True)
    except KeyboardInterrupt:
        print("interrupted", time.time() - t, flush=True)
    """
)


@pytest.mark.skipif(os.name != "posix", reason="SIGINT")
def test_ctrl_c_cancels_a_render_promptly():
    p = subprocess.Popen([sys.executable, "-c", SLOW], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    waited = time.time() - sent
    assert out.startswith("interrupted"), (out, err)
    assert waited < 5.0, f"the frame went on {waited:.1f} s after Ctrl-C"


def test_progress_is_reported_and_a_raising_callback_stops_the_frame():
    vol = volux.Volume(np.random.default_rng(2).random((48, 48, 48), dtype=np.float32))
    calls = []
    volux.render(vol, size=(256, 256), progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1][0] == calls[-1][1] > 0

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop()

    with pytest.raises(Stop):
        volux.render(vol, size=(512, 512), integrator="adaptive-simpson", tol=1e-4, progress=stop)
