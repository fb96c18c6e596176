"""`auv report`: a campaign's HTML page, with a second campaign beside it, read back as HTML (and, where Chromium
is installed, rendered by a real headless browser)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

pytest.importorskip("matplotlib")


def run(seed: int, completed: bool, camera: float, coverage: float) -> dict:
    return {"seed": seed, "completed": completed, "aborted": not completed, "abort_reason": None if completed else
            "geofence", "mission_time_s": 700.0, "wall_time_s": 60.0, "safety_violations": 0 if completed else 1,
            "seabed_contacts": 0, "navigation_error_max_m": 0.9 + seed / 100,
            "elements": {"survey": {"kind": "survey", "status": "succeeded", "coverage_percent": coverage},
                         "photograph": {"kind": "inspect", "status": "succeeded" if camera <= 0.1 else "failed",
                                        "targets": 4, "targets_ok": 4 if camera <= 0.1 else 3,
                                        "camera_error_max_m": camera}}}


def campaign(folder: Path, runs: list[dict]) -> Path:
    from mission.sim.campaign import aggregate

    folder.mkdir(parents=True)
    for r in runs:
        (folder / f"seed-{r['seed']}").mkdir()
    (folder / "campaign.json").write_text(json.dumps(
        {"mission": "missions/x.yaml", "seeds": [r["seed"] for r in runs], "summary": aggregate(runs), "runs": runs}))
    return folder


class Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.cells: list[str] = []
        self.links: list[str] = []
        self.images: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "a":
            self.links.append(attrs["href"])
        if tag == "img":
            self.images.append(attrs["src"])

    def handle_data(self, data):
        if data.strip():
            self.cells.append(data.strip())


@pytest.fixture
def two_campaigns(tmp_path):
    before = campaign(tmp_path / "before", [run(1, True, 0.06, 99.5), run(2, True, 0.12, 99.4), run(3, False, 0.05,
                                                                                                        98.0)])
    after = campaign(tmp_path / "after", [run(1, True, 0.05, 99.6), run(2, True, 0.08, 99.5), run(3, True, 0.07, 99.3)])
    return before, after


def test_the_report_compares_two_campaigns_and_lists_the_worst_seeds_with_links(two_campaigns, tmp_path):
    before, after = two_campaigns
    out = subprocess.run([sys.executable, "-m", "mission", "report", str(after), "--against", str(before)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    page = Page()
    page.feed((after / "report.html").read_text(encoding="utf-8"))
    cells = page.cells
    assert cells[cells.index("completed") + 1: cells.index("completed") + 3] == ["3 (100.0 %)", "2 (66.7 %)"]
    camera = next(i for i, c in enumerate(cells) if c.startswith("inspect: worst camera error"))
    assert cells[camera + 1: camera + 3] == ["0.07 / 0.08", "0.06 / 0.12"]  # median / worst of each campaign
    # worst first: the run that did not complete, then by camera error; links relative to the page
    assert page.links[:3] == ["seed-2/", "seed-3/", "seed-1/"]
    assert page.links[3:6] == ["../before/seed-3/", "../before/seed-2/", "../before/seed-1/"]
    assert len(page.images) == 1 and page.images[0].startswith("data:image/png;base64,")


def test_a_folder_without_a_campaign_is_one_line_and_exit_1(tmp_path):
    out = subprocess.run([sys.executable, "-m", "mission", "report", str(tmp_path)], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 1 and "not a campaign folder" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.skipif(shutil.which("chromium") is None, reason="Chromium is not installed (Debian: apt install chromium)")
def test_a_headless_browser_renders_the_page_with_its_figures(two_campaigns, tmp_path):
    import numpy as np
    from matplotlib.image import imread

    before, after = two_campaigns
    from mission.campaign_report import load_campaign, render

    page = render(load_campaign(after), load_campaign(before), after / "report.html")
    shot = tmp_path / "shot.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                    "--window-size=1600,1400", page.as_uri()], capture_output=True, timeout=120, check=True)
    image = imread(shot)[..., :3]
    # the figures are drawn: a good share of the screenshot is neither white nor text grey
    coloured = np.mean((image.max(axis=2) - image.min(axis=2)) > 0.2)
    assert coloured > 0.005
