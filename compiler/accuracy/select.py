r"""``motifs="auto"``: the cheapest spiking configuration that keeps the contract and the deadline.

Each op has a **ladder** of configurations, cheapest and least exact first
(:data:`LADDERS`). The search starts every op that the user did not pin at the
bottom rung, compiles, runs the held-back frames on the simulator and measures the
contract (:mod:`compiler.accuracy.contract`) and the frame deadline (the report's
steps × step time against the frame period). While something fails, it climbs the
ladder of the op of the *first* failing stage (its upstream spiking ops inside the
same segment when that op is at its top); a configuration that does not compile
(a motif the target lacks) is recorded and skipped; one too big for the chip climbs the
spiking rungs only (the host is never a way to fit a chip), and where none fits, its
:class:`~ir.errors.BudgetError` is raised. A host rung is the last of every ladder,
for accuracy only: reaching it is said in the result.

Why these rungs (measured; ``docs/chip_accuracy.md``): the time-coded S-FT's read-out
resolves about ``log₂ T`` bits, so on a scene whose returns span more than ≈ 48 dB it
decodes the noise floor to 0 and an OS-CFAR floods; the resonator streams the ADC
samples with a bit-plane code and keeps the floor; held-out frames with stronger
returns than the calibration set clip the input code unless its range has headroom
(30 dB here, paid for with two more stream bits); the time-coded CFAR's ties need
more than 100 steps on maps rich in near-threshold cells (a CA-CFAR on dB maps held
only at 1000).

Examples
--------
>>> [c.label for c in LADDERS["cfar"]]
['time', 'time(cfar_steps=300)', 'time(cfar_steps=1000)', 'host']
>>> Ladder(("dft", "cfar")).config([0, 3])
({'dft': 'time', 'cfar': 'host'}, {})
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from compiler.accuracy.contract import Contract
from ir.errors import AccuracyError, BudgetError, CompileError

__all__ = ["LADDERS", "Attempt", "Candidate", "Ladder", "Selection", "search"]


@dataclass(frozen=True)
class Candidate:
    """One rung: a motif for the op and the compile options it needs."""

    motif: str
    options: tuple[tuple[str, Any], ...] = ()

    @property
    def label(self) -> str:
        """``motif`` or ``motif(option=value, …)``."""
        if not self.options:
            return self.motif
        return f"{self.motif}({', '.join(f'{k}={v}' for k, v in self.options)})"


#: Op name -> its rungs, cheapest first; the last is always the host.
LADDERS: dict[str, tuple[Candidate, ...]] = {
    "dft": (Candidate("time"), Candidate("time", (("charging", "log"),)), Candidate("resonator"),
            Candidate("resonator", (("encoder_headroom", 32.0), ("stream_bits", 14)))),
    "cfar": (Candidate("time"), Candidate("time", (("cfar_steps", 300),)),
             Candidate("time", (("cfar_steps", 1000),)), Candidate("host")),
}

#: Ops whose ladder may end on the host when no spiking rung keeps the contract (a CFAR:
#: CA on linear power has no spiking code that keeps it on every map); a DFT never
#: falls back by itself (the papers put it on the chip): the compile is refused instead.
HOST_FALLBACK = frozenset({"cfar"})


@dataclass(frozen=True)
class Ladder:
    """The ops being searched, in graph order."""

    ops: tuple[str, ...]

    def config(self, rungs: Sequence[int]) -> tuple[dict[str, str], dict[str, Any]]:
        """Motifs by op name and the merged options of the chosen rungs (larger wins)."""
        motifs: dict[str, str] = {}
        merged: dict[str, Any] = {}
        for op, rung in zip(self.ops, rungs, strict=True):
            cand = LADDERS[op][rung]
            motifs[op] = cand.motif
            for k, v in cand.options:
                merged[k] = v if isinstance(v, str) or k not in merged else max(merged[k], v)
        return motifs, merged


@dataclass
class Attempt:
    """One configuration tried: what it was, what it measured, what it costs."""

    config: dict[str, str]
    contract: Contract | None = None
    steps: int | None = None
    fits: bool | None = None
    error: str | None = None

    def to_dict(self) -> dict:
        """JSON-able."""
        return {"config": self.config, "steps": self.steps, "fits": self.fits,
                "error": self.error,
                "holds": None if self.contract is None else self.contract.holds,
                "failures": [] if self.contract is None else
                [f"{s.node}: {'; '.join(f)}" for s, f in self.contract.failing()]}


@dataclass
class Selection:
    """The search's result: the attempts in order and the one chosen."""

    attempts: list[Attempt] = field(default_factory=list)
    chosen: int | None = None
    host_ops: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON-able."""
        return {"chosen": self.chosen, "host_ops": self.host_ops,
                "attempts": [a.to_dict() for a in self.attempts]}


def _op_of(program, node: str) -> str:
    return program.graph.op(node).op


def search(ops: Sequence[str], build: Callable[[dict[str, str], dict[str, Any]], Any],
           measure: Callable[[Any], Contract], *, accuracy: str = "error",
           max_attempts: int = 12) -> tuple[Any, Selection]:
    """Climb the ladders of ``ops`` until the contract and the deadline hold.

    Parameters
    ----------
    ops : sequence of str
        Op names to choose motifs for (each a key of :data:`LADDERS`).
    build : callable
        ``build(motifs_by_op, options) -> CompiledProgram`` (raises CompileError when a
        configuration cannot be compiled).
    measure : callable
        ``measure(program) -> Contract`` on the held-back frames.
    accuracy : {"error", "warn"}
        When nothing holds: raise :class:`~ir.errors.AccuracyError`, or return the
        configuration with the fewest failing stages (the selection says so).
    max_attempts : int
        Compiles at most.

    Returns
    -------
    program, Selection

    Raises
    ------
    AccuracyError
        Nothing holds and ``accuracy="error"``: names the stage, the best figure reached
        and the ways out.
    """
    ladder = Ladder(tuple(ops))
    rungs = [0] * len(ops)
    selection = Selection()
    programs: list[Any] = []
    budget: BudgetError | None = None  # the first configuration that did not fit the chip
    while len(selection.attempts) < max_attempts:
        motifs, options = ladder.config(rungs)
        attempt = Attempt(config={op: LADDERS[op][r].label for op, r in zip(ops, rungs,
                                                                            strict=True)})
        selection.attempts.append(attempt)
        program = None
        too_big = False
        try:
            program = build(motifs, options)
        except BudgetError as err:  # does not fit the chip: never a reason for the host
            attempt.error, too_big = " ".join(str(err).split()), True
            budget = budget or err
        except CompileError as err:
            attempt.error = " ".join(str(err).split())
        programs.append(program)
        deadline = False
        if program is not None:
            attempt.contract = measure(program)
            attempt.steps, attempt.fits = _latency(program)
            failing = attempt.contract.failing()
            if not failing and attempt.fits is not False:
                selection.chosen = len(selection.attempts) - 1
                selection.host_ops = [op for op, m in motifs.items() if m == "host"]
                return program, selection
            if failing:
                stage = failing[0][0]
                culprits = [_op_of(program, stage.node),
                            *[_op_of(program, n) for n in reversed(stage.upstream)]]
            else:  # within the contract but over the frame period: fewer steps, on spikes
                culprits, deadline = [op for op in ops if motifs[op] != "host"], True
        else:
            culprits = list(ops)
        # spiking rungs first (the failing op, then its upstream ops), the host last (for
        # accuracy only: a configuration too big for the chip climbs spiking rungs only)
        order = [(op, host) for host in ((False,) if too_big else (False, True))
                 for op in culprits if op in ops]
        step = next(((ops.index(op), r) for op, host in order
                     if (r := _next_rung(op, rungs[ops.index(op)], deadline, host)) is not None),
                    None)
        if step is None:
            break
        rungs[step[0]] = step[1]
    return _give_up(selection, programs, accuracy, budget)


def _next_rung(op: str, rung: int, deadline: bool, host: bool) -> int | None:
    """The next rung of ``op`` to try, or None: a spiking one (for the deadline, the next
    that changes the motif: only another motif has fewer steps), or (``host``) the host
    rung of an op in :data:`HOST_FALLBACK`, for accuracy only."""
    ladder = LADDERS[op]
    for nxt in range(rung + 1, len(ladder)):
        cand = ladder[nxt]
        if cand.motif == "host":
            return nxt if host and op in HOST_FALLBACK and not deadline else None
        if host:
            continue
        if not deadline or cand.motif != ladder[rung].motif:
            return nxt
    return None


def _latency(program) -> tuple[int | None, bool | None]:
    report = program.records.report
    if report is None:
        return None, None
    lat = report.data.get("latency", {})
    return lat.get("total_steps"), lat.get("fits")


def _give_up(selection: Selection, programs: list, accuracy: str,
             budget: BudgetError | None = None):
    scored = [(len(a.contract.failing()), a.fits is False, a.steps or 0, i)
              for i, a in enumerate(selection.attempts) if a.contract is not None]
    if not scored and budget is not None:  # nothing fits: the chip's limit, as it was
        raise budget
    if not scored:
        errors = "; ".join(dict.fromkeys(a.error or "" for a in selection.attempts))
        raise AccuracyError(f"no configuration compiles: {errors}")
    best = min(scored)[-1]
    attempt = selection.attempts[best]
    if accuracy == "warn":
        selection.chosen = best
        return programs[best], selection
    failing = attempt.contract.failing()
    if failing:
        stage, why = failing[0]
        node = stage.node.split("__")[0]  # the user's node (static-split parts share its id)
        what = (f"stage {node!r} ({stage.node}, motif {stage.motif}) breaks the accuracy "
                f"contract: {'; '.join(why)}")
    else:
        raise BudgetError(_deadline_message(programs[best], attempt))
    if attempt.config:
        tried = ", ".join(str(a.config) for a in selection.attempts)
        how = (f"best of {len(selection.attempts)} configurations tried: {attempt.config}; "
               f"tried {tried}")
    else:  # every op pinned by the user: one configuration, nothing to climb
        how = "with the motifs given; none left to choose"
    raise AccuracyError(
        f"{what} ({how}). Ways out: keep that stage on the host (motifs={{{node!r}: 'host'}}), "
        f"more steps (time_steps=...), or accept the loss (accuracy='warn')", node=node)


def _deadline_message(program, attempt: Attempt) -> str:
    """Which network breaks the frame deadline, by how much, and the ways out."""
    lat = program.records.report.data["latency"]
    worst = max(lat["networks"], key=lambda r: r["latency_steps"])
    period, total = lat["frame_period_s"], lat.get("total_s")
    over = f"{total:.3g} s per frame against a frame period of {period:.3g} s" \
        if total is not None else f"{lat['total_steps']} steps per frame"
    stages = _stages_of(program, worst["network"])
    return (f"no spiking configuration that keeps the accuracy contract fits the frame "
            f"deadline: the best ({attempt.config}) needs {over}; network "
            f"{worst['network']!r}" + (f" (stage {', '.join(map(repr, stages))})" if stages
                                       else "")
            + f" alone runs {worst['runs']} time-multiplexed repetition(s) "
            f"x {worst['time_steps']} steps = {worst['latency_steps']} steps"
            + (f" of {worst['step_s']:.3g} s" if worst.get("step_s") else "") + ". Ways out: a "
            "board profile with more cores (repetitions side by side), a lower frame rate "
            "(options={'frame_rate_hz': ...}), or keep a stage on the host "
            "(motifs={'dft': 'host'})")


def _stages_of(program, network: str) -> list[str]:
    """The user's nodes whose populations make up ``network`` (graph order; static-split
    parts under their node's id; none: unknown)."""
    nodes = {p.origin.get("node") for net in getattr(program, "networks", ())
             if net.name == network for p in net.populations}
    if not nodes:
        return []
    ids = [n.split("__")[0] for n in program.graph.topological_order() if n in nodes]
    return list(dict.fromkeys(ids))


def ops_to_search(graph, pinned: Mapping[str, str]) -> list[str]:
    """Op names of ``graph`` that have a ladder and are not pinned by the user (graph order)."""
    out: list[str] = []
    for n in graph.topological_order():
        op = graph.op(n).op
        if op in LADDERS and op not in out and n not in pinned and op not in pinned:
            out.append(op)
    return out
