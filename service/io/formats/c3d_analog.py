"""The label confidences of a written C3D, as analog channels, past 255 channels too.

A C3D parameter holds at most 255 values per dimension, so a file with more analog channels
goes on in ``ANALOG:LABELS2``, ``SCALE2``, ``UNITS2``, ... (the convention ezc3d and Vicon
read). ezc3d's Python writer splits the labels itself, but copies the other per-channel
parameters whole when they have one value per channel, which no reader takes back past 255,
and fills them with defaults otherwise. So past 255 channels those parameters are left to its
defaults and written afterwards, split, through ezc3d's own C++ layer (``fix_channels``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import ezc3d
import numpy as np
from ezc3d import ezc3d as ezc3d_core

from service.io.recording import LabeledTrajectories

CONFIDENCE_SUFFIX = "_confidence"  # analog channel <marker>_confidence holds that marker's label confidence
CONFIDENCE_DESCRIPTION = "markerflow label confidence"
PARAMETER_VALUES = 255  # most values of one C3D parameter dimension (and bytes of one label)
CHANNEL_TEXTS = ("DESCRIPTIONS", "UNITS")
CHANNEL_NUMBERS = ("SCALE", "OFFSET")

ChannelParameters = dict[str, list]  # a per-channel ANALOG parameter, one value per channel, whole


def with_confidence(c3d: ezc3d.c3d, traj: LabeledTrajectories, start: int) -> ChannelParameters:
    """Append one analog channel ``<marker>_confidence`` per labeled marker (in place); returns
    the per-channel parameters ``fix_channels`` must write after ezc3d (empty up to 255
    channels, where ezc3d writes them right).

    Why analog channels: a C3D parameter holds at most 255 values per dimension and about
    32 kB in all (ezc3d refuses to read back a MARKERFLOW:CONFIDENCE of 2 x 900 values),
    far less than markers x frames; and the POINT residual is stored as an 8-bit multiple
    of POINT:SCALE (0.5 reads back as 0 with the default scale) and means a reconstruction
    error where negative marks a gap. Analog channels are C3D's place for any per-frame
    signal: each frame's value is repeated over the analog samples of that frame (the
    file's own analog rate, or the point rate when it had none), 0 in frames outside the
    labels. Channels of these names already in the file (a relabeled markerflow output)
    are replaced. A label too long for the suffix is cut (``confidence_labels``), and its
    description names the point.
    """
    analog, frames = c3d["parameters"]["ANALOG"], c3d["data"]["points"].shape[2]
    data = c3d["data"]["analogs"]
    ratio = data.shape[2] // frames if data.size else 1
    labels = [str(label).strip() for label in joined_values(analog, "LABELS")] if data.size else []
    names = confidence_labels(traj.names)
    points = [str(label).strip() for label in joined_values(c3d["parameters"]["POINT"], "LABELS")]
    described = [CONFIDENCE_DESCRIPTION if label == f"{name}{CONFIDENCE_SUFFIX}" else
                 _cut(f"{CONFIDENCE_DESCRIPTION} of point {points.index(name) + 1} ({name})", PARAMETER_VALUES)
                 for name, label in zip(traj.names, names, strict=True)]
    kept = [i for i, label in enumerate(labels) if label not in names]
    values = np.zeros((len(names), frames))
    values[:, start : start + traj.n_frames] = np.nan_to_num(traj.confidence.T, nan=0.0)
    added = np.repeat(values, ratio, axis=1)[None]
    c3d["data"]["analogs"] = np.concatenate([data[:, kept], added], axis=1) if data.size else added
    channels: ChannelParameters = {"LABELS": [labels[i] for i in kept] + names}
    for key, added_texts in zip(CHANNEL_TEXTS, (described, ["1"] * len(names)), strict=True):
        texts = list(joined_values(analog, key)) if data.size else []
        texts += [""] * (len(labels) - len(texts))
        channels[key] = [texts[i] for i in kept] + added_texts
    for key, number in zip(CHANNEL_NUMBERS, (1.0, 0.0), strict=True):
        numbers = [float(v) for v in np.ravel(joined_values(analog, key))] if data.size else []
        numbers += [number] * (len(labels) - len(numbers))
        channels[key] = [numbers[i] for i in kept] + [number] * len(names)
    if not data.size:
        analog["RATE"]["value"] = np.array([float(c3d["parameters"]["POINT"]["RATE"]["value"][0])])
    return _set_channels(analog, channels)


def confidence_labels(names: list[str]) -> list[str]:
    """The analog channel label of each marker's confidence: ``<name>_confidence``, or where
    that passes the 255 bytes a C3D label holds (ezc3d then writes a file no reader opens),
    the name cut to fit ``<cut name>~<marker number>_confidence``, unique among them all."""
    full = [f"{name}{CONFIDENCE_SUFFIX}" for name in names]
    labels: list[str] = []
    taken = {label for label in full if len(label.encode()) <= PARAMETER_VALUES}
    for number, (name, label) in enumerate(zip(names, full, strict=True), start=1):
        while len(label.encode()) > PARAMETER_VALUES or (label in taken and label != full[len(labels)]):
            tail = f"~{number}{CONFIDENCE_SUFFIX}"
            label = _cut(name, PARAMETER_VALUES - len(tail.encode())) + tail
            number += len(names)  # a cut label that another marker's name spells in full: the next number
        taken.add(label)
        labels.append(label)
    return labels


def _cut(text: str, limit: int) -> str:
    """``text`` cut to at most ``limit`` UTF-8 bytes, whole characters only."""
    return text.encode()[:limit].decode(errors="ignore")


def fix_channels(path: str, channels: ChannelParameters) -> None:
    """Write the per-channel parameters ezc3d's Python writer cannot split (module docstring)
    into the C3D at ``path``, each as ``KEY``, ``KEY2``, ... of at most 255 values."""
    if not channels:
        return
    core = ezc3d_core.c3d(path)
    for key, values in channels.items():
        for name, chunk in _chunks(key, values):
            parameter = ezc3d_core.Parameter(name)
            if key in CHANNEL_TEXTS:
                parameter.set(ezc3d_core.VecString(chunk), [len(chunk)])
            elif key == "OFFSET":
                parameter.set(ezc3d_core.VecInt([int(round(v)) for v in chunk]), [len(chunk)])
            else:
                parameter.set(ezc3d_core.VecDouble(chunk), [len(chunk)])
            core.parameter("ANALOG", parameter)
    core.write(path, ezc3d_core.WriteOptions(True, False))


def _set_channels(analog: dict, channels: ChannelParameters) -> ChannelParameters:
    """Set ``channels`` in the ezc3d dictionary ``analog``: whole up to 255 channels; past
    that the labels split (ezc3d joins them) and the rest returned for ``fix_channels``."""
    for key in channels:
        for stale in [k for k in analog if re.fullmatch(rf"{key}\d+", k)]:
            del analog[stale]
    count = len(channels["LABELS"])
    if count <= PARAMETER_VALUES:
        for key, values in channels.items():
            analog[key]["value"] = values if key in CHANNEL_TEXTS + ("LABELS",) else np.asarray(values)
        return {}
    for name, chunk in _chunks("LABELS", channels["LABELS"]):
        analog[name] = {"type": ezc3d_core.CHAR, "description": "", "is_locked": False, "value": chunk}
    for key in CHANNEL_TEXTS + CHANNEL_NUMBERS:  # not one value per channel: ezc3d writes defaults
        analog.pop(key, None)
    return {key: values for key, values in channels.items() if key != "LABELS"}


def joined_values(group: dict, key: str) -> list:
    """A parameter group's ``KEY`` continued in ``KEY2``, ``KEY3``, ... past 255 values (absent: empty)."""
    keys = sorted((k for k in group if re.fullmatch(rf"{key}\d*", k)), key=lambda k: int(k[len(key):] or 1))
    return [value for k in keys for value in np.ravel(group[k]["value"]).tolist()]


def _chunks(key: str, values: Sequence) -> list[tuple[str, list]]:
    """``(KEY, first 255), (KEY2, next 255), ...``."""
    return [(key if i == 0 else f"{key}{i // PARAMETER_VALUES + 1}", list(values[i : i + PARAMETER_VALUES]))
            for i in range(0, len(values), PARAMETER_VALUES)]
