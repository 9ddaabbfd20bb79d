"""Shared pieces of the Python module's tests (run by ctest as python.pytest, with PYTHONPATH at
the build's python/ folder, TETCUT at the CLI and CGAL_DATA at Debian's libcgal-demo archive)."""

import os
import pathlib

import numpy as np
import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("TETCUT")
    if not path:
        pytest.fail("set TETCUT to the tetcut command-line tool (ctest does)")
    return pathlib.Path(path)


@pytest.fixture(scope="session")
def cgal_archive():
    path = pathlib.Path(os.environ.get("CGAL_DATA", "/usr/share/doc/libcgal-dev/data.tar.gz"))
    if not path.exists():
        pytest.fail(f"{path} is missing: install Debian's libcgal-demo (scripts/install-deps.sh does)")
    return path


def square(axis, value, lo=-0.5, hi=1.5):
    """The square {x[axis] = value} over [lo, hi]^2 in the other axes, as (V, F)."""
    others = [a for a in range(3) if a != axis]
    V = np.zeros((4, 3))
    for i, (u, v) in enumerate([(lo, lo), (hi, lo), (hi, hi), (lo, hi)]):
        V[i, axis] = value
        V[i, others[0]] = u
        V[i, others[1]] = v
    F = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    return V, F


def soup(*parts):
    """Concatenated (V, F) soups."""
    Vs, Fs, base = [], [], 0
    for V, F in parts:
        Vs.append(V)
        Fs.append(F + base)
        base += len(V)
    return np.concatenate(Vs), np.ascontiguousarray(np.concatenate(Fs), dtype=np.int32)


def figure4_planes():
    """The paper's Figure 4 cut: 16 planes x = i/17 and 16 planes y = i/17."""
    return soup(*[square(axis, i / 17) for axis in (0, 1) for i in range(1, 17)])


def tet_volumes(V, T):
    a, b, c, d = (V[T[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6
