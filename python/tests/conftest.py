"""Fixtures of the metariver pytest suite: small terrains that step fast.

The library: METARIVER_LIBRARY (the ctest sets it to the build's libmetariver.so) or a
copy installed next to the package. The package: this checkout's python/ folder.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

PYTHON_DIR = Path(__file__).resolve().parents[1]
REPO = PYTHON_DIR.parent
if str(PYTHON_DIR) not in sys.path:
    sys.path.insert(0, str(PYTHON_DIR))

import metariver  # noqa: E402

# A small budget so that a frame takes milliseconds; the river sizes the rest itself.
SMALL = {"particles": {"count": 1500}}


def valley(rows: int = 72, columns: int = 40) -> np.ndarray:
    """A V-shaped valley falling along +z (rows): heights in [0.05, 0.95]."""
    z = np.linspace(0.0, 1.0, rows)[:, None]
    x = np.linspace(-1.0, 1.0, columns)[None, :]
    return (0.05 + 0.45 * (1.0 - z) + 0.45 * np.abs(x)).astype(np.float64)


@pytest.fixture
def heights() -> np.ndarray:
    return valley()


@pytest.fixture
def world(heights):
    """A river on the small valley (area_scale 1 m, height_scale 12 m), stepped 20 frames."""
    with metariver.World(heights=heights, area_scale=1.0, height_scale=12.0, toml=SMALL, threads=2) as w:
        w.step(frames=20)
        yield w
