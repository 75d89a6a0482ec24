"""Content keys and completion markers."""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np
import pytest

from storage import ArtifactStore, content_key, is_done, mark_done, read_marker


@dataclasses.dataclass(frozen=True)
class Config:
    lr: float = 1e-3
    steps: int = 100
    name: str = "a"


BASE = (Config(), {"b": [1, 2.5, None], "a": "x"}, np.arange(6, dtype=np.float32).reshape(2, 3), b"raw", "s")


def test_same_inputs_same_key() -> None:
    again = (Config(), {"a": "x", "b": [1, 2.5, None]}, np.arange(6, dtype=np.float32).reshape(2, 3), b"raw", "s")
    assert content_key(*BASE) == content_key(*again)
    assert len(content_key(*BASE)) == 64
    assert content_key(np.arange(3)[::-1]) == content_key(np.array([2, 1, 0]))  # layout-independent
    assert content_key(pathlib.Path("a/b"), {1, 2}) == content_key(pathlib.PurePosixPath("a/b"), {2, 1})


@pytest.mark.parametrize(
    "changed",
    [
        (Config(lr=2e-3), *BASE[1:]),
        (Config(name="b"), *BASE[1:]),
        (BASE[0], {"b": [1, 2.5, None], "a": "y"}, *BASE[2:]),
        (BASE[0], {"b": [1, 2.5], "a": "x"}, *BASE[2:]),
        (*BASE[:2], np.arange(6, dtype=np.float64).reshape(2, 3), *BASE[3:]),  # dtype
        (*BASE[:2], np.arange(6, dtype=np.float32).reshape(3, 2), *BASE[3:]),  # shape
        (*BASE[:2], np.arange(1, 7, dtype=np.float32).reshape(2, 3), *BASE[3:]),  # values
        (*BASE[:3], b"raw!", "s"),
        (*BASE[:4], "t"),
        BASE[:4],  # fewer parts
        (*BASE, None),
    ],
)
def test_any_change_changes_key(changed: tuple) -> None:
    assert content_key(*changed) != content_key(*BASE)


def test_type_distinctions() -> None:
    assert content_key(1) != content_key(1.0) != content_key("1") != content_key(True)
    assert content_key([1, 2]) != content_key([[1, 2]])


def test_unhashable_inputs_raise() -> None:
    with pytest.raises(TypeError, match="dict keys"):
        content_key({1: "a"})
    with pytest.raises(TypeError, match="cannot hash"):
        content_key(object())


def test_markers(store: ArtifactStore) -> None:
    key = content_key("inputs", Config())
    assert not is_done(store, "scenes/s0/h", key)
    with store.staged_directory("scenes/s0/h") as tmp:
        store.write_bytes(f"{tmp}/out.bin", b"x")
        mark_done(store, tmp, key, {"rows": 3})
    assert is_done(store, "scenes/s0/h", key)
    assert not is_done(store, "scenes/s0/h", content_key("inputs", Config(steps=101)))
    marker = read_marker(store, "scenes/s0/h")
    assert {k: v for k, v in marker.items() if k != "integrity"} == {"key": key, "rows": 3}
    assert marker["integrity"]["files"]["out.bin"]["bytes"] == 1  # sealed: storage.integrity
    store.write_bytes("scenes/s0/h/_SUCCESS.json", b"{truncated")
    assert not is_done(store, "scenes/s0/h", key)  # unreadable marker = not done
    with pytest.raises(ValueError, match="reserved"):
        mark_done(store, "x", key, {"key": "other"})
