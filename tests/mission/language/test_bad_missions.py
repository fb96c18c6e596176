"""A corpus of broken missions: every mistake must be reported, at once, as FILE:LINE:COL: message.

Each file in tests/bad_missions/ starts with comment lines that declare what `auv validate` must print:

    # expect: 12:5: unknown key 'cruse_speed'               a diagnostic at 12:5 of this file containing the text
    # expect: worlds/broken_world.yaml:5:3: unknown key     ... of another file (relative to this file's folder)
    # expect-count: 2                                       exactly this many diagnostics in all
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from mission.cli import main
from mission.errors import MissionError
from mission.language import load_mission

ROOT = Path(__file__).resolve().parents[3]
BAD = ROOT / "tests" / "bad_missions"
FILES = sorted(BAD.glob("*.yaml"))
REFERENCE = ROOT / "missions" / "sps_field_inspection.yaml"

_EXPECT = re.compile(
    r"^#\s*expect:\s*(?:(?P<file>[^:]*[^\d:][^:]*):)?(?P<line>\d+):(?P<col>\d+):\s?(?P<text>.*?)\s*$")
_COUNT = re.compile(r"^#\s*expect-count:\s*(?P<count>\d+)\s*$")
_DIAGNOSTIC = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<message>.*)$")


@dataclass(frozen=True)
class Expected:
    file: Path  # resolved
    line: int
    col: int
    text: str

    def describe(self) -> str:
        return f"{self.file.name}:{self.line}:{self.col}: ...{self.text}..."


@dataclass(frozen=True)
class Printed:
    file: Path  # resolved
    line: int
    col: int
    message: str


def parse_expectations(path: Path) -> tuple[list[Expected], int | None]:
    """The `# expect:` lines and the optional `# expect-count:` of the leading comment block of `path`."""
    expected: list[Expected] = []
    count: int | None = None
    for raw in path.read_text(encoding="utf-8").splitlines():
        if not raw.startswith("#"):
            break
        if m := _COUNT.match(raw):
            count = int(m["count"])
        elif m := _EXPECT.match(raw):
            file = (path.parent / m["file"]).resolve() if m["file"] else path.resolve()
            assert m["text"], f"{path.name}: empty expected text in {raw!r}"
            expected.append(Expected(file, int(m["line"]), int(m["col"]), m["text"]))
        else:
            assert not raw.lstrip("# ").startswith("expect"), f"{path.name}: malformed expect line {raw!r}"
    assert expected, f"{path.name} declares no `# expect:` line"
    return expected, count


def parse_diagnostics(output: str) -> list[Printed]:
    printed = []
    for raw in output.splitlines():
        m = _DIAGNOSTIC.match(raw)
        assert m, f"not a FILE:LINE:COL: diagnostic: {raw!r}"
        printed.append(Printed(Path(m["file"]).resolve(), int(m["line"]), int(m["col"]), m["message"]))
    return printed


def test_corpus_is_large_enough() -> None:
    assert len(FILES) >= 30, [p.name for p in FILES]


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_bad_mission_reports_every_mistake_located(path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    expected, count = parse_expectations(path)
    monkeypatch.chdir(ROOT)  # validate as a user would: `auv validate tests/bad_missions/NN_name.yaml`
    status = main(["validate", str(path.relative_to(ROOT))])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert status == 1, f"{path.name} was not rejected:\n{out}{err}"
    printed = parse_diagnostics(out)
    listing = "\n".join(out.splitlines())
    for exp in expected:
        at = [d for d in printed if (d.file, d.line, d.col) == (exp.file, exp.line, exp.col)]
        assert any(exp.text in d.message for d in at), \
            f"expected {exp.describe()}; printed:\n{listing}"
    if count is not None:
        assert len(printed) == count, f"expected {count} diagnostic(s); printed:\n{listing}"


def test_python_m_mission_validate() -> None:
    broken = BAD / "09_misspelt_vehicle_key.yaml"
    rel = broken.relative_to(ROOT)
    run = subprocess.run([sys.executable, "-m", "mission", "validate", str(rel)], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 1
    assert "Traceback" not in run.stderr
    assert f"{rel}:7:3: unknown key 'cruse_speed' in vehicle; did you mean 'cruise_speed'?" in run.stdout

    ref = REFERENCE.relative_to(ROOT)
    run = subprocess.run([sys.executable, "-m", "mission", "validate", str(ref)], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert "Traceback" not in run.stderr
    assert run.returncode == 0, run.stdout
    assert [line for line in run.stdout.splitlines() if ": note: " not in line] == [f"{ref}: ok"]


@pytest.mark.parametrize("name", ["01_yaml_unclosed_bracket.yaml", "05_empty_document.yaml",
                                  "44_broken_world_file.yaml", "49_several_mistakes_at_once.yaml"])
def test_load_mission_raises_located_mission_error(name: str) -> None:
    path = BAD / name
    with pytest.raises(MissionError) as info:
        load_mission(path)
    diagnostics = info.value.diagnostics
    assert diagnostics
    for d in diagnostics:
        assert d.line >= 1 and d.col >= 1, d
        assert Path(d.file).is_file(), d
    assert str(info.value) == "\n".join(str(d) for d in diagnostics)
