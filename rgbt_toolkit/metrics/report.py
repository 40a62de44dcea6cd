"""Render a :class:`~rgbt_toolkit.metrics.scoring.ScoreTable` as an aligned table, CSV or JSON text."""

from __future__ import annotations

import csv
import io
import json
import math

from rgbt_toolkit.metrics.conventions import LOWER_IS_BETTER
from rgbt_toolkit.metrics.scoring import ScoreTable

FORMATS = ("table", "csv", "json")


def _number(value: float, digits: int) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    return f"{value:.{digits}f}" if digits else repr(float(value))


def _rows(table: ScoreTable) -> list[dict]:
    return table.rows + table.means()


def render(table: ScoreTable, fmt: str = "table") -> str:
    """Text of the table in ``fmt`` ('table', 'csv' or 'json'); mean rows (image 'mean') follow the images."""
    if fmt == "json":  # NaN (e.g. a metric undefined on a constant image) becomes null: valid JSON
        clean = lambda rows: [{k: (None if isinstance(v, float) and math.isnan(v) else v)  # noqa: E731
                               for k, v in row.items()} for row in rows]
        payload = {
            "convention": table.convention,
            "metrics": table.metrics,
            "rows": clean(table.rows),
            "means": clean(table.means()),
            "errors": table.errors,
        }
        return json.dumps(payload, indent=2, allow_nan=False) + "\n"
    header = ["image", "method", *table.metrics]
    if fmt == "csv":
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(header)
        for row in _rows(table):
            writer.writerow([row["image"], row["method"], *(_number(row[m], 0) for m in table.metrics)])
        return buffer.getvalue()
    if fmt != "table":
        raise ValueError(f"unknown format {fmt!r}; choose one of {', '.join(FORMATS)}")
    titles = ["image", "method", *(f"{m}{'(-)' if m in LOWER_IS_BETTER else ''}" for m in table.metrics)]
    body = [[row["image"], row["method"] or "-", *(_number(row[m], 4) for m in table.metrics)] for row in table.rows]
    means = [[row["image"], row["method"] or "-", *(_number(row[m], 4) for m in table.metrics)]
             for row in table.means()]
    widths = [max(len(cells[i]) for cells in [titles, *body, *means]) for i in range(len(titles))]

    def line(cells: list[str]) -> str:
        return "  ".join(c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths))).rstrip()

    out = [f"convention: {table.convention}  ((-) lower is better)", line(titles)]
    out += [line(cells) for cells in body]
    if means:
        out.append("-" * len(line(titles)))
        out += [line(cells) for cells in means]
    return "\n".join(out) + "\n"
