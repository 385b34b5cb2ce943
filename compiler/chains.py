"""Ready-made radar chains built from a :class:`radar.config.RadarConfig`.

The chain-file format is the contract (see ``docs/ir.md``); these factories
only fill it in from a radar configuration so a user (and ``radarsnn demo``)
gets a correct range-Doppler-CFAR chain for any sensor without writing YAML.

Examples
--------
>>> from radar.config import preset
>>> g = range_doppler_chain(preset("carrada"))
>>> g.verify()
>>> [g.op(n).op for n in g.topological_order()]
['adc_input', 'window', 'dft', 'window', 'dft', 'magnitude', 'sum', 'cfar', 'output']
>>> dict(g.infer_types()["det"].axes)
{'doppler': 64, 'range': 256}
"""

from __future__ import annotations

from typing import Any

from ir import Graph
from radar.config import RadarConfig

__all__ = ["CA_CFAR", "DEFAULT_CFAR", "RANGE_CFAR", "capture_chain", "range_cfar_chain",
           "range_chain", "range_doppler_chain"]

#: The demo's detector: 2-D OS-CFAR on the power map, guard 3/2 and training 8/4 cells per side
#: along range/Doppler (N = 23·13 − 7·5 = 264 training cells), the k = 198 ≈ ¾N-th largest as the
#: noise estimate, α from Pfa = 1e-6.  OS rather than CA: near range 0 the Tx→Rx leakage and the
#: bumper reflection sit in the training cells of close targets and would raise a CA mean.
DEFAULT_CFAR: dict[str, Any] = {
    "kind": "os", "axes": ["range", "doppler"], "guard": [3, 2], "train": [8, 4], "k": 198,
    "pfa": 1e-6, "edge": ["clip", "wrap"],
}

#: :data:`DEFAULT_CFAR`'s window with cell averaging on linear power (Pfa 1e-6, α from N = 264).
CA_CFAR: dict[str, Any] = {
    "kind": "ca", "axes": ["range", "doppler"], "guard": [3, 2], "train": [8, 4],
    "pfa": 1e-6, "edge": ["clip", "wrap"],
}

#: The per-chirp detector of :func:`range_cfar_chain`: 1-D OS-CFAR along range on power,
#: guard 2 and training 12 cells per side (N = 24), k = 18 (¾N), Pfa 1e-4, edges clipped.
RANGE_CFAR: dict[str, Any] = {
    "kind": "os", "axes": ["range"], "guard": 2, "train": 12, "k": 18, "pfa": 1e-4,
    "edge": "clip",
}


def _range_front(config: RadarConfig, shape: dict[str, int], window: str) -> list[dict]:
    """The nodes every chain starts with: ADC cube ``adc`` → window ``win`` → range DFT ``rng``
    (all bins for IQ sampling, the positive half for real sampling)."""
    return [
        {"id": "adc", "op": "adc_input", "shape": shape, "complex": bool(config.iq),
         "full_scale": float(config.full_scale_code)},
        {"id": "win", "op": "window", "input": "adc", "axis": "sample", "kind": window},
        {"id": "rng", "op": "dft", "input": "win", "axis": "sample", "out_axis": "range",
         "keep": "all" if config.iq else "positive"},
    ]


def range_doppler_chain(config: RadarConfig, *, window: str = "hann",
                        doppler_window: str | None = "hann", magnitude: str = "square",
                        cfar: dict[str, Any] | None = None, name: str | None = None) -> Graph:
    """The conventional chain ADC cube → window → range DFT → Doppler DFT → magnitude → Σrx → CFAR.

    Parameters
    ----------
    config : RadarConfig
        The sensor; sets the cube shape, real/IQ sampling and so the kept range bins
        (all bins for IQ, the positive half for real sampling).
    window : str
        Range window kind (``hann``, ``hamming``, ``blackman``, ``rect``).
    doppler_window : str or None
        Window along the chirps before the Doppler DFT (``None``: no window node).
        Without one, a strong target's Doppler sidelobes (−13 dB for a rectangle)
        cross the CFAR threshold along its whole range row.
    magnitude : {"square", "l2", "l1"}
        Detector law; ``square`` (power) is the one the Pfa theory assumes.
    cfar : dict, optional
        Parameters of the ``cfar`` node (default :data:`DEFAULT_CFAR`).
    name : str, optional
        Chain name (default ``<config name>-rd-cfar``).

    Returns
    -------
    Graph
        A verified graph with node ids ``adc, win, rng, [dwin,] dop, mag, rd, det, out``; the
        map axes keep the cube's order, so ``det`` is ``[doppler, range]``.
    """
    shape = {"rx": config.n_virtual, "chirp": config.n_chirps, "sample": config.n_samples}
    nodes = [
        *_range_front(config, shape, window),
        *([{"id": "dwin", "op": "window", "input": "rng", "axis": "chirp",
             "kind": doppler_window}] if doppler_window else []),
        {"id": "dop", "op": "dft", "input": "dwin" if doppler_window else "rng", "axis": "chirp",
         "out_axis": "doppler", "shift": True},
        {"id": "mag", "op": "magnitude", "input": "dop", "kind": magnitude},
        {"id": "rd", "op": "sum", "input": "mag", "axis": "rx"},
        {"id": "det", "op": "cfar", "input": "rd", **(cfar or DEFAULT_CFAR)},
        {"id": "out", "op": "output", "input": "det"},
    ]
    graph = Graph.from_dict({"name": name or f"{config.name}-rd-cfar", "nodes": nodes})
    graph.verify()
    return graph


def range_chain(config: RadarConfig, *, window: str = "hann", rx: int | None = None,
                name: str | None = None) -> Graph:
    """The 1D chain ADC cube → window → range DFT → output (the range S-FT stage alone).

    Parameters
    ----------
    config : RadarConfig
        The sensor (cube shape, real/IQ sampling).
    window : str
        Range window kind.
    rx : int, optional
        Keep only this many (virtual) receivers (default: all).
    name : str, optional
        Chain name (default ``<config name>-range``).

    Returns
    -------
    Graph
        Node ids ``adc, win, rng, out``.

    Examples
    --------
    >>> from radar.config import preset
    >>> dict(range_chain(preset("carrada"), rx=1).infer_types()["rng"].axes)
    {'rx': 1, 'chirp': 64, 'range': 256}
    """
    shape = {"rx": rx or config.n_virtual, "chirp": config.n_chirps, "sample": config.n_samples}
    nodes = [
        *_range_front(config, shape, window),
        {"id": "out", "op": "output", "input": "rng"},
    ]
    graph = Graph.from_dict({"name": name or f"{config.name}-range", "nodes": nodes})
    graph.verify()
    return graph


def range_cfar_chain(config: RadarConfig, *, window: str = "hann",
                     cfar: dict[str, Any] | None = None, name: str | None = None) -> Graph:
    """The 1-D chain ADC cube → window → range DFT → power → Σrx → CFAR along range, per chirp.

    No Doppler DFT: the chirp axis is a batch (each chirp's range profile is detected on
    its own), as for chirp sequences whose targets cross range bins between chirps.

    Parameters
    ----------
    config : RadarConfig
        The sensor (cube shape, real/IQ sampling).
    window : str
        Range window kind.
    cfar : dict, optional
        Parameters of the ``cfar`` node (default :data:`RANGE_CFAR`, along ``range``).
    name : str, optional
        Chain name (default ``<config name>-range-cfar``).

    Returns
    -------
    Graph
        Node ids ``adc, win, rng, mag, rp, det, out``; ``det`` is ``[chirp, range]``.

    Examples
    --------
    >>> from radar.config import preset
    >>> g = range_cfar_chain(preset("chirpseq"))
    >>> dict(g.infer_types()["det"].axes)
    {'chirp': 201, 'range': 256}
    """
    shape = {"rx": config.n_virtual, "chirp": config.n_chirps, "sample": config.n_samples}
    nodes = [
        *_range_front(config, shape, window),
        {"id": "mag", "op": "magnitude", "input": "rng", "kind": "square"},
        {"id": "rp", "op": "sum", "input": "mag", "axis": "rx"},
        {"id": "det", "op": "cfar", "input": "rp", **(cfar or RANGE_CFAR)},
        {"id": "out", "op": "output", "input": "det"},
    ]
    graph = Graph.from_dict({"name": name or f"{config.name}-range-cfar", "nodes": nodes})
    graph.verify()
    return graph


def capture_chain(n_chirps: int = 128, n_samples: int = 128) -> Graph:
    """The range–Doppler OS-CFAR chain of the OpenRadar TI captures (``radar/data/openradar``).

    One complex frame ``[chirp, sample]`` (no receiver axis, no ADC full scale: the
    captures are decoded codes), Hann windows, fftshifted Doppler, power, OS-CFAR
    (guard 2 × 2, train 6 × 4, rank 100, Pfa 1e-4, range clipped, Doppler wrapped).

    Examples
    --------
    >>> capture_chain().topological_order()[-3:]
    ['mag', 'det', 'out']
    """
    return Graph.from_dict({"name": "openradar-rd", "nodes": [
        {"id": "frame", "op": "input", "shape": {"chirp": n_chirps, "sample": n_samples},
         "complex": True},
        {"id": "win", "op": "window", "input": "frame", "axis": "sample"},
        {"id": "rng", "op": "dft", "input": "win", "axis": "sample", "out_axis": "range"},
        {"id": "dwin", "op": "window", "input": "rng", "axis": "chirp"},
        {"id": "dop", "op": "dft", "input": "dwin", "axis": "chirp", "out_axis": "doppler",
         "shift": True},
        {"id": "mag", "op": "magnitude", "input": "dop", "kind": "square"},
        {"id": "det", "op": "cfar", "input": "mag", "kind": "os", "axes": ["range", "doppler"],
         "guard": [2, 2], "train": [6, 4], "k": 100, "pfa": 1e-4, "edge": ["clip", "wrap"]},
        {"id": "out", "op": "output", "input": "det"}]})
