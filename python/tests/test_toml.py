"""The dict-to-TOML writer World(toml=dict) and World.apply(dict) use."""
from __future__ import annotations

import tomllib

import pytest

from metariver import _toml


def test_dicts_round_trip_through_tomllib():
    scene = {"solver": "pbf", "particles": {"count": 10, "spawn_center": [1.0, 2.5, 3.0]},
             "foam": {"enabled": False}, "surface": {"smooth": {"iterations": 2}}}
    assert tomllib.loads(_toml.dumps(scene)) == scene


@pytest.mark.parametrize("bad", [{"a": float("nan")}, {"a": object()}, {1: 2}])
def test_values_toml_cannot_hold_are_refused_naming_the_key(bad):
    with pytest.raises(ValueError):
        _toml.dumps(bad)


def test_lists_of_dicts_are_arrays_of_tables():
    # a scene list ([[swe.sources]]) given as a list of dicts, read back by tomllib as the same
    scene = {"swe": {"sources": [{"shape": "line", "start": [1.0, 0.0, 2.0], "end": [5.0, 0.0, 2.0]},
                                 {"start": [3.0, 0.0, 4.0], "discharge": 2.5}]}}
    assert tomllib.loads(_toml.dumps(scene)) == scene
    with pytest.raises(ValueError, match="swe.sources"):
        _toml.dumps({"swe": {"sources": [{1: 2}]}})
