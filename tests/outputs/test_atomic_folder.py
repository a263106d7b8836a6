"""Output folders are written beside the target and moved into place at the end: a refused
folder is refused before the work, an overwrite leaves no stale file, and a failure or a
kill midway leaves the target as it was."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from casflutter._outputs import (INCOMPLETE_TAG, MANIFEST_NAME, atomic_file, atomic_folder,
                                 config_hash, thread_settings, write_manifest)
from casflutter.errors import CasflutterError, OutputError


def _tree(folder):
    """{relative path: bytes} of every file under ``folder``."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _old_run(folder):
    folder.mkdir()
    (folder / "summary.json").write_text('{"run": "old"}')
    (folder / "stale_figure.png").write_bytes(b"\x89PNG old")
    (folder / "sub").mkdir()
    (folder / "sub" / "x.txt").write_text("old")
    return _tree(folder)


def test_new_folder_appears_only_at_the_end(tmp_path):
    target = tmp_path / "a" / "out"
    with atomic_folder(target) as tmp:
        assert not target.exists()                 # nothing at the target while writing
        assert tmp.parent == target.parent and tmp.name.startswith("out" + INCOMPLETE_TAG)
        (tmp / "summary.json").write_text("{}")
    assert _tree(target) == {"summary.json": b"{}"}
    assert sorted(p.name for p in target.parent.iterdir()) == ["out"]


def test_empty_existing_folder_is_accepted(tmp_path):
    target = tmp_path / "out"
    target.mkdir()
    with atomic_folder(target) as tmp:
        (tmp / "f").write_text("new")
    assert _tree(target) == {"f": b"new"}


def test_non_empty_folder_is_refused_before_the_block_runs(tmp_path):
    target = tmp_path / "out"
    before = _old_run(target)
    ran = []
    with pytest.raises(OutputError, match="already exists and is not empty.*--overwrite"):
        with atomic_folder(target, what="--out") as tmp:
            ran.append(tmp)
    assert ran == [] and _tree(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]   # no temporary folder


def test_overwrite_replaces_the_whole_folder(tmp_path):
    target = tmp_path / "out"
    _old_run(target)
    with atomic_folder(target, overwrite=True) as tmp:
        (tmp / "summary.json").write_text('{"run": "new"}')
    # the old run's other files are gone, not left beside the new ones
    assert _tree(target) == {"summary.json": b'{"run": "new"}'}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]   # no .old or .incomplete


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt()])
def test_failure_midway_leaves_the_target_untouched(tmp_path, exc):
    target = tmp_path / "out"
    before = _old_run(target)
    with pytest.raises(type(exc)):
        with atomic_folder(target, overwrite=True) as tmp:
            (tmp / "summary.json").write_text('{"run": "new"}')
            (tmp / "half.png").write_bytes(b"\x89PNG")
            raise exc
    assert _tree(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]   # the temporary folder went


def test_a_killed_process_leaves_only_a_folder_named_incomplete(tmp_path):
    target = tmp_path / "out"
    before = _old_run(target)
    code = textwrap.dedent(f"""
        import os, signal
        from pathlib import Path
        from casflutter._outputs import atomic_folder
        with atomic_folder(Path({str(target)!r}), overwrite=True) as tmp:
            (tmp / "summary.json").write_text('{{"run": "new"}}')
            os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", code], timeout=120)
    assert proc.returncode == -signal.SIGKILL
    assert _tree(target) == before                                   # target untouched
    left = sorted(p.name for p in tmp_path.iterdir() if p.name != "out")
    assert len(left) == 1 and left[0].startswith("out" + INCOMPLETE_TAG)
    assert _tree(tmp_path / left[0]) == {"summary.json": b'{"run": "new"}'}


def test_a_folder_that_appears_meanwhile_is_not_overwritten(tmp_path):
    target = tmp_path / "out"
    with pytest.raises(OutputError, match="appeared while the run was working") as err:
        with atomic_folder(target) as tmp:
            (tmp / "new.txt").write_text("new")
            target.mkdir()
            (target / "someone_else.txt").write_text("theirs")
    assert _tree(target) == {"someone_else.txt": b"theirs"}
    assert str(tmp) in str(err.value) and _tree(tmp) == {"new.txt": b"new"}   # not lost
    assert isinstance(err.value, CasflutterError)


def test_atomic_file_is_renamed_at_the_end_and_removed_on_failure(tmp_path):
    target = tmp_path / "rom.npz"
    target.write_bytes(b"old")
    with atomic_file(target) as tmp:
        assert tmp.suffix == ".npz" and tmp.parent == tmp_path
        tmp.write_bytes(b"new")
        assert target.read_bytes() == b"old"
    assert target.read_bytes() == b"new"
    with pytest.raises(ValueError):
        with atomic_file(target) as tmp:
            tmp.write_bytes(b"half")
            raise ValueError
    assert target.read_bytes() == b"new" and sorted(os.listdir(tmp_path)) == ["rom.npz"]


def test_manifest_lists_every_file_with_its_hash(tmp_path):
    (tmp_path / "summary.json").write_text('{"a": 1}')
    (tmp_path / "figs").mkdir()
    (tmp_path / "figs" / "f.png").write_bytes(b"\x89PNG" * 100)
    info = {"casflutter_version": "9.9", "seed": 7, "threads": {"env": {}, "pools": []},
            "python": "3.x", "platform": "p", "libraries": {}}
    path = write_manifest(tmp_path, config={"b": 2, "a": [1.5, None]},
                          started="2026-01-01T00:00:00Z", stages=["data", "rom"], info=info,
                          extra={"flags": {"x": True}})
    assert path.name == MANIFEST_NAME
    m = json.loads(path.read_text())
    assert m["complete"] is True and m["seed"] == 7 and m["casflutter_version"] == "9.9"
    assert m["completed_stages"] == ["data", "rom"] and m["flags"] == {"x": True}
    assert m["started"] == "2026-01-01T00:00:00Z" and m["finished"] >= m["started"]
    assert set(m["files"]) == {"summary.json", "figs/f.png"}
    for name, entry in m["files"].items():
        data = (tmp_path / name).read_bytes()
        assert entry == {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    # the hash is of the canonical JSON: key order does not matter, a value does
    canonical = json.dumps({"a": [1.5, None], "b": 2}, separators=(",", ":"))
    assert m["config_hash"] == "sha256:" + hashlib.sha256(canonical.encode()).hexdigest()
    assert config_hash({"a": [1.5, None], "b": 2}) == m["config_hash"]
    assert config_hash({"a": [1.5, None], "b": 3}) != m["config_hash"]


def test_thread_settings_report_the_environment_and_the_pools(monkeypatch):
    import numpy as np  # noqa: F401 - loads the BLAS pool
    from threadpoolctl import threadpool_limits

    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    with threadpool_limits(limits=1):
        t = thread_settings()
    assert t["env"]["OPENBLAS_NUM_THREADS"] == "3" and t["env"]["OMP_NUM_THREADS"] is None
    assert t["pools"] and all(p["num_threads"] == 1 for p in t["pools"])
    assert {p["user_api"] for p in t["pools"]} >= {"blas"}


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_folder_whose_parent_is_not_writable_is_refused_before_the_work(tmp_path):
    from casflutter._outputs import check_output_folder

    parent = tmp_path / "ro"
    (parent / "out").mkdir(parents=True)
    parent.chmod(0o555)           # the existing output folder is writable, its parent not
    try:
        with pytest.raises(OutputError, match="cannot write in the folder"):
            check_output_folder(parent / "out", overwrite=True)
    finally:
        parent.chmod(0o755)


def stat_mode(path) -> int:
    """Permission bits of ``path``."""
    return os.stat(path).st_mode & 0o777


@pytest.fixture(params=[0o022, 0o077, 0o002])
def umask(request):
    """The process umask set for one test (and restored)."""
    old = os.umask(request.param)
    try:
        yield request.param
    finally:
        os.umask(old)


def test_folder_and_file_modes_follow_the_umask(tmp_path, umask):
    """The outputs get the modes of any folder or file the user creates (0755/0644 under
    umask 022), not the private 0700/0600 of a temporary name."""
    target = tmp_path / "out"
    with atomic_folder(target) as tmp:
        assert stat_mode(tmp) == 0o777 & ~umask          # already while being written
        (tmp / "summary.json").write_text("{}")
    assert stat_mode(target) == 0o777 & ~umask
    assert stat_mode(target / "summary.json") == 0o666 & ~umask
    one = tmp_path / "model.npz"
    with atomic_file(one) as tmp:
        assert stat_mode(tmp) == 0o666 & ~umask
        tmp.write_bytes(b"x")
    assert stat_mode(one) == 0o666 & ~umask
    # replacing a file gives the new one the same ordinary mode
    with atomic_file(one) as tmp:
        tmp.write_bytes(b"y")
    assert stat_mode(one) == 0o666 & ~umask and one.read_bytes() == b"y"
