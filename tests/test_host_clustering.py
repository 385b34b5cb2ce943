"""DBSCAN clustering of detections (radar.clustering) and the IR op ``cluster``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from ir import Graph, evaluate
from ir.errors import IRError, RadarConfigError
from ir.ops import CLUSTER_FEATURES, Cluster
from ir.types import TensorType
from radar.clustering import FEATURES, cluster_detections, cluster_table, label_detections

# ------------------------------------------------------------------ hand-made maps


def _map() -> tuple[np.ndarray, np.ndarray]:
    """8 x 8 [range, doppler] map with three clusters, one across the Doppler wrap."""
    power = np.zeros((8, 8))
    power[1, 1], power[1, 2], power[2, 1] = 4.0, 2.0, 2.0   # A: peak 4 at (1, 1)
    power[5, 7], power[5, 0], power[6, 0] = 6.0, 3.0, 3.0   # B: peak 6 at (5, 7), wraps
    power[7, 4] = 5.0                                       # C: a single cell
    return power > 0, power


def test_hand_made_clusters_with_doppler_wrap() -> None:
    mask, power = _map()
    table = cluster_detections(mask, power, eps_bins=1.5, max_clusters=4)
    # B: range 5 + (0*6 + 0*3 + 1*3)/12 = 5.25; Doppler offsets from bin 7: 0, +1, +1 (bin 0
    #    is one step past 7) -> 7 + (3 + 3)/12 = 7.5.   A: 1 + 2/8 = 1.25 on both axes.
    assert table.tolist() == [[1.0, 5.25, 7.5, 3.0, 6.0],
                              [1.0, 7.0, 4.0, 1.0, 5.0],
                              [1.0, 1.25, 1.25, 3.0, 4.0],
                              [0.0, 0.0, 0.0, 0.0, 0.0]]


def test_without_wrap_the_edge_cluster_splits_and_ties_pick_the_lowest_cell() -> None:
    mask, power = _map()
    table = cluster_detections(mask, power, eps_bins=1.5, max_clusters=5, wrap=(False, False))
    # {(5,0), (6,0)}: both 3.0 -> the peak is the lower flat index (5, 0); range 5 + 3/6.
    assert table.tolist() == [[1.0, 5.0, 7.0, 1.0, 6.0],
                              [1.0, 7.0, 4.0, 1.0, 5.0],
                              [1.0, 1.25, 1.25, 3.0, 4.0],
                              [1.0, 5.5, 0.0, 2.0, 3.0],
                              [0.0, 0.0, 0.0, 0.0, 0.0]]


def test_equal_peaks_are_ordered_by_bins_and_capacity_drops_the_weakest() -> None:
    mask = np.zeros((4, 6), dtype=bool)
    mask[3, 3] = mask[0, 5] = mask[2, 0] = True
    power = np.where(mask, 1.0, 0.0)
    power[2, 0] = 0.5
    table = cluster_detections(mask, power, eps_bins=1.0, max_clusters=2)
    assert table[:, 1:3].tolist() == [[0.0, 5.0], [3.0, 3.0]]      # (2, 0) dropped
    no_power = cluster_detections(mask, None, eps_bins=1.0, max_clusters=3)
    assert no_power[:, 1:3].tolist() == [[0.0, 5.0], [2.0, 0.0], [3.0, 3.0]]
    assert (no_power[:, 4] == 1.0).all()


def test_min_samples_makes_noise_and_border_cells() -> None:
    mask = np.zeros((6, 8), dtype=bool)
    mask[1, 2:5] = True        # a line of three
    mask[4, 6] = True          # isolated
    two = label_detections(mask, eps_bins=1.0, min_samples=2)
    assert two[1, 2:5].tolist() == [0, 0, 0] and two[4, 6] == -1
    # min_samples 3: only the middle cell is core; the ends are border cells of its cluster
    three = label_detections(mask, eps_bins=1.0, min_samples=3)
    assert three[1, 2:5].tolist() == [0, 0, 0] and three[4, 6] == -1
    assert (label_detections(mask, eps_bins=1.0, min_samples=4) == -1).all()


def test_axes_scale_stretches_distances() -> None:
    mask = np.zeros((4, 10), dtype=bool)
    mask[1, [2, 4]] = True     # two Doppler bins apart
    assert label_detections(mask, eps_bins=1.0)[1, [2, 4]].tolist() == [0, 1]
    assert label_detections(mask, eps_bins=1.0, axes_scale=(1.0, 0.5))[1, [2, 4]].tolist() == [
        0, 0]


def test_empty_mask_gives_an_all_zero_table_and_batches_pass_through() -> None:
    mask = np.zeros((3, 2, 5, 4), dtype=bool)
    mask[1, 0, 2, 3] = True
    out = cluster_detections(mask, max_clusters=2)
    assert out.shape == (3, 2, 2, len(FEATURES))
    assert out[1, 0, 0].tolist() == [1.0, 2.0, 3.0, 1.0, 1.0]
    assert np.count_nonzero(out) == 5


def test_bad_arguments_raise_radar_config_errors() -> None:
    mask, power = _map()
    with pytest.raises(RadarConfigError, match="2-D bool"):
        label_detections(mask.astype(float))
    with pytest.raises(RadarConfigError, match="eps_bins > 0"):
        label_detections(mask, eps_bins=0.0)
    with pytest.raises(RadarConfigError, match="power has shape"):
        cluster_detections(mask, power[:4])
    with pytest.raises(RadarConfigError, match=">= 0"):
        cluster_detections(mask, -power)
    with pytest.raises(RadarConfigError, match="max_clusters=0"):
        cluster_table(label_detections(mask), power, max_clusters=0)


# ------------------------------------------------------------------ against brute force


def _components(mask: np.ndarray, wrap: bool) -> list[list[tuple[int, int]]]:
    """8-connected components (Doppler circular if ``wrap``), by breadth-first search."""
    n_r, n_d = mask.shape
    seen, comps = np.zeros_like(mask), []
    for start in zip(*np.nonzero(mask), strict=True):
        if seen[start]:
            continue
        comp, todo = [], [start]
        seen[start] = True
        while todo:
            r, d = todo.pop()
            comp.append((int(r), int(d)))
            for dr in (-1, 0, 1):
                for dd in (-1, 0, 1):
                    rr, cc = r + dr, d + dd
                    if wrap:
                        cc %= n_d
                    if 0 <= rr < n_r and 0 <= cc < n_d and mask[rr, cc] and not seen[rr, cc]:
                        seen[rr, cc] = True
                        todo.append((rr, cc))
        comps.append(sorted(comp))
    return comps


def _brute_row(comp, power, n_d, wrap) -> list[float]:
    pr, pd = max(comp, key=lambda c: power[c])
    w = np.array([power[c] for c in comp])
    dr = np.array([r - pr for r, _ in comp], dtype=float)
    dd = np.array([d - pd for _, d in comp], dtype=float)
    if wrap:
        dd = (dd + n_d // 2) % n_d - n_d // 2
    d = pd + (w * dd).sum() / w.sum()
    return [1.0, pr + (w * dr).sum() / w.sum(), d % n_d if wrap else d, len(comp), power[pr, pd]]


@given(mask=arrays(bool, st.tuples(st.integers(1, 9), st.integers(1, 9))),
       seed=st.integers(0, 2**16), wrap=st.booleans(), capacity=st.integers(1, 6))
def test_min_samples_one_equals_8_connected_components(mask, seed, wrap, capacity) -> None:
    # distinct positive powers: no ties, so the oracle's order is unambiguous
    power = np.random.default_rng(seed).permutation(mask.size).reshape(mask.shape) + 1.0
    table = cluster_detections(mask, power, eps_bins=1.5, max_clusters=capacity,
                               wrap=(False, wrap))
    comps = _components(mask, wrap)
    rows = sorted((_brute_row(c, power, mask.shape[1], wrap) for c in comps),
                  key=lambda r: -r[4])[:capacity]
    expected = np.zeros((capacity, len(FEATURES)))
    if rows:
        expected[: len(rows)] = rows
    np.testing.assert_allclose(table, expected, rtol=0, atol=1e-9)


@given(mask=arrays(bool, st.tuples(st.integers(1, 10), st.integers(1, 10))),
       eps=st.floats(0.5, 3.0), min_samples=st.integers(1, 5),
       scale=st.tuples(st.floats(0.25, 2.0), st.floats(0.25, 2.0)),
       wrap=st.tuples(st.booleans(), st.booleans()), capacity=st.integers(1, 8))
def test_table_invariants(mask, eps, min_samples, scale, wrap, capacity) -> None:
    power = np.arange(mask.size, dtype=float).reshape(mask.shape) % 7
    kw = {"eps_bins": eps, "min_samples": min_samples, "axes_scale": scale, "wrap": wrap}
    labels = label_detections(mask, **kw)
    table = cluster_detections(mask, power, max_clusters=capacity, **kw)
    assert table.shape == (capacity, len(FEATURES)) and table.dtype == np.float64
    assert not (labels >= 0)[~mask].any()                         # clusters are detections
    n_clusters = int(labels.max()) + 1
    assert sorted(set(labels[labels >= 0].tolist())) == list(range(n_clusters))
    valid = table[:, 0] == 1.0
    n_valid = min(n_clusters, capacity)
    assert valid.tolist() == [True] * n_valid + [False] * (capacity - n_valid)
    assert (table[~valid] == 0).all()
    assert np.all(np.diff(table[valid, 4]) <= 0)                  # by descending peak power
    assert table[valid, 3].sum() <= (labels >= 0).sum()
    for col, n, circular in ((1, mask.shape[0], wrap[0]), (2, mask.shape[1], wrap[1])):
        top = n if circular else n - 1                            # [0, n) or [0, n - 1]
        assert np.all((table[valid, col] >= 0) & (table[valid, col] <= top))
        assert not circular or np.all(table[valid, col] < n)
    # each row's peak power is a detected cell's power
    assert set(table[valid, 4].tolist()) <= set(power[labels >= 0].tolist())
    np.testing.assert_array_equal(cluster_detections(mask, power, max_clusters=capacity, **kw),
                                  table)                          # deterministic


# ------------------------------------------------------------------ the IR op


def _chain(cluster: dict, *, power_domain: str = "power", with_power: bool = True) -> Graph:
    shape = {"frame": 2, "doppler": 8, "range": 8}
    nodes = [{"id": "det", "op": "input", "shape": shape, "domain": "mask"},
             {"id": "pw", "op": "input", "shape": shape, "domain": power_domain},
             {"id": "clu", "op": "cluster", **({"inputs": ["det", "pw"]} if with_power
                                               else {"input": "det"}), **cluster},
             {"id": "out", "op": "output", "input": "clu"}]
    graph = Graph.from_dict({"name": "c", "nodes": nodes})
    graph.verify()
    return graph


def test_ir_cluster_matches_the_reference_with_map_axes_reordered() -> None:
    mask, power = _map()                                 # [range, doppler]
    masks = np.stack([mask.T, np.zeros_like(mask.T)])    # IR order [frame, doppler, range]
    powers = np.stack([power.T, power.T])
    g = _chain({"max_clusters": 4, "eps_bins": 1.5})
    assert dict(g.infer_types()["clu"].axes) == {"frame": 2, "cluster": 4, "feature": 5}
    out = evaluate(g, {"det": masks, "pw": powers})["out"]
    np.testing.assert_array_equal(out[0], cluster_detections(mask, power, max_clusters=4))
    assert not out[1].any()
    assert CLUSTER_FEATURES == FEATURES


@pytest.mark.parametrize(("change", "match"), [
    ({"cluster": {"axes": ["range", "angle"]}}, "axes entry 'angle' is not an axis"),
    ({"cluster": {"axes": ["range", "range"]}}, "repeat an axis"),
    ({"power_domain": "db"}, "input domain 'db' is not accepted"),
])
def test_ir_cluster_rejects_bad_graphs_naming_the_node(change, match) -> None:
    with pytest.raises(IRError, match=match) as info:
        _chain(change.get("cluster", {}), power_domain=change.get("power_domain", "power"))
    assert info.value.node == "clu" and "node 'clu' (cluster)" in str(info.value)


def test_ir_cluster_input_types_are_checked() -> None:
    m = TensorType(axes={"doppler": 4, "range": 4}, domain="mask")
    op = Cluster()
    with pytest.raises(IRError, match="must be a detection mask"):
        op.infer("clu", [m.replace(domain="power")])
    with pytest.raises(IRError, match="power map's axes"):
        op.infer("clu", [m, TensorType(axes={"range": 4, "doppler": 4}, domain="power")])
    with pytest.raises(IRError, match="input is complex"):
        op.infer("clu", [m, TensorType(axes=m.axes, complex=True)])
    with pytest.raises(IRError, match="takes 1 input"):
        op.infer("clu", [m, m.replace(domain="power"), m])
    batch = TensorType(axes={"cluster": 2, "doppler": 4, "range": 4}, domain="mask")
    with pytest.raises(IRError, match="clash with the table axes"):
        op.infer("clu", [batch])
    assert op.infer("clu", [m]).axes == {"cluster": 16, "feature": 5}
