"""Output paths are checked before any work (``check_output_path``), their missing folders
are created by the writers (``atomic_file``, ``save_figure``), and ``casflutter flutter``
writes a figure only where asked."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from casflutter.cli import main
from casflutter.errors import CasflutterError


def _check():
    from casflutter._outputs import check_figure_path, check_output_path

    return check_output_path, check_figure_path


def test_creatable_paths_pass_and_nothing_is_created(tmp_path):
    check, _ = _check()
    target = tmp_path / "a" / "b" / "out.json"
    assert check(target, what="--out") == target
    assert check(tmp_path / "new" / "folder", kind="dir") == tmp_path / "new" / "folder"
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no folder, no probe file left
    (tmp_path / "exists.json").write_text("{}")
    assert check(tmp_path / "exists.json") == tmp_path / "exists.json"
    (tmp_path / "d").mkdir()
    assert check(tmp_path / "d", kind="dir") == tmp_path / "d"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "exists.json"]


@pytest.mark.parametrize("make, path, kind, kw, words", [
    (lambda t: (t / "afile").write_text(""), "afile/sub/out.json", "file", {},
     "afile is a file, not a folder"),
    (lambda t: (t / "afile").write_text(""), "afile/sub", "dir", {},
     "afile is a file, not a folder"),
    (lambda t: (t / "adir").mkdir(), "adir", "file", {}, "is a folder; give a file name"),
    (lambda t: (t / "afile").write_text(""), "afile", "dir", {}, "is a file, not a folder"),
    (lambda t: (t / "old.json").write_text(""), "old.json", "file", {"overwrite": False},
     "already exists; remove it, choose another name or pass --overwrite"),
    (lambda t: (t / "full").mkdir() or (t / "full" / "x").write_text(""), "full", "dir",
     {"overwrite": False}, "already exists and is not empty"),
    (lambda t: None, "fig.xyz", "file", {"suffixes": (".png", ".pdf")},
     "unsupported file type '.xyz'; use one of .png, .pdf"),
])
def test_paths_that_cannot_be_written_are_refused(tmp_path, make, path, kind, kw, words):
    from casflutter.errors import OutputError

    check, _ = _check()
    make(tmp_path)
    with pytest.raises(OutputError, match="^--out ") as err:
        check(tmp_path / path, what="--out", kind=kind, **kw)
    assert words in str(err.value)
    assert isinstance(err.value, OSError) and isinstance(err.value, CasflutterError)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc is Linux's")
def test_a_folder_without_write_permission_is_refused():
    from casflutter.errors import OutputError

    check, _ = _check()
    with pytest.raises(OutputError, match="cannot write in the folder /proc"):
        check("/proc/casflutter-test/out.json", what="--out")  # even root cannot write there


def test_figure_suffix_must_be_a_matplotlib_format(tmp_path):
    from casflutter.errors import OutputError

    _, check_figure = _check()
    assert check_figure(tmp_path / "f.pdf") == tmp_path / "f.pdf"
    with pytest.raises(OutputError, match=r"unsupported file type '\.xyz'.*\.png"):
        check_figure(tmp_path / "f.xyz")


@pytest.mark.parametrize("command", ["flutter", "lco"])
@pytest.mark.parametrize("figure, words", [
    ("afile/sub.png", "afile is a file, not a folder"),
    ("f.xyz", "unsupported file type '.xyz'"),
])
def test_figure_path_is_checked_before_any_work(tmp_path, monkeypatch, capsys, command, figure,
                                                words):
    import casflutter.truth

    def no_work(*a, **k):
        raise AssertionError("the work started before the figure path was checked")

    monkeypatch.setattr(casflutter.truth, "load_problem", no_work)
    (tmp_path / "afile").write_text("")
    assert main([command, "typical_section", "--figure", str(tmp_path / figure)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("casflutter: error: --figure ") and words in err


def test_flutter_writes_no_figure_unless_asked(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["flutter", "typical_section", "--no-parametric", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["figure"] is None and doc["truth"]["V_flutter"] > 0
    assert list(tmp_path.iterdir()) == []  # nothing dropped into the current folder


def test_atomic_file_and_save_figure_create_the_missing_folders(tmp_path):
    """``check_output_path`` accepts a file whose folder does not exist yet ("created later by
    the writer"): the writers create it, and leave no temporary file beside the target."""
    import matplotlib.pyplot as plt

    from casflutter._outputs import atomic_file, save_figure

    target = tmp_path / "new" / "sub" / "x.json"
    with atomic_file(target) as tmp:
        tmp.write_text("{}")
    assert target.read_text() == "{}" and os.listdir(target.parent) == ["x.json"]
    fig = plt.figure(figsize=(1, 1))
    try:
        path = save_figure(fig, tmp_path / "figs" / "a" / "f.png", dpi=20)
    finally:
        plt.close(fig)
    assert path == tmp_path / "figs" / "a" / "f.png"
    assert path.read_bytes()[:4] == b"\x89PNG" and os.listdir(path.parent) == ["f.png"]


def test_atomic_file_that_cannot_create_its_folder_is_an_output_error(tmp_path):
    from casflutter._outputs import atomic_file
    from casflutter.errors import OutputError

    (tmp_path / "afile").write_text("")
    with pytest.raises(OutputError, match=r"^--out .*afile.*choose a writable location"):
        with atomic_file(tmp_path / "afile" / "x.json", what="--out"):
            raise AssertionError("the block ran without a file to write")


def test_bench_design_out_in_a_missing_folder_is_written(tmp_path):
    """R2: the folder of ``--out`` is created (it was an internal FileNotFoundError after the
    whole design)."""
    from casflutter.aeroelastic import write_family

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verify"))
    from family_helpers import random_family

    fam = random_family(4, n_modes=2)
    write_family(fam, tmp_path / "fam.toml", fam.speeds)
    out = tmp_path / "new" / "sub" / "bench.json"
    assert main(["-q", "bench", "design", "--problem", str(tmp_path / "fam.toml"),
                 "--interval", "0.1", "0.5", "--orders", "1", "--seeds", "0",
                 "--out", str(out)]) == 0
    (rec,) = json.loads(out.read_text())["records"]
    assert rec["held"] is True and sorted(p.name for p in out.parent.iterdir()) == ["bench.json"]
