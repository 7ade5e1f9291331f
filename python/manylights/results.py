"""``load_results``: an experiment's ``cells.csv`` (what ``cargo xtask run-experiments`` writes
beside its tables) as one dict per cell, numbers as numbers, so a notebook can re-plot a table."""
import csv
import json
from pathlib import Path


def _value(text):
    if text == "":
        return None
    if text in ("true", "false"):
        return text == "true"
    if text[0] in "{[":
        try:
            return json.loads(text)
        except ValueError:
            return text
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def load_results(path, as_frame=False):
    """The cells of ``path`` (an experiment's results folder, e.g. ``results/paper``, or its
    ``cells.csv``): a list of dicts, one per cell, keyed by the CSV's columns (``scene``,
    ``strategy``, ``budget``, ``seed``, ``spp``, ``rel_mse_unlit``, ``flip_all``, ...). With
    ``as_frame=True`` a pandas DataFrame instead (pandas is not a dependency)."""
    path = Path(path)
    csv_path = path / "cells.csv" if path.is_dir() else path
    if not csv_path.is_file():
        raise FileNotFoundError(f"{csv_path}: no such results table (cells.csv)")
    with open(csv_path, newline="", encoding="utf-8") as f:
        cells = [{k: _value(v) for k, v in row.items()} for row in csv.DictReader(f)]
    if as_frame:
        import pandas

        return pandas.DataFrame(cells)
    return cells
