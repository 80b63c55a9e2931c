"""A report document: tables and figures, written as one HTML page and one JSON file.

The HTML is self-contained (PNG figures embedded as base64, inline CSS) so it can
be mailed or archived as one file; the JSON holds every table and every figure's
data, for anyone who wants the numbers rather than the pictures.
"""

from __future__ import annotations

import base64
import html
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rapidfix import __version__
from rapidfix.atomic import write_text_atomic
from rapidfix.report.figures import Figure

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.6em 0; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.7em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
thead { background: #f2f2f2; }
figure { margin: 1em 0; } figcaption { font-size: 0.9em; color: #555; }
img { max-width: 100%; }
p.note { color: #555; font-size: 0.9em; }
"""


@dataclass(frozen=True)
class Table:
    """A titled table: a header row and rows of cells (numbers or text)."""

    title: str
    headers: list[str]
    rows: list[list[Any]]
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON data."""
        return {"title": self.title, "headers": self.headers, "rows": self.rows,
                "note": self.note}


@dataclass
class Report:
    """Title, free-form summary numbers, tables and figures, in display order."""

    title: str
    summary: dict[str, Any] = field(default_factory=dict)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Everything in the report as JSON data (figures as their data, not pixels)."""
        return {
            "title": self.title,
            "rapidfix_version": __version__,
            "summary": self.summary,
            "notes": self.notes,
            "tables": [t.to_dict() for t in self.tables],
            "figures": {
                f.name: {"title": f.title, "caption": f.caption, "data": f.data}
                for f in self.figures
            },
        }

    def to_html(self) -> str:
        """A self-contained HTML page."""
        esc = html.escape
        parts = [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            f"<title>{esc(self.title)}</title><style>{_CSS}</style></head><body>",
            f"<h1>{esc(self.title)}</h1>",
        ]
        parts += [f'<p class="note">{esc(n)}</p>' for n in self.notes]
        for table in self.tables:
            parts.append(f"<h2>{esc(table.title)}</h2><table><thead><tr>")
            parts += [f"<th>{esc(h)}</th>" for h in table.headers]
            parts.append("</tr></thead><tbody>")
            for row in table.rows:
                parts.append("<tr>" + "".join(f"<td>{esc(_cell(c))}</td>" for c in row) + "</tr>")
            parts.append("</tbody></table>")
            if table.note:
                parts.append(f'<p class="note">{esc(table.note)}</p>')
        for fig in self.figures:
            data = base64.b64encode(fig.png).decode("ascii")
            parts.append(
                f"<h2>{esc(fig.title)}</h2><figure>"
                f'<img alt="{esc(fig.title)}" src="data:image/png;base64,{data}">'
                f"<figcaption>{esc(fig.caption)}</figcaption></figure>"
            )
        parts.append(f'<p class="note">rapidfix {esc(__version__)}</p></body></html>')
        return "\n".join(parts) + "\n"


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"  # four significant digits: mm and degrees alike
    return "" if value is None else str(value)


def write_report(report: Report, out_dir: str | Path, stem: str = "report") -> tuple[Path, Path]:
    """Write STEM.html and STEM.json into out_dir atomically; returns both paths."""
    out = Path(out_dir)
    html_path = write_text_atomic(out / f"{stem}.html", report.to_html())
    json_text = json.dumps(report.to_dict(), indent=1, allow_nan=False) + "\n"
    json_path = write_text_atomic(out / f"{stem}.json", json_text)
    return html_path, json_path
