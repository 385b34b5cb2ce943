"""The ``radarsnn crosscheck`` sub-command: a saved network in Lava or NengoLoihi vs the reference.

``radarsnn crosscheck ARTIFACT --with lava|nengo-loihi [--build-env] [--inputs X.npz]
[--frames N] [--seed S] [--json]`` — ``ARTIFACT`` is a network folder (``backends.save``)
or a program folder (each spiking network is checked).  Without ``--inputs`` (an ``.npz``
with one array per encoder port) the inputs are ``--frames`` seeded uniform draws over
each encoder's code range.  ``--build-env`` first builds the cross-check environment
(:mod:`backends.crosscheck.env`).  Exit 0 when every compared population is equal spike
for spike, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["add_parsers", "crosscheck", "random_inputs"]


def random_inputs(network, frames: int, seed: int) -> dict[str, np.ndarray]:
    """Seeded uniform inputs over each encoder's code range ``[x_min, x_max]``.

    Examples
    --------
    >>> from compiler.snn import Encoder, LatencyCode, Population, SpikingNetwork
    >>> net = SpikingNetwork(name="n", n_steps=4,
    ...     populations=[Population(id="in", shape={"i": 3}, source=True)],
    ...     encoders=[Encoder(port="x", population="in",
    ...                       code=LatencyCode(t_max=4, x_min=0.0, x_max=2.0))])
    >>> x = random_inputs(net, frames=2, seed=0)["x"]
    >>> x.shape, bool((x >= 0).all() and (x <= 2).all())
    ((2, 3), True)
    """
    rng = np.random.default_rng(seed)
    out = {}
    for enc in network.encoders:
        pop = network.population[enc.population]
        shape = tuple(n for a, n in pop.shape.items() if a != "part")
        lo, hi = getattr(enc.code, "x_min", 0.0), getattr(enc.code, "x_max", 1.0)
        out[enc.port] = rng.uniform(lo, hi, size=(frames, *shape))
    return out


def crosscheck(args: argparse.Namespace) -> list[dict]:
    """Run what ``args`` names; one row per (network, population)."""
    from backends import load
    from backends.artifact import save
    from backends.crosscheck.env import build_env, env_python
    from backends.crosscheck.run import compare, reference_run, run_saved
    from compiler.program import CompiledProgram

    python = build_env() if args.build_env else env_python()
    obj = load(args.artifact)
    networks = obj.networks if isinstance(obj, CompiledProgram) else [obj]
    given = dict(np.load(args.inputs, allow_pickle=False)) if args.inputs else None
    rows = []
    for net in networks:
        inputs = given if given is not None else random_inputs(net, args.frames, args.seed)
        ref = reference_run(net, inputs)
        rasters = {p.id: ref.spikes[p.id].reshape(*ref.spikes[p.id].shape[:2], -1)
                   for p in net.populations if p.source}
        with tempfile.TemporaryDirectory() as tmp:
            run = run_saved(args.model, save(net, Path(tmp) / "net"), rasters, python)
        if run.refused:
            rows.append({"network": net.name, "population": None, "exact": False,
                         "refused": run.refused})
            continue
        for m in compare(net, ref, run):
            rows.append({"network": net.name, "population": m.population,
                         "compared": m.compared, "spikes_reference": m.n_spikes_ref,
                         "spikes_chip": m.n_spikes_chip, "mismatched": m.mismatched,
                         "exact": m.exact, "notes": run.notes})
    return rows


def _cmd(args: argparse.Namespace) -> int:
    rows = crosscheck(args)
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        for r in rows:
            if r.get("refused"):
                print(f"{r['network']}: not expressible in {args.model}: {r['refused']}")
                continue
            verdict = "exact" if r["exact"] else f"{r['mismatched']} mismatched"
            print(f"{r['network']}/{r['population']}: {r['compared']}: reference "
                  f"{r['spikes_reference']}, {args.model} {r['spikes_chip']} — {verdict}")
        for note in sorted({n for r in rows for n in r.get("notes", [])}):
            print(f"note: {note}")
    return 0 if rows and all(r["exact"] for r in rows) else 1


def add_parsers(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``crosscheck`` sub-command.

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="radarsnn")
    >>> p = add_parsers(parser.add_subparsers(dest="command"))
    >>> a = parser.parse_args(["crosscheck", "net", "--with", "lava"])
    >>> a.model, a.build_env, a.frames
    ('lava', False, 2)
    """
    p = subparsers.add_parser("crosscheck", help="run a saved network in Lava's fixed-point "
                              "processes or NengoLoihi's emulator and compare it spike for "
                              "spike with the reference engine")
    p.add_argument("artifact", type=Path, metavar="ARTIFACT",
                   help="a network folder (backends.save) or a program folder")
    p.add_argument("--with", dest="model", required=True, choices=["lava", "nengo-loihi"],
                   help="the bit-accurate model to compare with: Lava 0.10's fixed-point "
                        "processes or NengoLoihi 1.1's emulator")
    p.add_argument("--build-env", action="store_true",
                   help="build the Python 3.10 cross-check environment first (cached)")
    p.add_argument("--inputs", type=Path, metavar="X.npz",
                   help="one array per encoder port (default: seeded uniform draws)")
    p.add_argument("--frames", type=int, default=2, help="frames of random inputs (default 2)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random inputs")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_cmd)
    return p
