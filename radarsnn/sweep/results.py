"""The results file of a sweep (JSON lines, one record per cell) and its summary per point.

Records are appended as cells finish, in whatever order they finish; the
file is the sweep's only state.  :func:`read_records` takes back what a killed
run left (a torn last line is cut off), :func:`summarize` groups the records of
the current spec by point, adds their sums **in frame order** and applies each
metric's formula, so the summary is identical whatever the workers did.

Examples
--------
>>> import tempfile
>>> path = Path(tempfile.mkdtemp()) / "results.jsonl"
>>> append_record(path, {"cell": "a", "x": 1})
>>> _ = path.open("a").write('{"cell": "b", "x"')   # a run killed mid-line
>>> [r["cell"] for r in read_records(path)]
['a']
>>> path.read_text()
'{"cell": "a", "x": 1}\\n'
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

from ir.errors import ArtifactError
from radarsnn.cli.chain import write_output
from radarsnn.sweep.cost import finalize_cost

__all__ = ["RESULTS_FILE", "append_record", "read_records", "summarize", "write_summary"]

RESULTS_FILE = "results.jsonl"
#: Cost fields of a record that are sums over its frames (the rest is the program's).
RUN_COUNTS = ("spikes", "synaptic_events", "clipped", "frames")


def append_record(path: Path, record: dict[str, Any]) -> None:
    """Append one record as a JSON line and flush it to the disk."""
    with Path(path).open("a") as f:
        f.write(json.dumps(record, sort_keys=True) + "\n")
        f.flush()


def read_records(path: Path) -> list[dict[str, Any]]:
    """The records of a results file (none if it does not exist); cuts a torn last line.

    Raises
    ------
    ArtifactError
        A complete line that is not a JSON record (the file was edited or is not ours).
    """
    path = Path(path)
    if not path.exists():
        return []
    text = path.read_text()
    if text and not text.endswith("\n"):
        keep = text[:text.rfind("\n") + 1]
        write_output(path, keep.encode(), "the results")  # atomic: a kill keeps every record
        text = keep
    records = []
    for n, line in enumerate(text.splitlines(), 1):
        try:
            rec = json.loads(line)
        except json.JSONDecodeError as err:
            raise ArtifactError(f"results file {str(path)!r}, line {n}: not JSON ({err}); "
                                "delete the line or the file to recompute those cells") from None
        if not isinstance(rec, dict) or "cell" not in rec:
            raise ArtifactError(f"results file {str(path)!r}, line {n}: not a cell record")
        records.append(rec)
    return records


def _add(total: dict, part: dict) -> None:
    for k, v in part.items():
        total[k] = total.get(k, 0) + v


def summarize(records: list[dict[str, Any]], points: list[dict[str, Any]],
              registry) -> list[dict[str, Any]]:
    """One summary row per point, from its cells' records.

    Parameters
    ----------
    records : list of dict
        Cell records (any order; records of other specs are ignored).
    points : list of dict
        Per point, in spec order: ``point`` (id), ``params``, ``cells`` (cell ids in
        slice order) and ``metrics`` (``[(key, name)]``).
    registry : MetricRegistry
        Gives each metric's ``finalize``.

    Returns
    -------
    list of dict
        ``point``, ``params``, ``complete`` (every cell done), ``error`` (the first
        cell error, or None), ``metrics`` ({key: figures}) and ``cost``.
    """
    by_cell = {r["cell"]: r for r in records}
    rows = []
    for p in points:
        done = [by_cell[c] for c in p["cells"] if c in by_cell]
        errors = [r["error"] for r in done if r.get("error")]
        row: dict[str, Any] = {"point": p["point"], "params": p["params"],
                               "complete": len(done) == len(p["cells"]),
                               "error": errors[0] if errors else None, "metrics": {},
                               "cost": {}}
        ok = [r for r in done if not r.get("error")]
        if ok:
            sums: dict[str, dict] = {key: {} for key, _ in p["metrics"]}
            runs: dict[str, int] = {}
            for r in ok:  # slice order: float sums do not depend on arrival order
                for key, _ in p["metrics"]:
                    _add(sums[key], r["metrics"].get(key, {}))
                _add(runs, {k: r["cost"].get(k, 0) for k in RUN_COUNTS})
            row["metrics"] = {key: registry[name].finalize(sums[key])
                              for key, name in p["metrics"]}
            static = {k: v for k, v in ok[0]["cost"].items()
                      if k not in RUN_COUNTS}
            row["cost"] = {**static, **finalize_cost(runs)}
        rows.append(row)
    return rows


def _flat(row: dict[str, Any]) -> dict[str, Any]:
    out = {"point": row["point"], **row["params"], "complete": row["complete"],
           "error": row["error"] or ""}
    for key, figures in row["metrics"].items():
        out |= {f"{key}.{k}": v for k, v in figures.items()}
    out |= {f"cost.{k}": v for k, v in row["cost"].items()}
    return {k: json.dumps(v) if isinstance(v, (dict, list)) else v for k, v in out.items()}


def write_summary(rows: list[dict[str, Any]], out_dir: Path) -> tuple[Path, Path]:
    """Write ``summary.json`` (the rows) and ``summary.csv`` (flattened, one row a point),
    each atomically (whole, or the previous one kept)."""
    out_dir = Path(out_dir)
    js = out_dir / "summary.json"
    write_output(js, (json.dumps(rows, indent=1, sort_keys=True) + "\n").encode(), "the summary")
    flat = [_flat(r) for r in rows]
    columns = list(dict.fromkeys(k for r in flat for k in r))
    path = out_dir / "summary.csv"
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=columns)
    writer.writeheader()
    writer.writerows(flat)
    write_output(path, text.getvalue().encode(), "the summary")
    return js, path
