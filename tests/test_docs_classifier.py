"""Every figure under *Figures* of docs/classifier.md is the recorded output of
``python benchmarks/classifier.py`` (``benchmarks/results/classifier.txt``); the dataset's split
sizes are counted from ``make_dataset``'s draws.

The run trains four networks for minutes, so the tests compare the page with the record and
check that the script still prints every line the page quotes (by reading its source).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "classifier.md"
RECORD = ROOT / "benchmarks" / "results" / "classifier.txt"
SCRIPT = ROOT / "benchmarks" / "classifier.py"

#: Page row of the figures table -> the pattern that finds its value in the record.
FIGURES = {
    "ROI sequences in the dataset": r"dataset: (\d+) ROI sequences",
    "test split (sequences)": r"test split (\d+) ",
    "test classes": r"\(classes \[(\d+), (\d+), (\d+)\]\)",
    "spike-input SNN: input spikes per sequence": r"input spikes (\d+) per sequence",
    "spike-input SNN: spikes in the four inner layers": r"spikes per layer ([\d, ]+);",
    "spike-input SNN: synaptic events / ANN MACs": r"synaptic events / ANN MACs = ([\d.]+%)",
    "compiled for `loihi`": r"step simulator: accuracy ([\d.]+%)",
    "the float SNN's accuracy": r"vs float ([\d.]+%)",
    "difference": r"\(diff ([-+][\d.]+ pp)\)",
    "per-sample agreement": r"per-sample agreement ([\d.]+%);",
    "synaptic events per sequence counted by the simulator": r"; total (\d+) = ",
    "the same / ANN MACs": r" = ([\d.]+%) of the ANN's",
    "Table-3 row": r"Object classification \(SNN\) \| (.+)$",
    "wall time of the run": r"^total (\d+ s)$",
}


def norm(value: str) -> str:
    """One spelling for a figure: no thin/ordinary spaces inside numbers, ``%`` attached,
    ASCII minus, ``|`` or ``/`` as list separators become commas.

    Examples
    --------
    >>> norm("1 654 976"), norm("−0.35 pp"), norm("97.2 %"), norm("1 024 | 1 699")
    ('1654976', '-0.35 pp', '97.2%', '1024, 1699')
    """
    value = value.replace("−", "-").replace(" %", "%").replace(" | ", ", ").replace(" / ", ", ")
    return re.sub(r"(?<=\d) (?=\d)", "", value).strip()


def _section() -> str:
    text = PAGE.read_text(encoding="utf-8")
    return text[text.index("## Figures\n"):text.index("```python\nfrom compiler.classifier")]


def _rows(section: str) -> list[list[str]]:
    return [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in section.splitlines()
            if line.startswith("|") and not set(line) <= {"|", "-", " "}]


def test_table_2_is_the_recorded_table() -> None:
    record = RECORD.read_text(encoding="utf-8")
    printed = {}
    for line in record.splitlines():
        m = re.match(r"^(\S.*?\))\s+(\d+)\s+([\d.]+%)\s+(\S+)\s+(\S+)\s+(\S+)$", line)
        if m:
            printed[m.group(1)] = [norm(v) for v in m.groups()[1:]]
    rows = [r for r in _rows(_section()) if len(r) == 6 and r[0] != "Architecture"]
    assert len(rows) == len(printed) == 5
    for name, *cells in rows:
        assert [norm(c).replace("–", "-") for c in cells] == printed[name], name


def test_every_quoted_figure_is_the_recorded_one() -> None:
    record = RECORD.read_text(encoding="utf-8")
    quoted = {r[0]: r[1] for r in _rows(_section()) if len(r) == 2 and r[0] != "figure"}
    for label, pattern in FIGURES.items():
        (row,) = [k for k in quoted if k.startswith(label)]
        found = re.search(pattern, record, re.M)
        assert found, f"{label}: not in {RECORD.name}"
        value = quoted[row].split(" (")[0] if label.startswith("wall") else quoted[row]
        assert norm(value) == norm(", ".join(found.groups())), (label, quoted[row])
    assert quoted["acceptance checks passed"] == f"{record.count('✓')} of 4"
    assert "✗" not in record
    dataset_s = re.search(r"in (\d+) s; test split", record).group(1)
    assert quoted["wall time of the run (of which the dataset)"].endswith(f"({dataset_s} s)")


def test_the_script_still_prints_those_lines() -> None:
    source = SCRIPT.read_text(encoding="utf-8")
    for piece in ("ROI sequences", "test split", "input spikes", "spikes per layer",
                  "synaptic events / ANN MACs", "step simulator: accuracy", "per-sample agreement",
                  "of the ANN's", "Table 3 row", "Acceptance checks", "total "):
        assert piece in source, piece


def _split_sizes(n_scenes: int, seed: int, fractions=(0.7, 0.15), max_objects: int = 3):
    """Sequences per split of ``make_dataset``, from its first draws of each scene (the split
    and the object count come before anything is synthesised)."""
    sizes = {"train": 0, "val": 0, "test": 0}
    per_scene = []
    for scene in range(n_scenes):
        rng = np.random.default_rng([seed, scene])
        u = rng.random()
        split = "train" if u < fractions[0] else "val" if u < sum(fractions) else "test"
        n = int(rng.integers(1, max_objects + 1))
        sizes[split] += n
        per_scene.append((split, n))
    return sizes, per_scene


def test_the_split_sizes_are_the_shipped_datasets() -> None:
    """The page's "train 4 160, val 966, test 866" of the shipped 3 000-scene dataset: the
    counts from each scene's first draws, which a small ``make_dataset`` confirms draw by draw."""
    from compiler.classifier.default import DATASET
    from radar.roi_dataset import make_dataset

    sizes, per_scene = _split_sizes(DATASET["n_scenes"], DATASET["seed"])
    small = make_dataset(**{**DATASET, "n_scenes": 3})
    scenes = small.meta["scene"]
    assert [(str(small.split[scenes == s][0]), int((scenes == s).sum())) for s in range(3)] \
        == per_scene[:3]
    text = PAGE.read_text(encoding="utf-8")
    quoted = re.search(r"\(([\d ]+) scenes, ([\d ]+) sequences of [^:]+: train ([\d ]+), "
                       r"val ([\d ]+),\s+test ([\d ]+)\)", text)
    assert quoted, "the dataset's sizes are not on the page"
    n_scenes, total, *splits = (int(norm(g)) for g in quoted.groups())
    assert n_scenes == DATASET["n_scenes"]
    assert splits == [sizes["train"], sizes["val"], sizes["test"]]
    assert total == sum(splits)
    record = RECORD.read_text(encoding="utf-8")
    assert f"dataset: {total} ROI sequences" in record
    assert f"test split {sizes['test']} " in record
