"""Reading photos into a roll log: each photo counted once, another die refused, bad input before any write."""

from __future__ import annotations

import json
import os
import shutil

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")
if not hasattr(cv2, "aruco"):
    pytest.skip("OpenCV without the aruco module", allow_module_level=True)

from diefab import load_design  # noqa: E402
from diefab.camera.pose import Camera, MarkerDetector, read_frame  # noqa: E402
from diefab.camera.rig import rendered_rests  # noqa: E402
from diefab.core.errors import StatsError  # noqa: E402
from diefab.dice.markers import marker_layout  # noqa: E402
from diefab.stats.rolllog import Roll, append_roll, read_log, remove_last_roll  # noqa: E402


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """Six photos of a resting d6 (no finger) and their true values."""
    design = load_design("d6")
    folder = tmp_path_factory.mktemp("photos")
    truth = []
    for i, rest in enumerate(rendered_rests(design, marker_layout(design), 6, seed=11, finger=0.0)):
        cv2.imwrite(str(folder / f"{i:02d}.png"), rest.image)
        truth.append(rest.value)
    return folder, truth


def _read(*args) -> int:
    from diefab.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["read", *map(str, args)])
    return stop.value.code


def test_another_die_s_markers_are_never_read_as_this_die_s(photos):
    # the d6's markers are numbered from the same dictionary as the d20's and the gem's: a pose on one of them
    # leaves the others unexplained, and the frame is unread
    folder, _ = photos
    for name in ("d20", "fudge-gem", "3d6"):
        design = load_design(name)
        detector = MarkerDetector(marker_layout(design))
        for path in sorted(folder.iterdir()):
            image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
            read = read_frame(image, design, detector, Camera.from_fov(image.shape[1], image.shape[0]))
            assert read.value is None
            assert read.pose is None or read.pose.conflicts


def test_photos_of_another_die_end_in_one_line_and_leave_no_log(photos, tmp_path, capsys):
    folder, _ = photos
    assert _read("d20", "--images", folder, "--out", tmp_path) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not on this die" in err
    assert not (tmp_path / "d20-rolls.csv").exists()


def test_a_folder_read_again_counts_each_photo_once(photos, tmp_path, capsys):
    folder, truth = photos
    mine = tmp_path / "mine"
    shutil.copytree(folder, mine, ignore=shutil.ignore_patterns("04.png", "05.png"))
    shutil.copy(mine / "00.png", mine / "00-copy.png")  # the same photo twice is one roll
    assert _read("d6", "--images", mine, "--out", tmp_path) == 0
    assert len(read_log(tmp_path / "d6-rolls.csv").rolls) == 4
    assert _read("d6", "--images", mine, "--out", tmp_path) == 0
    assert "5 photos" in capsys.readouterr().err
    assert len(read_log(tmp_path / "d6-rolls.csv").rolls) == 4
    for name in ("04.png", "05.png"):
        shutil.copy(folder / name, mine / name)
    assert _read("d6", "--images", mine, "--out", tmp_path) == 0
    log = read_log(tmp_path / "d6-rolls.csv")
    assert [r.value for r in log.rolls] == truth  # every photo once, none guessed, in name order
    assert len(log.digests) == 6
    assert [r.frame for r in log.rolls] == list(range(6))


def test_a_bad_photo_is_refused_before_any_roll_is_written(photos, tmp_path, capsys):
    folder, _ = photos
    mine = tmp_path / "mine"
    shutil.copytree(folder, mine)
    (mine / "03.png").write_bytes((folder / "03.png").read_bytes()[:2000])  # cut short
    assert _read("d6", "--images", mine, "--out", tmp_path) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert not (tmp_path / "d6-rolls.csv").exists()


@pytest.mark.parametrize("size", [(40, 30), (2, 2)])
def test_a_photo_too_small_to_read_is_one_line(tmp_path, capsys, size):
    mine = tmp_path / "mine"
    mine.mkdir()
    cv2.imwrite(str(mine / "a.png"), np.full(size[::-1], 128, np.uint8))
    assert _read("d6", "--images", mine, "--out", tmp_path) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pixels" in err


def test_a_photo_whose_name_is_not_utf8_is_read(photos, tmp_path):
    folder, truth = photos
    mine = tmp_path / "mine"
    mine.mkdir()
    shutil.copy(folder / "00.png", mine / os.fsdecode(b"\xe9t\xe9.png"))
    assert _read("d6", "--images", mine, "--out", tmp_path) == 0
    assert [r.value for r in read_log(tmp_path / "d6-rolls.csv").rolls] == truth[:1]


def test_the_picture_show_keeps_is_never_read_as_a_photo(photos, tmp_path):
    folder, truth = photos
    for name in ("00.png", "01.png"):
        shutil.copy(folder / name, tmp_path / name)
    shutil.copy(folder / "02.png", tmp_path / "d6-live.png")  # what --show leaves where no window opens
    assert _read("d6", "--images", tmp_path, "--out", tmp_path) == 0
    assert [r.value for r in read_log(tmp_path / "d6-rolls.csv").rolls] == truth[:2]


def test_an_append_cut_short_leaves_the_log_as_it_was(tmp_path, monkeypatch):
    path = tmp_path / "rolls.csv"
    append_roll(path, Roll("0.000", 4, "f6", 1.0, 0, "sha256:0123456789abcdef a.png"))
    before = path.read_bytes()
    write = os.write
    monkeypatch.setattr(os, "write", lambda fd, data: write(fd, data[: len(data) // 2]))  # a full disk
    with pytest.raises(StatsError, match="whole roll"):
        append_roll(path, Roll("1.000", 5, "f5", 1.0, 1, "sha256:fedcba9876543210 b.png"))
    monkeypatch.undo()
    assert path.read_bytes() == before


def test_a_torn_last_line_is_cut_before_rolls_are_appended(photos, tmp_path):
    folder, truth = photos
    log = tmp_path / "d6-rolls.csv"
    log.write_text("time,value,face,confidence,frame\n0.1,3,f1,0.9,1\n0.2,2")
    assert _read("d6", "--images", folder, "--out", tmp_path) == 0
    rolls = read_log(log).rolls
    assert [r.value for r in rolls] == [3, *truth]


def test_a_header_without_its_line_end_is_a_log_to_append_to(photos, tmp_path):
    folder, truth = photos
    log = tmp_path / "d6-rolls.csv"
    log.write_text("time,value,face,confidence,frame")
    assert read_log(log).rolls == () and read_log(log).torn
    assert _read("d6", "--images", folder, "--out", tmp_path) == 0
    assert [r.value for r in read_log(log).rolls] == truth


def test_stats_says_when_it_leaves_out_a_last_line_cut_short(tmp_path, capsys):
    from diefab.cli import main

    log = tmp_path / "rolls.csv"
    log.write_text("time,value,face,confidence,frame\n,1,,,\n,2,,,\n,3,,,")
    with pytest.raises(SystemExit) as stop:
        main(["stats", "--rolls", str(log), "--target", "uniform:3", "--json"])
    assert stop.value.code == 0 and json.loads(capsys.readouterr().out)["n"] == 2
    with pytest.raises(SystemExit):
        main(["stats", "--rolls", str(log), "--target", "uniform:3"])
    assert "last line has no line end and is left out" in capsys.readouterr().err


def test_undo_removes_the_last_roll_read_and_keeps_the_unread_after_it(tmp_path):
    path = tmp_path / "rolls.csv"
    for roll in (Roll("0.000", 4, "f6", 1.0, 0, "sha256:0123456789abcdef a.png"),
                 Roll("1.000", 5, "f5", 1.0, 1, "sha256:fedcba9876543210 b.png"),
                 Roll("2.000", None, None, 0.2, 2, "sha256:00000000000000ff c.png")):  # fmt: skip
        append_roll(path, roll)
    assert remove_last_roll(path).value == 5
    log = read_log(path)
    assert [r.value for r in log.rolls] == [4, None]
    assert log.digests == {"sha256:0123456789abcdef", "sha256:00000000000000ff"}
    assert remove_last_roll(path).value == 4
    with pytest.raises(StatsError, match="no roll read"):
        remove_last_roll(path)
    assert [r.value for r in read_log(path).rolls] == [None]


def test_a_roll_s_source_round_trips_and_goes_with_it_on_undo(tmp_path):
    path = tmp_path / "rolls.csv"
    append_roll(path, Roll("0.000", 4, "f6", 1.0, 0, "sha256:0123456789abcdef a b.png"))
    append_roll(path, Roll("1.000", 5, "f5", 1.0, 1, "sha256:fedcba9876543210 c.png"))
    log = read_log(path)
    assert [r.source for r in log.rolls] == ["sha256:0123456789abcdef a b.png", "sha256:fedcba9876543210 c.png"]
    assert log.digests == {"sha256:0123456789abcdef", "sha256:fedcba9876543210"}
    assert remove_last_roll(path).value == 5
    assert read_log(path).digests == {"sha256:0123456789abcdef"}
    with pytest.raises(ValueError, match="one line"):
        Roll("2.000", 5, source="x\ny").line()
