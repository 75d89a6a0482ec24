"""Two processes committing the same group of files at once (two runs storing the same content-keyed scene): every
commit is whole, the group is never missing once committed, and no commit undoes the other's swap."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from storage import ArtifactStore
from storage.store import OLD_TAG, TMP_TAG

GROUP = "scenes/synth-000001/abc123"
FILES = ("gaussians.parquet", "nodes.parquet", "_SUCCESS.json")
COMMITS = 150


def commit_many(root: str, writer: str, n: int) -> None:
    """Once ``<root>/go`` exists, commit ``GROUP`` ``n`` times, every file of a commit holding ``<writer>-<k>``."""
    store = ArtifactStore(root)
    Path(root, f"ready-{writer}").touch()
    while not Path(root, "go").exists():
        time.sleep(0.01)
    for k in range(n):
        with store.staged_directory(GROUP) as tmp:
            for name in FILES:
                store.write_bytes(f"{tmp}/{name}", f"{writer}-{k}".encode())


def test_two_processes_committing_one_group_leave_it_whole(tmp_path):
    repo = str(Path(__file__).resolve().parents[2])
    script = "import sys; from tests.storage.test_concurrent_commits import commit_many; " \
             "commit_many(sys.argv[1], sys.argv[2], int(sys.argv[3]))"
    writers = [subprocess.Popen([sys.executable, "-c", script, str(tmp_path), name, str(COMMITS)], cwd=repo,
                                stderr=subprocess.PIPE, text=True) for name in ("a", "b")]
    store = ArtifactStore(tmp_path)
    while not all((tmp_path / f"ready-{name}").exists() for name in ("a", "b")):
        assert all(w.poll() is None for w in writers), [w.communicate()[1] for w in writers]
        time.sleep(0.05)
    (tmp_path / "go").touch()  # both start committing at once
    seen: set[str] = set()
    while any(w.poll() is None for w in writers):  # read while they write: a committed group stays whole
        if store.exists(f"{GROUP}/_SUCCESS.json"):
            try:
                contents = {store.read_bytes(f"{GROUP}/{name}").decode() for name in FILES}
            except FileNotFoundError:  # replaced between two reads: the next version is whole again
                continue
            seen |= contents
    errors = [w.communicate(timeout=300)[1] for w in writers]
    assert [w.returncode for w in writers] == [0, 0], errors
    final = {store.read_bytes(f"{GROUP}/{name}").decode() for name in FILES}
    assert len(final) == 1 and final.pop() in {f"a-{COMMITS - 1}", f"b-{COMMITS - 1}"}
    assert seen  # the reader saw committed versions while both wrote
    siblings = store.listdir("scenes/synth-000001")
    assert [s for s in siblings if TMP_TAG in s or OLD_TAG in s] == []  # nothing staged or set aside is left
