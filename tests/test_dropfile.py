"""A validation kept in a drop file: continued after a stop or extended, it equals one uninterrupted run."""

from __future__ import annotations

import io
import json
import re

import numpy as np
import pytest

from diefab.core.errors import PhysicsError
from diefab.dice.design import load_design
from diefab.physics.dropfile import UNKNOWN, DropFile, drops_identity
from diefab.physics.simulate import PhysicsSettings, simulate

VALIDATE = ["validate", "d6", "--seed", "2", "--workers", "1", "--json"]


def _stop_after(batches: int):
    """A ``check_stop`` that stops the run after `batches` batches."""
    from diefab.core import stopping

    calls = []

    def check_stop():
        calls.append(1)
        if len(calls) == batches:
            raise stopping.Stopped

    return check_stop


def _counts(run, *args) -> dict:
    code, out, err = run(*VALIDATE, *args)
    assert code == 0, err
    return json.loads(out)


def test_simulate_runs_only_the_drops_not_known_and_gives_the_same_outcomes():
    d6 = load_design("d6")
    whole = simulate(d6, 300, seed=4, workers=1)
    known = whole.outcomes.copy()
    known[np.random.default_rng(0).random(300) < 0.4] = UNKNOWN
    runs = []
    again = simulate(d6, 300, seed=4, workers=1, known=known, keep=lambda o: runs.append(int((o == UNKNOWN).sum())))
    assert np.array_equal(again.outcomes, whole.outcomes)
    assert again.resumed == int((known != UNKNOWN).sum())
    assert runs[-1] == 0 and all(a > b for a, b in zip(runs, runs[1:]))  # each batch filled in drops not known


def test_a_validation_extended_from_its_drop_file_equals_one_run(run, tmp_path):
    whole = _counts(run, "--sims", "400")
    part = _counts(run, "--sims", "150", "--checkpoint", tmp_path / "d6.npz")
    assert part["checkpoint"]["resumed"] == 0
    more = _counts(run, "--sims", "400", "--checkpoint", tmp_path / "d6.npz")
    assert more["checkpoint"]["resumed"] == 150
    assert more["face_counts"] == whole["face_counts"] and more["counts"] == whole["counts"]
    fewer = _counts(run, "--sims", "100", "--checkpoint", tmp_path / "d6.npz")  # the first 100, none run again
    assert fewer["checkpoint"]["resumed"] == 100
    assert sum(fewer["face_counts"].values()) + fewer["cocked"] + fewer["unsettled"] == 100


def test_a_stopped_validation_keeps_its_finished_drops_and_continues(run, tmp_path, monkeypatch):
    from diefab.core import stopping

    whole = _counts(run, "--sims", "600")
    with monkeypatch.context() as m:
        m.setattr(stopping, "check_stop", _stop_after(2))
        code, _, err = run(*VALIDATE, "--sims", "600", "--checkpoint", tmp_path / "d6.npz")
    assert code == 130 and "kept in" in err and len(err.strip().splitlines()) == 1
    held = np.load(tmp_path / "d6.npz")["outcomes"]
    assert 0 < int((held != UNKNOWN).sum()) < 600
    resumed = _counts(run, "--sims", "600", "--checkpoint", tmp_path / "d6.npz")
    assert resumed["checkpoint"]["resumed"] == int((held != UNKNOWN).sum())
    assert resumed["face_counts"] == whole["face_counts"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d6.npz"]  # no lock or temporary file left


def test_a_drop_file_of_another_run_or_not_a_drop_file_is_refused_in_one_line(run, bad, tmp_path):
    path = tmp_path / "d6.npz"
    _counts(run, "--sims", "50", "--checkpoint", path)
    assert "another die, fill, physics, seed" in bad(*VALIDATE, "--sims", "50", "--seed", "3", "--checkpoint", path)
    assert "another die" in bad(*VALIDATE, "--sims", "50", "--restitution", "0.5", "--checkpoint", path)
    assert "another die" in bad(*VALIDATE, "--sims", "50", "--fill", "print", "--checkpoint", path)
    (tmp_path / "junk.npz").write_bytes(b"PK\x03\x04 not an archive")
    assert "is not a diefab drop file" in bad(*VALIDATE, "--sims", "50", "--checkpoint", tmp_path / "junk.npz")
    with open(tmp_path / "one.npz", "wb") as fh:  # one array, not an archive
        np.save(fh, np.zeros(3))
    assert "is not a diefab drop file" in bad(*VALIDATE, "--sims", "50", "--checkpoint", tmp_path / "one.npz")
    hurt = bytearray(path.read_bytes())  # a disk error inside the compressed outcomes
    for at in range(len(hurt) // 3, len(hurt) // 2, 7):
        hurt[at : at + 3] = b"\x00\xff\x13"
    (tmp_path / "hurt.npz").write_bytes(bytes(hurt))
    assert "is not a diefab drop file" in bad(*VALIDATE, "--sims", "50", "--checkpoint", tmp_path / "hurt.npz")
    assert "must end in .npz" in bad(*VALIDATE, "--sims", "50", "--checkpoint", tmp_path / "d6.json")
    assert "not --sensitivity" in bad(*VALIDATE, "--sims", "50", "--sensitivity", "--checkpoint", path)


@pytest.mark.parametrize(
    ("outcomes", "words"),
    [(np.array([0, 7]), "corrupt"), (np.array([0, -3]), "corrupt"), (np.array([[0, 1]]), "corrupt"),
     (np.array([0.0, 1.0]), "corrupt")],
)  # fmt: skip
def test_a_drop_file_holding_what_no_drop_gives_is_refused(tmp_path, outcomes, words):
    d6 = load_design("d6")
    identity = drops_identity(d6, PhysicsSettings(), 0)
    buffer = io.BytesIO()
    np.savez(buffer, format=np.int64(1), identity=np.str_(identity), outcomes=outcomes)
    (tmp_path / "x.npz").write_bytes(buffer.getvalue())
    with pytest.raises(PhysicsError, match=words):
        DropFile(tmp_path / "x.npz").load(identity, 2, faces=6)


def test_the_identity_follows_what_decides_a_drop():
    d6 = load_design("d6")
    base = drops_identity(d6, PhysicsSettings(), 0)
    assert base == drops_identity(load_design("d6"), PhysicsSettings(), 0)
    assert base != drops_identity(d6, PhysicsSettings(), 1)
    assert base != drops_identity(d6, PhysicsSettings(friction=0.5), 0)
    assert base != drops_identity(load_design("fudge-gem"), PhysicsSettings(), 0)


def test_a_run_that_fails_part_way_keeps_the_drops_that_finished(run, bad, tmp_path, monkeypatch):
    """A worker or a cluster that dies ends the run in one line; the drops finished before are kept."""
    from diefab.physics import checkpoint as physics

    def dies_after_some(design, n, *, known, keep, **kwargs):
        outcomes = known.copy()
        outcomes[:40] = 3
        keep(outcomes)
        raise PhysicsError("a simulation worker process died")

    with monkeypatch.context() as m:
        m.setattr(physics, "simulate", dies_after_some)
        assert "worker process died" in bad(*VALIDATE, "--sims", "100", "--checkpoint", tmp_path / "d6.npz")
    held = np.load(tmp_path / "d6.npz")["outcomes"]
    assert held[:40].tolist() == [3] * 40 and np.all(held[40:] == UNKNOWN)


def test_an_error_in_a_callback_stops_the_pooled_run_and_the_next_run_is_whole():
    """A keep that fails (a full disk) ends the run at once: its workers are stopped, none runs on."""
    from diefab.physics import pool

    d6 = load_design("d6")

    def full_disk(outcomes):
        raise OSError("No space left on device")

    with pytest.raises(OSError, match="No space"):
        simulate(d6, 20_000, seed=6, workers=2, keep=full_disk)
    assert pool._POOL is None  # the pool was shut down, its pending batches with it
    again = simulate(d6, 500, seed=6, workers=2)
    assert np.array_equal(again.outcomes, simulate(d6, 500, seed=6, workers=1).outcomes)


def test_a_drop_file_that_would_unpack_past_the_largest_run_is_refused_unread(tmp_path):
    import zipfile

    from diefab.physics.dropfile import MAX_BYTES

    with zipfile.ZipFile(tmp_path / "bomb.npz", "w", zipfile.ZIP_DEFLATED) as archive:  # zeros pack small
        with archive.open("outcomes.npy", "w", force_zip64=True) as member:
            chunk = bytes(1 << 20)
            for _ in range(MAX_BYTES // len(chunk) + 1):
                member.write(chunk)
    assert (tmp_path / "bomb.npz").stat().st_size < MAX_BYTES // 100
    with pytest.raises(PhysicsError, match="unpacks to"):
        DropFile(tmp_path / "bomb.npz").load("x", 10, faces=6)


def _search(store=None):
    from diefab.dice.targets import parse_target
    from diefab.search.synthesis import synthesize

    return synthesize(parse_target("uniform:3"), family="cuboid", model="simulation", max_drops=1200, seed=3,
                      workers=1, store=store)  # fmt: skip


def test_a_drop_store_counts_the_drops_of_its_own_files_and_nothing_else(tmp_path):
    from diefab.physics.checkpoint import DropStore
    from diefab.physics.world import UNSETTLED

    store = DropStore(tmp_path)
    assert store.held() == 0 and DropFile(tmp_path / "none.npz").count() == 0
    DropFile(tmp_path / "a.npz").save("a", np.array([0, UNKNOWN, 3, UNSETTLED], dtype=np.int32))  # another run's
    (tmp_path / "c.npz").write_bytes(b"not a drop file")
    assert DropFile(tmp_path / "a.npz").count() == 3 and store.held() == 0
    store.run(load_design("d6"), None, seed=5, n=12, workers=1)
    assert store.held() == store.drops == 12 and len(list(tmp_path.glob("*.npz"))) == 3
    again = DropStore(tmp_path)
    again.run(load_design("d6"), None, seed=5, n=20, workers=1)
    assert again.held() == again.drops == 20 and again.resumed == 12


def test_a_stopped_search_continued_from_its_drop_store_finds_the_same_die(tmp_path, monkeypatch):
    from diefab.core import stopping
    from diefab.physics.checkpoint import DropStore
    from diefab.physics.simulate import SimulationInterrupted

    whole = _search()
    with monkeypatch.context() as m:
        m.setattr(stopping, "check_stop", _stop_after(3))
        with pytest.raises(SimulationInterrupted):
            _search(DropStore(tmp_path))
    kept = [np.load(p)["outcomes"] for p in tmp_path.glob("*.npz")]
    assert kept and 0 < sum(int((k != UNKNOWN).sum()) for k in kept) < whole.drops
    store = DropStore(tmp_path)
    again = _search(store)
    assert again.design.params == whole.design.params and again.steps == whole.steps and again.drops == whole.drops
    assert 0 < store.resumed < store.drops == whole.drops
    replay = DropStore(tmp_path)
    assert _search(replay).design.params == whole.design.params
    assert replay.resumed == replay.drops == whole.drops  # every drop found, none run again


def test_a_stopped_design_says_where_its_drops_are_and_continues_from_them(run, bad, tmp_path, monkeypatch):
    from diefab.core import stopping

    args = ["design", "uniform:3", "--family", "cuboid", "--model", "solid-angle", "--validate-sims", "300",
            "--workers", "1", "--out", tmp_path / "out", "--json", "--checkpoint", tmp_path / "drops"]  # fmt: skip
    (tmp_path / "drops").mkdir()
    DropFile(tmp_path / "drops" / "other.npz").save("another target's", np.zeros(50, dtype=np.int32))
    with monkeypatch.context() as m:
        m.setattr(stopping, "check_stop", _stop_after(2))
        code, _, err = run(*args)
    said = re.fullmatch(rf"diefab: interrupted; (\d+) drops are kept in {re.escape(str(tmp_path / 'drops'))}: "
                        "run the same command again to continue", err.strip())  # fmt: skip
    assert code == 130 and said, err
    code, out, err = run(*args)
    first = json.loads(out)
    assert code in (0, 3), err
    assert first["checkpoint"]["drops"] == 300 and 0 < first["checkpoint"]["resumed"] == int(said[1]) < 300
    code, out, err = run(*args[:-5], "--out", tmp_path / "again", "--json", "--checkpoint", tmp_path / "drops")
    second = json.loads(out)
    assert second["checkpoint"]["resumed"] == 300 and second["validated"] == first["validated"]
    (tmp_path / "file").write_text("")
    assert "is a file" in bad(*args[:-1], tmp_path / "file")
    (tmp_path / "blocked").mkdir()
    (tmp_path / "blocked" / "optimized").write_text("")  # where the search keeps its optimizations
    assert "optimized (where the search keeps its optimizations) is not a folder" in bad(
        *args[:-1], tmp_path / "blocked"
    )
