"""Figures of docs/hardware.md that come from long runs, checked against their records.

* The chip-model table is the output of ``python benchmarks/chip_models.py --out
  benchmarks/results/chip_models.md`` (minutes, and a Python 3.10 environment): row for row,
  and the figures the prose quotes from it.
* *Energy per frame* on the built-in chains: the reports of ``radarsnn report
  examples/chains/carrada_rd_oscfar.yaml --target loihi`` and of ``radarsnn compile
  examples/chains/ti_range.yaml --target loihi -c chirps.npy`` (half a minute each), kept in
  ``benchmarks/results/report_*_loihi.md``; every figure of the two bullets is derived from
  them here. The page's own small energy example asserts its printed line (tests/test_docs.py).
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "hardware.md"
RESULTS = ROOT / "benchmarks" / "results"


def _text() -> str:
    return " ".join(PAGE.read_text(encoding="utf-8").split())


def _energy_rows(report: str) -> dict[str, dict[str, float]]:
    """Node -> the numeric cells of the report's energy table.

    Examples
    --------
    >>> r = ("| node | basis | energy_J |\\n|---|---|---|\\n| rng | bound | 0.02211 |\\n\\nx")
    >>> _energy_rows("## Energy and latency per frame\\n\\n" + r)
    {'rng': {'energy_J': 0.02211}}
    """
    section = report[report.index("## Energy and latency per frame"):]
    (table,) = [b for b in section.split("\n\n") if b.startswith("| node |")][:1]
    lines = table.splitlines()
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    rows = {}
    for line in lines[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[cells[0]] = {k: float(v.replace(" ", "")) for k, v in zip(head, cells, strict=True)
                          if re.fullmatch(r"[\d .e+-]+", v)}
    return rows


def test_the_chip_model_table_is_the_recorded_one() -> None:
    record = (RESULTS / "chip_models.md").read_text(encoding="utf-8")
    page = PAGE.read_text(encoding="utf-8")
    table = page[page.index("| motif | target | model | result |"):].split("\n\n")[0]
    assert table.splitlines() == [line for line in record.splitlines() if line.startswith("|")]


def test_the_chip_model_prose_quotes_the_record() -> None:
    record = (RESULTS / "chip_models.md").read_text(encoding="utf-8")
    text = _text()
    rate = re.search(r"\| rate S-DFT \| [\w-]+ \| lava \| f/out \(all spikes\): "
                     r"(\d+) of (\d+) differ", record)
    assert f"{int(rate.group(1)):,} of {int(rate.group(2)):,}".replace(",", " ") in text
    ca = re.search(r"\| CA-CFAR \| [\w-]+ \| lava \|.*final v max diff det/det (\d+)", record)
    assert f"the table's {int(ca.group(1)):,} units".replace(",", " ") in text
    graded = re.search(r"\| graded read-out \| [\w-]+ \| lava \|.*final v max diff f/out ([\d.]+)",
                       record)
    assert f"({float(graded.group(1)):.0f} units measured" in text
    bias = re.search(r"bias ([\d.]+)e\+0(\d) raw LSBs", record)
    assert f"a bias of {float(bias.group(1)):.1f}·10{'⁰¹²³⁴⁵⁶⁷⁸⁹'[int(bias.group(2))]} LSBs" in text
    assert "f/out (first spikes): exact" in record.split("| resonator | loihi2 | lava |")[1]


def test_the_carrada_energy_figures_are_the_recorded_report() -> None:
    report = (RESULTS / "report_carrada_loihi.md").read_text(encoding="utf-8")
    rows = _energy_rows(report)
    total = re.search(r"Chip: dynamic ([\d.]+) mJ \+ static ([\d.]+) J .* = ([\d.]+) J per frame; "
                      r"DSP: ([\d.]+) mJ in ([\d.]+) s per frame", report)
    dynamic, static, frame, dsp, dsp_s = (float(g) for g in total.groups())
    ratio = re.search(r"chip/DSP = (\d+)\.", report).group(1)
    mj = {n: f"{rows[n + k]['energy_J'] * 1e3:.1f}" for n, k in
          (("rng", "__moving"), ("dop", "__moving"))}
    updates = rows["rng__moving"]["neuron_updates"]
    assert updates == rows["dop__moving"]["neuron_updates"]
    latency = sum(r["latency_s"] for r in rows.values())
    expected = (
        f"dynamic {dynamic:.2f} mJ per frame (`rng` {mj['rng']} mJ, `dop` {mj['dop']} mJ, "
        f"`det` {rows['det']['energy_J'] * 1e3:.2f} mJ; the 2 × {updates / 1e6:.0f} M neuron "
        f"updates of the two time-multiplexed DFT stages at 81 pJ are "
        f"{updates * 81e-12 * 1e3:.1f} mJ each) + static {static:.3f} J (0.104 W × the "
        f"{latency:.2f} s latency at the assumed 10 µs per step) = {frame:.3f} J; the same three "
        f"nodes on the C674x: {dsp:.3f} mJ in {dsp_s * 1e3:.1f} ms (the OS-CFAR's "
        f"{rows['det']['dsp_cycles'] / 1e6:.1f} M compare cycles are "
        f"{rows['det']['dsp_J'] * 1e3:.1f} mJ of it), so the chip costs {dynamic / dsp:.1f} × the "
        f"DSP in dynamic energy and {ratio} × with its leakage.")
    assert expected in _text()
    assert "loihi_programmable.neuron_update_j | 8.1e-11 |" in report
    assert "loihi_programmable.static_power_w | 0.104 |" in report


def test_the_ti_range_energy_figures_are_the_recorded_report() -> None:
    report = (RESULTS / "report_ti_range_loihi.md").read_text(encoding="utf-8")
    line = re.search(r"energy ≈ ([\d.]+) µJ/frame on loihi_programmable \(dynamic ([\d.]+) µJ "
                     r"\+ static "
                     r"([\d.]+) µJ; measured counts\); conventional DSP \(C674x\) ≈ ([\d.]+) "
                     r"µJ/frame, chip/DSP = (\d+)\.", report)
    frame, dynamic, static, dsp, ratio = line.groups()
    steps = re.search(r"Total (\d+) steps = ", report).group(1)
    expected = (f"{dynamic} µJ dynamic + {static} µJ static ({steps} steps × 10 µs) = {frame} µJ "
                f"per frame against {dsp} µJ for the range DFT on the C674x (ratio {ratio}).")
    assert expected in _text()
    assert "| rng | measured |" in report


def _stages(report: str) -> dict[str, list[str]]:
    head = "| node | motif | inputs | neurons |"
    lines = report[report.index(head):].split("\n\n")[0].splitlines()
    names = [c.strip() for c in lines[0].strip("|").split("|")]
    return {cells[0]: dict(zip(names, cells, strict=True)) for cells in
            ([c.strip() for c in line.strip("|").split("|")] for line in lines[2:])}


def test_the_carrada_placement_figures_are_the_recorded_reports() -> None:
    text = _text()
    for name in ("report_carrada_loihi.md", "report_carrada_loihi2.md"):
        report = (RESULTS / name).read_text(encoding="utf-8")
        stages = _stages(report)
        total = re.search(r"Total ([\d ]+) steps = ([\d.]+) s per frame", report)
        assert f"{total.group(1)} steps = {total.group(2)} s" in text, name
        runs = sum(int(st["repetitions"].replace(" ", "")) for st in stages.values()
                   if st["node"] != "det")
        steps = int(stages["rng__moving"]["time_steps"])
        cores = sum(int(st["cores"]) for st in stages.values())
        if name.endswith("loihi.md"):
            rng, dop, det = stages["rng__moving"], stages["dop__moving"], stages["det"]
            assert (rng["multiplexed"], dop["multiplexed"], det["multiplexed"]) == ("yes",) * 2 \
                + ("no",)
            assert (f"`rng__moving` (R = {rng['repetitions']}, one instance: {rng['neurons']} "
                    f"neurons, {rng['cores']} cores) and `dop__moving` (R = {dop['repetitions']}, "
                    f"{dop['neurons']} neurons, {dop['cores']} cores); the OS-CFAR stays spatial "
                    f"({det['cores']} cores): {cores} cores in all") in text
            assert f"(256 + 1 024) × {steps} + 100 = {total.group(1)} steps" in text
            fit = re.search(r"it would fit with steps of at most (\S+) s\)", report).group(1)
            assert f"it would with steps of at most {fit} s" in text
            assert runs == 256 + 1024
        else:
            rng, dop, det = stages["rng__moving"], stages["dop__moving"], stages["det"]
            assert (rng["multiplexed"], dop["multiplexed"]) == ("yes", "no")
            assert (f"only `rng__moving` is multiplexed ({rng['cores']} cores; `dop__moving` is "
                    f"spatial on {dop['cores']} cores, the OS-CFAR on {det['cores']}: {cores} "
                    f"cores), {int(rng['repetitions']) + 1} × {steps} + 100 = "
                    f"{total.group(1)} steps") in text


def test_the_board_figures_are_the_recorded_run() -> None:
    """``python benchmarks/allocation.py --only boards`` (``allocation_boards.txt``)."""
    record = (RESULTS / "allocation_boards.txt").read_text(encoding="utf-8")
    text = _text()

    def spaced(value: str) -> str:
        return f"{int(value.replace(',', '')):,}".replace(",", " ")

    refused = {m.group(1): m for m in re.finditer(
        r"^imaging \(192 virtual rx\) on board (\w+) .*?: ([\d.]+) s; BudgetError: network "
        r"'imaging' needs ([\d,]+) (neurons|bits of synaptic memory) but .*? x ([\d,]+) cores "
        r"= .*?: at least ([\d,]+) cores", record, re.M)}
    assert set(refused) == {"kapoho_point", "nahuku32", "spinnaker2_48"}
    assert all(float(m.group(2)) < 0.5 for m in refused.values())  # "each in < 0.5 s"
    kapoho, nahuku, spinnaker = (refused[k] for k in ("kapoho_point", "nahuku32",
                                                      "spinnaker2_48"))
    assert (f"({spaced(kapoho.group(3))} neurons need ≥ {spaced(kapoho.group(6))} Loihi 2 cores, "
            f"{spaced(kapoho.group(5))} available)") in text
    bits = int(nahuku.group(3).replace(",", ""))
    assert f"{bits / 1e9:.0f} Gbit of synapses, ≥ {spaced(nahuku.group(6))} cores" in text
    assert f"≥ {spaced(spinnaker.group(6))} PEs" in text
    fits = re.search(r"on board hala_point \((\d+) x loihi2\): fits on ([\d,]+) cores, (\d+) of "
                     r"\d+ chips; compile \(quantize\+split\+place\+report\) ([\d.]+) s; peak "
                     r"resident memory of this process ([\d.]+) GB", record)
    chips, cores, used, secs, gb = fits.groups()
    assert (f"it fits on {spaced(cores)} cores = {used} of the {spaced(chips)} chips "
            f"in {secs} s (quantize + split + place + report) with a peak resident memory of "
            f"{gb} GB") in text
    assert "Inter-chip: 0 messages per frame" in record


def test_the_split_weights_figure_is_the_recorded_report() -> None:
    """"768 extra synapses on 2 899 968": the OS-CFAR's synapses in the carrada report, less
    those of the unsplit hand-built network the *Figures* block asserts."""
    report = (RESULTS / "report_carrada_loihi.md").read_text(encoding="utf-8")
    det = int(_stages(report)["det"]["synapses"].replace(" ", ""))
    assert f"{det - 2_899_968} extra synapses on 2 899 968" in _text()
    assert "2_899_968" in PAGE.read_text(encoding="utf-8")  # the block's assert
