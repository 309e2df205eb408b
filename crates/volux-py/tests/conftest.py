"""Fixtures of the Python package's tests: the `volux` command line the pictures are
compared with, the shared datasets (a missing one fails under VOLUX_DATA_REQUIRED=1, as in
CI), and small synthetic volumes."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]
SHARED = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def volux_cli():
    """The `volux` binary (VOLUX_CLI, else the workspace's debug build)."""
    path = os.environ.get("VOLUX_CLI") or str(REPO / "target" / "debug" / "volux")
    if not os.path.exists(path):
        pytest.fail(f"the volux command line is not built at {path} (cargo build -p volux-cli, or set VOLUX_CLI)")
    return path


def run_cli(cli, *args):
    """Runs `volux ARGS`, failing the test with its stderr when it fails."""
    r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"volux {' '.join(map(str, args))}: {r.stderr}"
    return r


@pytest.fixture
def cli(volux_cli):
    return lambda *args: run_cli(volux_cli, *args)


def shared(*parts):
    """A file of ../shared/data; missing: a failure under VOLUX_DATA_REQUIRED=1, else a
    skip (a test that skips is not a pass: CI sets the switch)."""
    path = SHARED.joinpath(*parts)
    if not path.exists():
        message = f"shared dataset missing: {path}"
        if os.environ.get("VOLUX_DATA_REQUIRED") == "1":
            pytest.fail(message)
        pytest.skip(message)
    return path


def ball(n=32, dtype=np.int16, centre=None):
    """A ball of value 1000 in a field of 0 (indexed [z, y, x], x fastest), off-centre so
    that a wrong axis order or a flipped axis shows."""
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    c = centre or (0.6 * n, 0.45 * n, 0.4 * n)  # (x, y, z)
    r = np.sqrt((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2)
    return np.where(r < 0.25 * n, 1000, 0).astype(dtype) + (x * 3).astype(dtype)


@pytest.fixture
def ball_array():
    return ball()


def cube_tets(n=4):
    """A cube of n^3 cells, each split into 6 tetrahedra (points, tets, scalars)."""
    g = np.arange(n + 1, dtype=np.float64)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    idx = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)  # noqa: E731
    tets = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                c = [idx(i + a, j + b, k + d) for d in (0, 1) for b in (0, 1) for a in (0, 1)]
                # Six tetrahedra around the diagonal c0-c7.
                for t in ((0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)):
                    tets.append([c[t[0]], c[t[1]], c[t[2]], c[t[3]]])
    scalars = (points[:, 0] + 2 * points[:, 1] + 0.5 * points[:, 2]).astype(np.float32)
    return points, np.asarray(tets, dtype=np.int64), scalars


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Under VOLUX_DATA_REQUIRED=1 (CI) a skipped test is a failure: a missing test
    library or dataset must not pass unseen."""
    outcome = yield
    report = outcome.get_result()
    if report.skipped and os.environ.get("VOLUX_DATA_REQUIRED") == "1":
        report.outcome = "failed"
        report.longrepr = f"skipped under VOLUX_DATA_REQUIRED=1: {report.longrepr}"
