"""game-suite's checks of what it keeps (rbcd.game_suite; docs/games.md): an
expanded entry counts as up to date only when its trace, geometry and
summary all match what the entry records, and a regenerated summary is
compared with the entry's committed summary.jsonl (its first N lines for
--frames N)."""
import os

from conftest import ROOT
from rbcd import game_suite
from rbcd.game_suite import Entry

ENTRY = os.path.join(ROOT, "workloads", "games", "openarena-oa_dm1")


def test_summary_compared_with_the_committed_one(tmp_path):
    e = Entry(ENTRY)
    with open(os.path.join(ENTRY, "summary.jsonl")) as f:
        committed = f.read()
    lines = committed.splitlines(keepends=True)
    p = tmp_path / "s.jsonl"
    p.write_text(committed)
    assert e.summary_matches(str(p)), "the committed summary itself"
    p.write_text("".join(lines[:3]))
    assert e.summary_matches(str(p), 3) and not e.summary_matches(str(p)), "a --frames 3 summary"
    p.write_text(committed.replace('"fragments":', '"fragments":1', 1))
    assert not e.summary_matches(str(p)), "a changed summary passed"
    assert not e.summary_matches(str(tmp_path / "missing.jsonl"))


def test_an_expansion_with_a_changed_summary_is_not_up_to_date(tmp_path, monkeypatch):
    """up_to_date reads the summary too: with the trace and geometry taken as
    matching their checksums, a changed summary.jsonl makes the entry be
    expanded again, never skipped as up to date."""
    e = Entry(ENTRY)
    trace, geo, summary = e.outputs(str(tmp_path))
    for p in (trace, geo):
        open(p, "w").close()
    recorded = {trace: e.sha["trace"], geo: e.sha["geometry"]}
    monkeypatch.setattr(game_suite, "sha256_file", lambda path, decompress=False: recorded[path])
    with open(os.path.join(ENTRY, "summary.jsonl")) as f:
        committed = f.read()
    open(summary, "w").write(committed)
    assert e.up_to_date(str(tmp_path)), "everything matching: up to date"
    open(summary, "w").write(committed + "\n")
    assert not e.up_to_date(str(tmp_path)), "a changed summary counted as up to date"
