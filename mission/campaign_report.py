"""`auv report CAMPAIGN_DIR [--against OTHER_DIR]`: one HTML page for a campaign of seeded runs (`campaign.json`,
as `auv simulate --seeds` writes it): completion and success per element, the distributions of the figures that
say whether each element did its job, the worst seeds with links to their run folders, and, with `--against`, the
same figures of a second campaign beside them (for example before and after a change).

The page is self-contained (figures inlined as PNG) so that it can be mailed or archived with its folder.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import os
from pathlib import Path
from statistics import median
from typing import Any

from mission.errors import AuvError

# (element kind, figure, label, whether lower is worse)
FIGURES = (
    ("survey", "coverage_percent", "survey coverage (%)", True),
    ("explore", "surface_observed_percent", "explore: true surface observed (%)", True),
    ("inspect", "camera_error_max_m", "inspect: worst camera error per run (m)", False),
    ("inspect", "targets_ok", "inspect: targets photographed within tolerance", True),
)


def load_campaign(folder: Path) -> dict[str, Any]:
    path = folder / "campaign.json"
    try:
        data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise AuvError(f"{folder}: not a campaign folder (no campaign.json; `auv simulate MISSION --seeds …` "
                       "writes one)") from None
    except (OSError, ValueError) as exc:
        raise AuvError(f"{path}: cannot read ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("runs"), list):
        raise AuvError(f"{path}: not a campaign file (no list of runs)")
    data["folder"] = folder
    return data


def _values(campaign: dict[str, Any], kind: str, key: str) -> list[float]:
    out = []
    for run in campaign["runs"]:
        for element in run.get("elements", {}).values():
            value = element.get(key)
            if element.get("kind") == kind and isinstance(value, int | float) and math.isfinite(value):
                out.append(float(value))
    return out


def _nav_errors(campaign: dict[str, Any]) -> list[float]:
    return [float(r["navigation_error_max_m"]) for r in campaign["runs"] if "navigation_error_max_m" in r]


def worst_runs(campaign: dict[str, Any], count: int = 5) -> list[dict[str, Any]]:
    """The runs that did worst: crashed, then not completed, then by their worst inspection camera error."""
    def badness(run: dict[str, Any]) -> tuple[int, float]:
        if "error" in run:
            return (2, 0.0)
        errors = [e.get("camera_error_max_m") or 0.0 for e in run.get("elements", {}).values()]
        return (0 if run.get("completed") else 1, max(errors, default=0.0))

    return sorted(campaign["runs"], key=badness, reverse=True)[:count]


def _figure_png(campaigns: list[dict[str, Any]]) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(f"{kind}.{key}", label, [_values(c, kind, key) for c in campaigns]) for kind, key, label, _ in FIGURES]
    panels = [p for p in panels if any(p[2])]
    panels.append(("nav", "worst navigation error per run (m)", [_nav_errors(c) for c in campaigns]))
    columns = min(3, len(panels) + 1)
    rows = -(-(len(panels) + 1) // columns)
    fig, grid = plt.subplots(rows, columns, figsize=(3.6 * columns, 3.1 * rows), squeeze=False)
    axes = list(grid.flat)
    for spare in axes[len(panels) + 1:]:
        spare.set_visible(False)
    names = [c["folder"].name for c in campaigns]
    success = axes[0]
    ids = list(dict.fromkeys(i for c in campaigns for i in c["summary"]["elements"]))
    width = 0.8 / len(campaigns)
    for k, c in enumerate(campaigns):
        rates = [100.0 * c["summary"]["elements"].get(i, {}).get("succeeded", 0) /
                 max(c["summary"]["elements"].get(i, {}).get("runs", 1), 1) for i in ids]
        success.bar([x + k * width for x in range(len(ids))], rates, width, label=names[k])
    success.set_xticks([x + 0.4 - width / 2 for x in range(len(ids))], ids, rotation=45, ha="right", fontsize=7)
    success.set_ylabel("succeeded (%)")
    success.set_ylim(0, 105)
    success.set_title("success per element", fontsize=9)
    for ax, (_, label, series) in zip(axes[1:len(panels) + 1], panels, strict=True):
        for k, values in enumerate(series):
            ax.scatter([k + 0.1 * ((j % 5) - 2) for j in range(len(values))], values, s=12, label=names[k])
        ax.set_xticks(range(len(series)), names, fontsize=7)
        ax.set_xlim(-0.5, len(series) - 0.5)
        ax.set_title(label, fontsize=8)
    if len(campaigns) > 1:
        success.legend(fontsize=7)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _summary_rows(campaigns: list[dict[str, Any]]) -> list[list[str]]:
    def cell(c: dict[str, Any], getter: Any) -> str:
        try:
            return html.escape(str(getter(c)))
        except (KeyError, TypeError, ValueError):
            return "–"

    rows = [["runs", *(cell(c, lambda c: c["summary"]["runs"]) for c in campaigns)],
            ["completed", *(cell(c, lambda c: f"{c['summary']['completed']} ({c['summary']['completed_percent']} %)")
                            for c in campaigns)],
            ["aborted / crashed", *(cell(c, lambda c: f"{c['summary']['aborted']} / {c['summary']['crashed']}")
                                    for c in campaigns)],
            ["safety violations", *(cell(c, lambda c: c["summary"]["safety_violations"]) for c in campaigns)]]
    for kind, key, label, lower_worse in FIGURES:
        series = [_values(c, kind, key) for c in campaigns]
        if any(series):
            rows.append([f"{label}: median / worst",
                         *(f"{median(v):.4g} / {(min(v) if lower_worse else max(v)):.4g}" if v else "–"
                           for v in series)])
    return rows


def render(campaign: dict[str, Any], against: dict[str, Any] | None, out: Path) -> Path:
    """Write the report page to `out` (links to run folders relative to it); returns its path."""
    campaigns = [campaign] + ([against] if against is not None else [])
    title = f"Campaign report: {campaign.get('mission', campaign['folder'].name)}"
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
             "td,th{border:1px solid #ccc;padding:3px 8px;font-size:90%}img{max-width:100%}</style></head><body>",
             f"<h1>{html.escape(title)}</h1>"]
    header = "".join(f"<th>{html.escape(str(c['folder']))}</th>" for c in campaigns)
    parts.append(f"<h2>Summary</h2><table id='summary'><tr><th></th>{header}</tr>")
    for row in _summary_rows(campaigns):
        parts.append("<tr>" + "".join(f"<td>{html.escape(x) if k == 0 else x}</td>" for k, x in enumerate(row))
                     + "</tr>")
    parts.append("</table>")
    parts.append(f"<h2>Figures</h2><img id='figures' alt='campaign figures' "
                 f"src='data:image/png;base64,{_figure_png(campaigns)}'>")
    for c in campaigns:
        parts.append(f"<h2>Worst seeds of {html.escape(str(c['folder']))}</h2><table class='worst'>"
                     "<tr><th>seed</th><th>outcome</th><th>worst camera error (m)</th><th>run folder</th></tr>")
        for run in worst_runs(c):
            folder = c["folder"] / f"seed-{run['seed']}"
            link = os.path.relpath(folder, out.parent)
            outcome = ("crashed: " + str(run["error"])) if "error" in run else (
                "completed" if run.get("completed") else f"not completed ({run.get('abort_reason') or 'failed'})")
            errors = [e.get("camera_error_max_m") for e in run.get("elements", {}).values()
                      if e.get("camera_error_max_m") is not None]
            parts.append(f"<tr><td>{run['seed']}</td><td>{html.escape(outcome)}</td>"
                         f"<td>{max(errors) if errors else '–'}</td>"
                         f"<td><a href='{html.escape(link)}/'>{html.escape(link)}</a></td></tr>")
        parts.append("</table>")
    parts.append("</body></html>")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text("\n".join(parts), encoding="utf-8")
    os.replace(tmp, out)
    return out
