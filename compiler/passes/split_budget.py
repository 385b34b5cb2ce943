r"""Budget checks of the ``split`` pass and the errors that say what does not fit and what to do.

A block fits a core when :math:`\max_k \text{amount}_k / \text{limit}_k \le 1` over
the budgets (:data:`~compiler.hardware.BUDGETS`; unbounded limits never bind).
Before splitting, the resident neurons and (a lower bound on the) synapse bits of
a whole program are checked against all cores together.

Examples
--------
>>> import numpy as np
>>> fits(np.array([[3, 0, 0, 8]]), np.array([4.0, np.inf, np.inf, 16.0]))
(True, 0.75)
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from math import ceil

import numpy as np

from compiler.hardware import BUDGETS, HardwareProfile
from compiler.hardware.repetition import Stage, stages
from compiler.passes.split_record import describe
from compiler.snn import Population, SpikingNetwork
from ir.errors import BudgetError

__all__ = ["check_totals", "explain_failure", "fits", "too_big"]

_BUDGET_TEXT = {
    "neurons": "neurons",
    "input_axons": "input axons (fan-in lines)",
    "output_axons": "output axons (fan-out lines)",
    "synapse_bits": "bits of synaptic memory",
}
_SUGGEST = {
    "neurons": "use more cores or chips (a profile file with a larger 'chips'), or run the "
               "largest stages on the host",
    "input_axons": "reduce the fan-in (a smaller window or a sparser matrix, e.g. the radix-4 "
                   "S-FFT instead of a dense DFT) or use a target with more input axons per core",
    "output_axons": "let each neuron drive fewer target populations, or use a target with more "
                    "output axons per core",
    "synapse_bits": "store fewer or narrower synapses (fewer training cells, a sparser matrix), "
                    "or use a target with more synaptic memory or shared weights",
}


def fits(amounts: np.ndarray, limits: np.ndarray) -> tuple[bool, float]:
    ratio = float((amounts / limits).max()) if amounts.size else 0.0
    return ratio <= 1.0, ratio


def _resident(stage: Stage, multiplexed: Collection[str], shared: bool) -> tuple[int, int]:
    """Neurons and stored synapse entries (a lower bound) of a stage as placed."""
    r = stage.repetitions if stage.key in multiplexed else 1
    return stage.neurons // r, stage.synapses_stored if shared else stage.synapse_instances // r


def check_totals(networks: Sequence[SpikingNetwork], profile: HardwareProfile,
                  multiplexed: Sequence[Collection[str]], what: str,
                  stage_lists: Sequence[list[Stage]] | None = None) -> None:
    """Raise when the resident neurons or synapse bits exceed all cores together."""
    cores = profile.n_cores
    if cores is None:
        return
    limits = profile.limits()
    shared = profile.shared_weights_per_core
    stage_lists = stage_lists or [stages(n) for n in networks]
    rows = [(net, st, *_resident(st, mux, shared))
            for net, mux, sts in zip(networks, multiplexed, stage_lists, strict=True)
            for st in sts]
    need = {"neurons": sum(r[2] for r in rows),
            "synapse_bits": sum(r[3] for r in rows) * profile.bits_per_synapse}
    # the budget that needs the most cores is the one to report
    budget = max(need, key=lambda b: need[b] / limits[BUDGETS.index(b)])
    amount, limit = need[budget], limits[BUDGETS.index(budget)]
    if amount > limit * cores:
        net, st, n_res, _ = max(rows, key=lambda r: r[2])
        biggest = net.population[st.populations[0]]
        inst = (f" (one instance of {st.repetitions:,})"
                if any(st.key in m for m in multiplexed) else "")
        n = ceil(amount / limit)
        raise BudgetError(
            f"{what} needs {amount:,} {_BUDGET_TEXT[budget]} but "
            f"{profile.name} has {int(limit):,} per core x {cores} cores = "
            f"{int(limit * cores):,}: at least {n:,} cores "
            f"({ceil(n / profile.cores_per_chip):,} chips of {profile.cores_per_chip} cores, "
            f"{profile.chips} available); the largest population is {describe(biggest)} with "
            f"{n_res:,} neurons{inst}; {_SUGGEST[budget]}", node=biggest.origin.get("node"))


def too_big(pop: Population, profile: HardwareProfile, amounts: np.ndarray,
             limits: np.ndarray) -> BudgetError:
    worst = np.unravel_index(np.argmax(amounts / limits), amounts.shape)
    budget = BUDGETS[worst[1]]
    return BudgetError(
        f"{describe(pop)}: even one neuron per core needs {int(amounts[worst]):,} "
        f"{_BUDGET_TEXT[budget]}, {profile.name} allows {int(limits[worst[1]]):,} per core; "
        f"{_SUGGEST[budget]}", node=pop.origin.get("node", pop.id))


def explain_failure(err: BudgetError, chosen: list[tuple[int, Stage]], mode: str,
                    n_candidates: int) -> BudgetError:
    """``err`` with what the repetition mode tried, and what else could help."""
    if chosen:
        runs = ", ".join(f"{st.key} x{st.repetitions:,}" for _, st in chosen)
        extra = (f" — even with every repeated stage time-multiplexed (one instance each of "
                 f"{runs}); what does not fit is not repeated, so shrink it or add chips")
    elif mode == "spatial" and n_candidates:
        extra = (f"; or time-multiplex the {n_candidates} repeated stage(s) (compile option "
                 "repetitions='auto' or 'temporal', CLI --repetitions)")
    else:
        extra = ""
    return BudgetError(f"{err}{extra}", node=err.node)
