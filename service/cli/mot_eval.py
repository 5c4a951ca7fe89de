"""``markerflow mot-eval``: HOTA, MOTA, IDF1 and identity switches of a MOTChallenge result (TrackEval)."""

from __future__ import annotations

import json
from pathlib import Path

from rich.table import Table

from service.boxes.mot_checks import few_matched_warning
from service.boxes.scores import mot_scores
from service.cli.report import out, warn

LABELS = {"hota": "HOTA", "deta": "DetA", "assa": "AssA", "mota": "MOTA", "idf1": "IDF1",
          "id_switches": "ID switches", "gt_ids": "ground-truth ids", "result_ids": "result ids", "frames": "frames",
          "matched": "result boxes on a ground-truth box"}


def run_mot_eval(result: Path, gt: Path, seqinfo: Path | None, as_json: bool) -> None:
    """Score ``result`` against ``gt`` and print the figures (one JSON line with ``as_json``);
    a figure that does not exist (``matched`` of an empty result) is null, ``-`` in the table."""
    found = mot_scores(result, gt, seqinfo)
    scores, warnings = found.as_dict(), [*found.warnings, few_matched_warning(found.matched, result, gt)]
    if as_json:
        print(json.dumps(scores))
    else:
        table = Table(title=f"{result.name} against {gt}", show_header=False)
        for key, value in scores.items():
            table.add_row(LABELS[key], "-" if value is None else f"{value:.3f}" if isinstance(value, float) else str(value))
        out.print(table)
    for warning in warnings:
        warn(warning)
