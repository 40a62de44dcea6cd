"""The fixed split of the real clips into folds, and the report's aggregation over folds, classes and clips.

The split is a pure function of the clip names, so it is the same on every machine and does not change when the
trackers or this code around it change:

1. A clip's **class** is its name without the trailing ``_NNN``: ``svan_ir_bird_005`` is ``svan_ir_bird`` (thermal
   birds), ``antiuav_ir_09`` is ``antiuav_ir`` (Anti-UAV's thermal drones, kept apart from Halmstad's thermal drones:
   640x512 frames, labels made by a tracker). Classes are modality x target kind.
2. Within a class the names are sorted and dealt round-robin to the folds 0, 1, 2, 3, the first going to fold
   ``crc32(class) % 4``, so that the classes' left-over clips do not all fall into fold 0 (on the 116 clips each fold
   gets 29).

A clip's fold depends only on its own class's names: adding a clip to one class leaves every other class's folds as
they are, and a clip numbered after all others of its class leaves its own class's earlier clips where they are.
"""

from __future__ import annotations

import re
import zlib
from collections import defaultdict

import numpy as np

N_FOLDS = 4
# goal 3 of the real-footage issue: ECO-hc "collapses" on a clip when it scores below this share of ECO-deep's
# success while ECO-deep scores at least COLLAPSE_FLOOR
COLLAPSE_RATIO = 0.6
COLLAPSE_FLOOR = 50.0


def clip_class(name: str) -> str:
    """The clip's class (modality x target kind): its name without the trailing ``_NNN``."""
    return re.sub(r"_\d+$", "", name)


def folds(names: list[str], n_folds: int = N_FOLDS) -> dict[str, int]:
    """Each clip's fold, stratified by class (see the module's description of the rule)."""
    if len(set(names)) != len(names):
        raise ValueError("clip names must be unique; the split is defined on names")
    by_class = defaultdict(list)
    for n in names:
        by_class[clip_class(n)].append(n)
    out = {}
    for cls, members in by_class.items():
        first = zlib.crc32(cls.encode()) % n_folds
        for i, n in enumerate(sorted(members)):
            out[n] = (first + i) % n_folds
    return out


def parse_folds(text: str | None, n_folds: int = N_FOLDS) -> list[int]:
    """``"0,1"`` -> ``[0, 1]``; an empty or absent text is no folds."""
    if not text:
        return []
    picked = sorted({int(t) for t in text.split(",") if t.strip()})
    bad = [k for k in picked if not 0 <= k < n_folds]
    if bad:
        raise ValueError(f"fold {bad[0]} does not exist; folds are numbered 0 to {n_folds - 1}")
    return picked


def groups(seqs: list[str], fold_of: dict[str, int], sets: dict[str, str], tuned: list[int],
           aside: tuple[str, ...] = ()) -> list[tuple[str, list[str]]]:
    """The report's mean rows, label and clips, empty groups left out: all clips; with ``tuned`` folds, those folds
    together and the others together; each fold; each folder of ``sets`` (clip -> folder name); the clips of
    ``aside`` (the 34-clip protocol's held-aside clips)."""
    rows = [(f"all ({len(seqs)})", list(seqs))]
    if tuned:
        on = [s for s in seqs if fold_of[s] in tuned]
        off = [s for s in seqs if fold_of[s] not in tuned]
        names = ",".join(map(str, tuned))
        rows += [(f"tuned on, folds {names} ({len(on)})", on), (f"not tuned on ({len(off)})", off)]
    for k in sorted(set(fold_of[s] for s in seqs)):
        mark = " (tuned on)" if k in tuned else ""
        members = [s for s in seqs if fold_of[s] == k]
        rows.append((f"fold {k}{mark} ({len(members)})", members))
    for folder in sorted(set(sets[s] for s in seqs)):
        members = [s for s in seqs if sets[s] == folder]
        rows.append((f"{folder}/ ({len(members)})", members))
        held = [s for s in members if s in aside]
        if held:
            rows.append((f"{folder}/ held aside ({len(held)})", held))
    return [(label, members) for label, members in rows if members]


def mean_of(results: dict, seqs: list[str], name: str, key: str = "success") -> float:
    """Mean of one score of one tracker over the given clips."""
    return float(np.mean([results[(s, name)][key] for s in seqs]))


def best_peer(results: dict, seqs: list[str], peers: list[str]) -> tuple[str, float]:
    """The peer with the highest mean success over the clips, and that mean."""
    means = {p: mean_of(results, seqs, p) for p in peers}
    top = max(means, key=means.get)
    return top, means[top]


def collapses(results: dict, seqs: list[str], weak: str = "ECO-hc", strong: str = "ECO-deep",
              ratio: float = COLLAPSE_RATIO, floor: float = COLLAPSE_FLOOR) -> list[str]:
    """Clips where ``weak`` scores below ``ratio`` times ``strong``'s success while ``strong`` scores at least
    ``floor``, worst ratio first."""
    hit = [s for s in seqs if results[(s, strong)]["success"] >= floor
           and results[(s, weak)]["success"] < ratio * results[(s, strong)]["success"]]
    return sorted(hit, key=lambda s: results[(s, weak)]["success"] / results[(s, strong)]["success"])


def class_rows(results: dict, seqs: list[str], names: list[str], peers: list[str]) -> list[tuple]:
    """Per class: ``(class, n, {tracker: mean success}, best peer, its mean)``, classes in sorted order."""
    out = []
    for cls in sorted(set(map(clip_class, seqs))):
        members = [s for s in seqs if clip_class(s) == cls]
        means = {n: mean_of(results, members, n) for n in names}
        top, top_mean = best_peer(results, members, peers) if peers else ("-", float("nan"))
        out.append((cls, len(members), means, top, top_mean))
    return out


# --- markdown ------------------------------------------------------------------------------------------------------
def _margin_heads(own: list[str], peers: list[str]) -> list[str]:
    heads = [f"{n} − CSRT" for n in own] if "CSRT" in peers else []
    return heads + [f"{n} − best peer" for n in own]


def _margins(results: dict, seqs: list[str], own: list[str], peers: list[str]) -> list[str]:
    mine = {n: mean_of(results, seqs, n) for n in own}
    cells = [f"{mine[n] - mean_of(results, seqs, 'CSRT'):+.1f}" for n in own] if "CSRT" in peers else []
    if peers:
        top, top_mean = best_peer(results, seqs, peers)
        cells += [f"{mine[n] - top_mean:+.1f} ({top})" for n in own]
    return cells


def group_table(results: dict, names: list[str], rows: list[tuple[str, list[str]]], peers: list[str]) -> list[str]:
    """Mean success of every tracker per group, and each of ours against CSRT and against the best peer by mean."""
    own = [n for n in names if n not in peers]
    heads = names + (_margin_heads(own, peers) if peers else [])
    lines = ["| clips | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]
    for label, seqs in rows:
        cells = [f"{mean_of(results, seqs, n):.1f}" for n in names]
        cells += _margins(results, seqs, own, peers) if peers else []
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def class_table(results: dict, names: list[str], seqs: list[str], peers: list[str],
                margin: float = 5.0) -> list[str]:
    """Mean success per class; ``**`` marks one of ours more than ``margin`` below the class's best peer (goal 3)."""
    own = [n for n in names if n not in peers]
    heads = ["n", *names, "best peer", *(f"{n} − best peer" for n in own)]
    lines = ["| class | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]
    for cls, n, means, top, top_mean in class_rows(results, seqs, names, peers):
        cells = [str(n), *(f"{means[m]:.1f}" for m in names), f"{top} {top_mean:.1f}"]
        for m in own:
            d = means[m] - top_mean
            cells.append(f"**{d:+.1f}**" if d < -margin else f"{d:+.1f}")
        lines.append(f"| {cls} | " + " | ".join(cells) + " |")
    return lines


def collapse_table(results: dict, seqs: list[str], fold_of: dict[str, int], peers: list[str],
                   weak: str = "ECO-hc", strong: str = "ECO-deep") -> list[str]:
    """The clips of :func:`collapses`, with their fold, both scores, their ratio and the best peer on the clip."""
    lines = [f"| clip | fold | {weak} | {strong} | ratio | best peer |", "|---|---:|---:|---:|---:|---|"]
    hit = collapses(results, seqs, weak, strong)
    if not hit:
        return lines + ["| none | | | | | |"]
    for s in hit:
        w, d = results[(s, weak)]["success"], results[(s, strong)]["success"]
        top = max(peers, key=lambda p: results[(s, p)]["success"]) if peers else None
        peer = f"{top} {results[(s, top)]['success']:.1f}" if top else "-"
        lines.append(f"| {s} | {fold_of[s]} | {w:.1f} | {d:.1f} | {w / d:.2f} | {peer} |")
    return lines
