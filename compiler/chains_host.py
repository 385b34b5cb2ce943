"""A whole radar chain with its host stages: range-Doppler-CFAR, then DBSCAN clusters, then tracks.

:func:`tracking_chain` extends :func:`compiler.chains.range_doppler_chain` with a
leading ``frame`` axis on the ADC cube (every map op treats it as a batch), a
``cluster`` node reading the CFAR mask and the power map, and a ``track`` node
that runs the Kalman tracker over the frames in order (``docs/host.md``).

Examples
--------
>>> from radar.config import preset
>>> g = tracking_chain(preset("carrada"), n_frames=4)
>>> [g.op(n).op for n in g.topological_order()][-3:]
['cluster', 'track', 'output']
>>> dict(g.infer_types()["trk"].axes)
{'frame': 4, 'track': 16, 'state': 7}
"""

from __future__ import annotations

from typing import Any

from compiler.chains import range_doppler_chain
from ir import Graph
from radar.config import RadarConfig

__all__ = ["tracking_chain"]


def tracking_chain(config: RadarConfig, *, n_frames: int, cluster: dict[str, Any] | None = None,
                   track: dict[str, Any] | None = None, name: str | None = None,
                   **rd_options: Any) -> Graph:
    """ADC frames → range-Doppler map → CFAR → ``cluster`` → ``track`` → output.

    Parameters
    ----------
    config : RadarConfig
        The sensor: cube shape, and the tracker's bin widths (``range_resolution_m``,
        ``velocity_resolution_mps``), zero-Doppler bin ``n_chirps // 2`` and
        ``dt_s = 1 / frame_rate_hz``.
    n_frames : int
        Size of the leading ``frame`` axis of the ADC input (frames tracked per run).
    cluster, track : dict, optional
        Parameters overriding the ``cluster`` / ``track`` nodes' defaults.
    name : str, optional
        Chain name (default ``<config name>-tracking``).
    **rd_options
        Passed to :func:`~compiler.chains.range_doppler_chain` (``window``, ``cfar`` …).

    Returns
    -------
    Graph
        Verified; node ids ``adc … rd, det`` as in ``range_doppler_chain``, then ``clu``
        (inputs ``det``, ``rd``), ``trk`` and ``out`` (the track table
        ``[frame, track, state]``).

    Raises
    ------
    IRError
        If an override makes the chain invalid (naming the node).
    """
    base = range_doppler_chain(config, **rd_options).to_dict()
    nodes = [n for n in base["nodes"] if n["op"] != "output"]
    adc = next(n for n in nodes if n["op"] == "adc_input")
    adc["shape"] = {"frame": int(n_frames), **adc["shape"]}
    det = next(n for n in nodes if n["op"] == "cfar")
    det.setdefault("axes", ["range", "doppler"])
    track_params = {"dt_s": 1.0 / config.frame_rate_hz,
                    "range_bin_m": config.range_resolution_m,
                    "velocity_bin_mps": config.velocity_resolution_mps,
                    "doppler_zero_bin": config.n_chirps // 2}
    nodes += [
        {"id": "clu", "op": "cluster", "inputs": [det["id"], det["input"]], **(cluster or {})},
        {"id": "trk", "op": "track", "input": "clu", **track_params, **(track or {})},
        {"id": "out", "op": "output", "input": "trk"},
    ]
    graph = Graph.from_dict({"name": name or f"{config.name}-tracking", "nodes": nodes})
    graph.verify()
    return graph
