"""The resumable manifest: records survive a kill mid-line, and only the same job with its outputs counts as done."""

from __future__ import annotations

from rgbt_toolkit.batch.manifest import Manifest


def test_records_round_trip(tmp_path):
    out = tmp_path / "a.txt"
    out.write_text("1,2,3,4\n")
    manifest = Manifest(tmp_path / "m.jsonl")
    manifest.record("a", "job1", [out], 1.25)
    again = Manifest(tmp_path / "m.jsonl")
    assert len(again) == 1 and again.is_done("a", "job1")
    assert again.get("a").outputs == (str(out),) and again.get("a").seconds == 1.25
    assert not again.is_done("a", "job2")  # another preset / tracker: redo
    assert not again.is_done("b", "job1")
    out.unlink()
    assert not Manifest(tmp_path / "m.jsonl").is_done("a", "job1")  # outputs deleted since: redo


def test_line_cut_short_by_a_kill_is_ignored_and_repaired(tmp_path):
    path = tmp_path / "m.jsonl"
    Manifest(path).record("a", "job", [], 0.1)
    with open(path, "a", encoding="utf-8") as handle:
        handle.write('{"key": "b", "job": "jo')  # the kill came mid-write
    manifest = Manifest(path)
    assert "a" in manifest and "b" not in manifest
    manifest.record("c", "job", [], 0.2)
    reloaded = Manifest(path)
    assert "a" in reloaded and "c" in reloaded and "b" not in reloaded
    assert all(line.startswith("{") or line.startswith('{"key": "b"') for line in path.read_text().splitlines())


def test_damaged_line_costs_only_its_item(tmp_path):
    path = tmp_path / "m.jsonl"
    path.write_text('{"key": "a", "job": "j", "outputs": []}\nnot json at all\n{"job": "j"}\n'
                    '{"key": "d", "job": "j", "outputs": []}\n')
    manifest = Manifest(path)
    assert sorted(manifest._entries) == ["a", "d"]
