"""Run folders: what `--out` may name, `--force` replacing a run folder whole, and the lock a run holds."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from conftest import MISSIONS

from mission.cli import main
from mission.errors import RunFolderError
from mission.runlock import MARKER, claim_run_folder, is_run_folder

TRANSIT = MISSIONS / "fault_battery.yaml"  # aborts after ~440 simulated seconds: about a second of CPU


def refusal(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run `auv simulate` expecting a refusal: exit 1 and one line on stderr, no traceback."""
    assert main(["simulate", str(TRANSIT), "-q", "--no-plots", *argv]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_an_existing_file_and_a_path_below_a_file_are_refused(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    assert refusal(capsys, "--out", str(tmp_path / "notes.txt")).endswith("notes.txt: exists and is not a folder")
    line = refusal(capsys, "--out", str(tmp_path / "notes.txt" / "run"))
    assert "notes.txt is a file, not a folder" in line
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_the_missions_own_folder_and_its_ancestors_are_refused(tmp_path, capsys):
    mission = tmp_path / "work" / "m.yaml"
    mission.parent.mkdir()
    mission.write_text(TRANSIT.read_text().replace("../worlds/", f"{MISSIONS.parent}/worlds/"))
    for out in (mission.parent, tmp_path):
        assert main(["simulate", str(mission), "-q", "--no-plots", "--out", str(out), "--force"]) == 1
        err = capsys.readouterr().err.strip()
        assert err.endswith("a run folder must be a folder of its own") and "holds the mission" in err
    assert mission.read_text().startswith("# A battery fault")  # untouched


def test_a_folder_holding_the_world_is_refused():
    with pytest.raises(RunFolderError, match="holds the world"):
        claim_run_folder(MISSIONS.parent / "worlds", "test", [("world", MISSIONS.parent / "worlds" / "x.yaml")])


def test_a_non_empty_folder_that_is_not_a_run_is_refused_even_with_force(tmp_path, capsys):
    (tmp_path / "thesis.tex").write_text("mine")
    assert refusal(capsys, "--out", str(tmp_path), "--force").endswith("not empty and not a run folder; choose a "
                                                                       "new or empty folder")
    assert [p.name for p in tmp_path.iterdir()] == ["thesis.tex"]


def test_an_earlier_run_is_kept_unless_force_which_replaces_the_folder_whole(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", str(TRANSIT), "-q", "--no-plots", "--out", str(out)]) == 1  # the mission aborts
    capsys.readouterr()
    first = (out / "metrics.json").read_text()
    (out / "photos").mkdir()
    (out / "photos" / "stale.png").write_bytes(b"old")
    assert refusal(capsys, "--out", str(out)).endswith("holds an earlier run; pass --force to replace it, or choose "
                                                       "another --out")
    assert (out / "metrics.json").read_text() == first
    assert main(["simulate", str(TRANSIT), "-q", "--no-plots", "--out", str(out), "--force"]) == 1
    assert not (out / "photos").exists()  # nothing of the earlier run is left behind
    assert is_run_folder(out) and (out / MARKER).is_file() and (out / "metrics.json").is_file()


def test_a_second_run_into_a_locked_folder_is_refused_with_one_line(tmp_path, capsys):
    out = tmp_path / "run"
    with claim_run_folder(out, "another auv"):  # an open file description of its own: as another process
        line = refusal(capsys, "--out", str(out))
        assert line == f"auv: {out}: in use by another run (its lock is held); wait for it or choose another --out"
        with pytest.raises(RunFolderError, match="in use"):
            claim_run_folder(out, "a third", force=True)
    with claim_run_folder(out, "after the first ended"):
        pass


def test_an_unwritable_place_is_one_line_naming_the_path(capsys):
    line = refusal(capsys, "--out", "/proc/auv-run")
    assert line.startswith("auv: /proc/auv-run: cannot be used as a run folder (")


def test_a_campaign_folder_is_claimed_like_a_run_folder(tmp_path, capsys):
    (tmp_path / "data.csv").write_text("1,2")
    assert main(["simulate", str(TRANSIT), "--seeds", "1", "--no-plots", "--out", str(tmp_path)]) == 1
    assert capsys.readouterr().err.strip().endswith("not empty and not a run folder; choose a new or empty folder")
    assert not (tmp_path / "seed-1").exists()


def test_read_only_results_become_run_folder_errors(tmp_path):
    from mission.runfolder import write_atomic

    with pytest.raises(RunFolderError, match="cannot write"):
        write_atomic(Path("/proc/version"), "x")


def test_auv_run_refuses_the_same_folders_before_it_connects(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    argv = ["run", str(MISSIONS / "field_transit.yaml"), "--vehicle", "mavlink:udpin:127.0.0.1:14998",
            "--connect-timeout", "30", "--out", str(tmp_path / "notes.txt")]
    started = time.monotonic()
    assert main(argv) == 1
    assert time.monotonic() - started < 10.0  # refused at once, not after waiting for the vehicle
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"auv: {tmp_path / 'notes.txt'}: exists and is not " \
                                                                "a folder"
