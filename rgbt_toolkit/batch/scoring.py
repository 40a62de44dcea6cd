"""``rgbt batch fusion-metrics``: fusion-quality metrics of many fused images, one item per fused image.

Pairing and the metrics themselves are :mod:`rgbt_toolkit.metrics` (the same as ``rgbt fusion-metrics``); the batch
adds parallel workers, a manifest and resuming. Each item writes its scores to ``OUT/scores/<fused name>.json``, so
a resumed run re-reads the finished ones, and :func:`collect_scores` assembles the table ``rgbt fusion-metrics``
prints.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rgbt_toolkit._atomic import write_text_atomic
from rgbt_toolkit.batch.items import Discovery, Item
from rgbt_toolkit.errors import InputError

if TYPE_CHECKING:  # the metrics package is imported only when a batch scores
    from rgbt_toolkit.metrics.scoring import ScoreTable


@dataclass(frozen=True)
class ScoreJob:
    """Settings of ``rgbt batch fusion-metrics``: convention, metric names, output folder."""

    out_dir: Path
    convention: str = "paper"
    metrics: tuple[str, ...] = ()  # empty: the convention's default set

    def signature(self) -> str:
        return f"fusion-metrics:{self.convention}:{','.join(self.metrics) or 'default'}"

    def score_path(self, item: Item) -> Path:
        return self.out_dir / "scores" / f"{item.key}.json"

    def expected_outputs(self, item: Item) -> list[Path]:
        return [self.score_path(item)]


def plan_scores(visible: str | os.PathLike, infrared: str | os.PathLike, fused: str | os.PathLike,
                out_dir: str | os.PathLike, convention: str = "paper", metrics: list[str] | None = None
                ) -> tuple[ScoreJob, Discovery, list[str]]:
    """The job, the items (one per fused image) and the pairing problems, checked before any worker starts.

    Raises
    ------
    InputError
        Unknown convention or metric name, or no fused image pairs with its sources.
    """
    from rgbt_toolkit.metrics.conventions import get_convention
    from rgbt_toolkit.metrics.scoring import pair_by_stem

    conv = get_convention(convention)
    names = tuple(metrics) if metrics else ()
    for name in names:
        conv.metric(name)  # unknown names fail here, not in every worker
    triples, problems = pair_by_stem(visible, infrared, fused)
    if not triples:
        raise InputError(f"{fused}: no fused image pairs with a visible and an infrared image by stem "
                         f"(<stem>.<ext> or <stem>_<method>.<ext>)")
    items = tuple(Item(t.fused.name, "triple", (t.visible, t.infrared, t.fused), (t.image, t.method))
                  for t in triples)
    keys = [item.key for item in items]
    if len(set(keys)) != len(keys):
        raise InputError(f"{fused}: two fused images share a name; score them from separate folders")
    return ScoreJob(Path(out_dir), conv.name, names), Discovery(items), problems


def score_item(item: Item, job: ScoreJob) -> list[str]:
    """Score one fused image against its sources; write the scores as JSON; return that path."""
    from rgbt_toolkit.metrics.conventions import score_triple
    from rgbt_toolkit.metrics.scoring import read_scored_image

    visible, infrared, fused = (read_scored_image(p) for p in item.paths)
    values = score_triple(visible, infrared, fused, job.convention, list(job.metrics) or None)
    image, method = item.tags
    target = job.score_path(item)
    record = {"image": image, "method": method, "fused": str(item.paths[2]),
              "scores": {k: (None if v != v else v) for k, v in values.items()}}  # NaN -> null: valid JSON
    write_text_atomic(target, json.dumps(record, indent=1) + "\n")
    return [str(target)]


def collect_scores(job: ScoreJob, items: list[Item], failed: dict[str, str], problems: list[str]) -> ScoreTable:
    """The :class:`rgbt_toolkit.metrics.scoring.ScoreTable` of every item scored (now or by an earlier run).

    ``failed`` maps item keys to their error; those items and the pairing ``problems`` become the table's errors.
    """
    from rgbt_toolkit.metrics.conventions import get_convention
    from rgbt_toolkit.metrics.scoring import ScoreTable

    names = list(job.metrics) or list(get_convention(job.convention).default_metrics)
    table = ScoreTable(convention=job.convention, metrics=names, errors=list(problems))
    for item in items:
        if item.key in failed:
            table.errors.append(f"{item.paths[2]}: {failed[item.key]}")
            continue
        path = job.score_path(item)
        if not path.is_file():
            continue
        record = json.loads(path.read_text(encoding="utf-8"))
        scores = {k: (float("nan") if v is None else float(v)) for k, v in record["scores"].items()}
        table.rows.append({"image": record["image"], "method": record["method"], **scores})
    return table
