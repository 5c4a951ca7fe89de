"""Every labeled recording of ../shared/data relabeled by `markerflow track`, scored against its own labels.

Each take is relabeled from its own labels at S, the first frame with the most markers
labeled (0 when frame 0 has them all), as a user would:
`markerflow track TAKE --out OUT.c3d --json --start S --end E` (markers absent at S stay
unlabeled and count as missing). `--half` starts a take lacking a marker in frame 0 at its
middle frame H instead; `--starts K` at K frames spread evenly over it (at 1/(K+1) .. K/(K+1)
of its length, `--cap` frames from each, 600 unless given): one take's labels are a chain in
which one early decision, right or wrong, decides what is lost later, so a rule is judged on
many starts, not on one run. With `--model`, such a take is labeled with a subject model fitted
on the frames before its start (``fit_subject``, what `markerflow model` runs; its first half
with `--half`): `markerflow track TAKE --model M.json --start S [--end E]` identifies the
start frame from the model; with `--keep-labels` too, the file's labels there are kept and
the model names only the markers absent there (`track --keep-labels`). Each output is read
back and compared, marker by marker and frame by frame, with the file's own labels (a
marker the model lacks counts as missing where present):

- correct: the marker took its own point;
- wrong: it took a point, but another marker's (its own was present);
- missing: its own point was present, it took none;
- extra: it took a point in a frame where it has none of its own;
- in breaks: labels (points taken) inside the summary's shape breaks, where a label left the
  shape its rigid neighbours keep (``service/labeling/shape_doubt.py``); right there: how
  many of those are right (what ``SHAPE_BREAK_CONFIDENCE`` stands for).

Accuracy = correct / (marker-frames present in the file), over the labeled frames, frame
`start` included; "reachable" the accuracy a route could reach at most: the share of those
marker-frames whose marker it can name at all (not one absent at the start without a model,
nor one the model lacks); "off jumps" the same without the marker-frames where the file's own labels
jump to another marker after a gap (``service/evaluation/label_jumps.py``), where the file is
no truth. The recordings are those of ``service.evaluation.matrix.RECORDINGS`` (the
Pose2Sim TRCs are left out there: triangulated video keypoints, not markers); their
``exclude`` columns (copies, a trigger) are kept, as `track` gets the file as it is.
Wall time is the whole command (start-up, reading, writing); frames/s is the labeling time
``seconds`` of `--json`.

`--formulation NAME` labels with another formulation (`track --formulation`; lp-l1 by default),
`--mht-reading` with `track --mht-reading`.

    .venv/bin/python bench/real_takes.py [--only NAME ...] [--cap FRAMES] [--half | --starts K] [--model [--keep-labels]]
        [--formulation NAME] [--mht-reading] [--frame-step K]

`--frame-step K` relabels every K-th frame of each take (written as a TRC beside the run, the
take's unlabeled trajectories kept; frame numbers and frames/s are the decimated take's).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.errors import FormulationError  # noqa: E402
from formulations.subject.fit import fit_subject  # noqa: E402
from service.capture.model_input import model_names  # noqa: E402
from service.evaluation.label_jumps import label_jumps  # noqa: E402
from service.evaluation.matrix import DATA, RECORDINGS  # noqa: E402
from service.io.formats import read_labeled, write_labeled  # noqa: E402
from service.io.recording import LabeledTrajectories, Recording  # noqa: E402

MARKERFLOW = [sys.executable, "-m", "service.cli"]  # the interpreter running this bench, as `markerflow`
SAME_POINT_MM = 1e-3  # the output holds the input's own coordinates, through a unit round trip


@dataclass
class Row:
    name: str
    route: str
    frames: int
    markers: int
    correct: int = 0
    wrong: int = 0
    missing: int = 0
    extra: int = 0
    on_jumps: int = 0  # present marker-frames where the file's label jumped
    correct_on_jumps: int = 0
    out_of_reach: int = 0  # present marker-frames of markers the route cannot name (absent at the start, no model)
    in_breaks: int = 0  # labels inside the summary's shape breaks
    right_in_breaks: int = 0
    wall: float = float("nan")
    seconds: float = float("nan")
    failure: str = ""

    def cells(self) -> str:
        present = self.correct + self.wrong + self.missing
        if self.failure:
            return f"| {self.name} | {self.route} | {self.frames} | {self.markers} | {self.failure} | | | | | | | | | | |"
        off_jumps = (self.correct - self.correct_on_jumps) / (present - self.on_jumps)
        right_there = f"{self.right_in_breaks / self.in_breaks:.0%}" if self.in_breaks else "-"
        return (f"| {self.name} | {self.route} | {self.frames} | {self.markers} | {self.correct / present:.2%} | "
                f"{1 - self.out_of_reach / present:.2%} | {off_jumps:.2%} | "
                f"{self.wrong} | {self.missing} | {self.extra} | {present} | {self.in_breaks} | {right_there} | "
                f"{self.wall:.1f} | {self.frames / self.seconds:.0f} |")


def score(truth: Recording, output: Recording, rows: slice, row: Row, labeled: list[str] | None = None) -> None:
    """Count correct/wrong/missing/extra over the truth's frames ``rows`` (output aligned by frame and name).

    ``labeled``: the markers markerflow labeled (a model's); the file's others, which a .c3d
    output keeps as the input had them, count as missing where present."""
    theirs, missing_out = _aligned(truth, output, rows)
    jumped = label_jumps(truth)[rows]
    for i, name in enumerate(truth.names):
        own = ~truth.missing()[rows, i]
        if name not in output.names or (labeled is not None and name not in labeled):
            row.missing += int(own.sum())
            row.out_of_reach += int(own.sum())
            continue
        if labeled is None and not own[0]:  # absent at the start: track leaves it unlabeled
            row.out_of_reach += int(own.sum())
        j = output.names.index(name)
        took = ~missing_out[rows, j]
        same = np.linalg.norm(theirs[rows, j] - truth.positions[rows, i], axis=1) <= SAME_POINT_MM
        row.correct += int((own & took & same).sum())
        row.wrong += int((own & took & ~same).sum())
        row.missing += int((own & ~took).sum())
        row.extra += int((~own & took).sum())
        row.on_jumps += int((own & jumped[:, i]).sum())
        row.correct_on_jumps += int((own & took & same & jumped[:, i]).sum())


def _aligned(truth: Recording, output: Recording, rows: slice) -> tuple[np.ndarray, np.ndarray]:
    """The output's positions and missing mask over the truth's frames."""
    theirs = output.positions if output.n_frames == truth.n_frames else None
    if theirs is None:  # an output holding only the labeled frames
        theirs = np.full(truth.positions.shape[:1] + (output.n_markers, 3), np.nan)
        theirs[rows][: output.n_frames] = output.positions[: rows.stop - rows.start]
    missing_out = output.missing() if output.n_frames == truth.n_frames else np.isnan(theirs).any(axis=2)
    return theirs, missing_out


def score_breaks(truth: Recording, output: Recording, rows: slice, breaks: list[dict], row: Row) -> None:
    """Count the labels inside the summary's shape breaks (``service.labeling.shape_doubt``) and
    how many of them are right: what ``SHAPE_BREAK_CONFIDENCE`` stands for."""
    theirs, missing_out = _aligned(truth, output, rows)
    for each in breaks:
        i, j = truth.names.index(each["marker"]), output.names.index(each["marker"])
        frames = slice(rows.start + each["frames"][0], rows.start + each["frames"][1])
        took = ~missing_out[frames, j]
        same = np.linalg.norm(theirs[frames, j] - truth.positions[frames, i], axis=1) <= SAME_POINT_MM
        row.in_breaks += int(took.sum())
        row.right_in_breaks += int((took & same & ~truth.missing()[frames, i]).sum())


def run(command: list[str], row: Row) -> dict | None:
    began = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    row.wall = time.perf_counter() - began
    if done.returncode != 0:
        row.failure = f"rc {done.returncode}: {(done.stderr.strip().splitlines() or ['?'])[-1][:120]}"
        return None
    summary: dict = json.loads(done.stdout.strip().splitlines()[-1])
    row.seconds = summary["seconds"]
    return summary


@dataclass(frozen=True)
class Route:
    """How a take lacking a marker in frame 0 is labeled (a take with every marker in frame 0
    is relabeled from frame 0 by every route).

    at: start at this fraction of the take's length instead of S, the frame with the most
        markers labeled (``--half``: 0.5).
    model: fit a subject model on the frames before the start (``track --model``), identify the
        start frame from it unless ``keep_labels`` (``track --keep-labels``).
    """

    at: float | None = None
    model: bool = False
    keep_labels: bool = False

    def label(self, start: int) -> str:
        if not self.model:
            return f"frame {start}"
        return f"model of 0-{start - 1}{' + labels' if self.keep_labels else ''}"


def relabel(
    name: str, path: Path, truth: Recording, cap: int, folder: Path, route: Route, formulation: str, mht: bool = False,
) -> Row:
    """Relabel the take at ``path`` (read as ``truth``) by ``route`` with ``formulation`` (and
    ``track --mht-reading`` when ``mht``) and score it."""
    missing = truth.missing()
    out = folder / f"{name}.c3d"
    partial = bool(missing[0].any())
    start = int(np.argmax((~missing).sum(axis=1)))  # 0 when frame 0 has every marker
    if partial and route.at is not None:
        start = int(truth.n_frames * route.at)
    end = min(truth.n_frames, start + cap) if cap else truth.n_frames
    command = [*MARKERFLOW, "track", str(path), "--out", str(out), "--json", "--start", str(start), "--end", str(end),
               "--formulation", formulation, *(["--mht-reading"] if mht else [])]
    if not (partial and route.model and start > 0):  # no frame before the start: nothing to fit a model on
        row = Row(name, Route().label(start), end - start, truth.n_markers)
        if (summary := run(command, row)) is not None:
            score(truth, read_labeled(out), slice(start, end), row)
            score_breaks(truth, read_labeled(out), slice(start, end), summary["shape_breaks"], row)
        return row
    row = Row(name, route.label(start), end - start, truth.n_markers)
    present = np.where(missing[:, :, None], np.nan, truth.positions)
    try:
        model = fit_subject(list(truth.names), present[:start]).model
    except FormulationError as error:
        row.failure = f"model fit refused: {error}"[:140]
        return row
    model_path = folder / f"{name}.json"
    model_path.write_text(model.to_json())
    command += ["--model", str(model_path), *(["--keep-labels"] if route.keep_labels else [])]
    if (summary := run(command, row)) is not None:
        score_breaks(truth, read_labeled(out), slice(start, end), summary["shape_breaks"], row)
        # with its labels kept, the start frame's markers the model lacks are labeled too (as singles)
        kept = [n for i, n in enumerate(truth.names) if route.keep_labels and not missing[start, i]]
        score(truth, read_labeled(out), slice(start, end), row, [*model_names(model), *kept])
    return row


def every_kth_frame(path: Path, step: int, folder: Path) -> Path:
    """The take at ``path`` with every ``step``-th frame kept, written as a TRC in ``folder`` (its
    unlabeled trajectories kept as its *N columns): the take as a system capturing at 1/``step``
    of its rate would have recorded it. A C3D's analog data and parameters are not carried."""
    kept = read_labeled(path).every(step)
    missing = kept.missing()
    out = folder / f"{path.stem}_every{step}.trc"
    write_labeled(out, LabeledTrajectories(kept.names, np.where(missing[..., None], np.nan, kept.positions), missing, kept.rate))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    # choices: a misspelt or file name (03_rolling for numediart-rolling) is refused, not an empty table
    parser.add_argument("--only", nargs="*", choices=[r.name for r in RECORDINGS], metavar="NAME",
                        help="recording names (service.evaluation.matrix.RECORDINGS)")
    parser.add_argument("--cap", type=int, default=0, help="label at most this many frames of each take")
    parser.add_argument("--model", action="store_true", help="label a take without a full frame 0 from a model of the "
                        "frames before its start (its first half with --half)")
    parser.add_argument("--keep-labels", action="store_true", help="with --model: keep the file's labels at the start frame")
    parser.add_argument("--half", action="store_true", help="start a take lacking a marker in frame 0 at its middle frame")
    parser.add_argument("--starts", type=int, default=0, help="start a take lacking a marker in frame 0 at this many "
                        "frames spread over it (--cap frames from each, 600 unless given)")
    parser.add_argument("--formulation", default="lp-l1", help="track --formulation (default lp-l1)")
    parser.add_argument("--mht-reading", action="store_true", help="track --mht-reading")
    parser.add_argument("--frame-step", type=int, default=1, help="relabel every k-th frame of each take (as a TRC "
                        "with its unlabeled trajectories): the take at 1/k of its frame rate")
    args = parser.parse_args()
    if args.frame_step < 1:
        parser.error(f"--frame-step must be 1 or more, got {args.frame_step}")
    fractions = [(k + 1) / (args.starts + 1) for k in range(args.starts)] if args.starts else [0.5 if args.half else None]
    cap = args.cap or (600 if args.starts else 0)
    print("| take | start | frames | markers | correct | reachable | off jumps | wrong | missing | extra | present | "
          "in breaks | right there | wall s | frames/s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    means = []
    with tempfile.TemporaryDirectory() as folder:
        for recording in RECORDINGS:
            if args.only and recording.name not in args.only:
                continue
            path = DATA / recording.path
            if args.frame_step > 1:
                path = every_kth_frame(path, args.frame_step, Path(folder))
            # its markers (an unlabeled trajectory *N names none); a take with every marker in
            # frame 0 starts there on every route
            truth = read_labeled(path).without_unlabeled()
            rows = [relabel(recording.name, path, truth, cap, Path(folder), Route(at, args.model, args.keep_labels),
                            args.formulation, args.mht_reading)
                    for at in (fractions if bool(truth.missing()[0].any()) else [None])]
            print("\n".join(row.cells() for row in rows), flush=True)
            scored = [row.correct / (row.correct + row.wrong + row.missing) for row in rows if not row.failure]
            if len(rows) > 1 and scored:
                means.append(f"{recording.name}: mean {100 * np.mean(scored):.2f} % over {len(scored)} starts")
    print("\n".join(means))


if __name__ == "__main__":
    main()
