"""`auv bench` writes the results contract: name, quick, machine, timestamp, results, checks."""

import json

from mission.cli import main


def test_bench_simspeed_quick_writes_every_check_beside_the_full_results_and_leaves_them_alone(tmp_path, capsys):
    full = tmp_path / "simspeed.json"
    full.write_text('{"name": "simspeed", "quick": false}\n')
    assert main(["bench", "simspeed", "--quick", "--out", str(tmp_path)]) == 0
    assert full.read_text() == '{"name": "simspeed", "quick": false}\n'
    record = json.loads((tmp_path / "simspeed.quick.json").read_text())
    assert {"name", "quick", "machine", "timestamp", "results", "checks"} <= set(record)
    assert record["quick"] is True and record["machine"]["cores"] >= 1
    assert set(record["checks"]) == {"one_hour_mission_cpu_time_s", "realtime_factor"}
    assert all(c["pass"] is True for c in record["checks"].values())


def test_unknown_benchmark_is_a_clean_error(capsys):
    assert main(["bench", "nope"]) == 1
    assert "unknown benchmark 'nope'" in capsys.readouterr().err
