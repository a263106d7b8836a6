"""The JSON-lines point store: durable appends, torn lines, newest record wins."""

import math

from casflutter.study import PointStore


def test_append_roundtrip_and_newest_wins(tmp_path):
    s = PointStore(tmp_path / "sub" / "p.jsonl")
    s.append({"key": "a", "status": "failed", "error": "boom"})
    s.append({"key": "b", "status": "ok", "outputs": {"Vf": 2.17, "bad": math.nan}})
    s.append({"key": "a", "status": "ok", "outputs": {"Vf": 1.0}})
    recs = s.records()
    assert set(recs) == {"a", "b"} and recs["a"]["status"] == "ok"
    assert recs["b"]["outputs"] == {"Vf": 2.17, "bad": None}  # strict JSON: NaN -> null
    assert s.finished_keys() == {"a", "b"}


def test_failed_keys_and_torn_last_line(tmp_path):
    path = tmp_path / "p.jsonl"
    s = PointStore(path)
    s.append({"key": "a", "status": "failed", "error": "x"})
    s.append({"key": "b", "status": "ok"})
    with open(path, "a") as fh:  # a kill during a write leaves a torn line
        fh.write('{"key": "c", "status": "o')
    assert s.finished_keys() == {"a", "b"}
    assert s.finished_keys(include_failed=False) == {"b"}
    s.append({"key": "d", "status": "ok"})  # must not glue onto the torn line
    assert s.finished_keys() == {"a", "b", "d"}
