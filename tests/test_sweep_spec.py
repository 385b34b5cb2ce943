"""Sweep files: validation errors that name the field, grid expansion, cell ids."""

from __future__ import annotations

import json

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from ir.errors import CompileError
from radarsnn.sweep.cells import cell_key
from radarsnn.sweep.spec import SweepSpec, load_spec, parse_spec

CHAIN = {"name": "c", "nodes": [
    {"id": "x", "op": "input", "shape": {"range": 16, "doppler": 8}},
    {"id": "o", "op": "output", "input": "x"}]}


def _spec(**over):
    base = {"name": "t", "chains": {"a": CHAIN}, "grid": {"time_steps": [8, 16]},
            "frames": {"source": "scene", "n_frames": 5, "frames_per_cell": 2}}
    return {**base, **over}


@pytest.mark.parametrize(("over", "match"), [
    ({"grid": {"time_step": [8]}}, r"grid axis 'time_step' is not a compile option"),
    ({"grid": {"time_steps": []}}, r"grid axis 'time_steps' has no values"),
    ({"grid": {"time_steps": [8, 8]}}, r"grid axis 'time_steps' repeats a value"),
    ({"grid": {"chain": ["a", "zz"]}}, r"names \['zz'\], not in chains \['a'\]"),
    ({"chains": {"a": CHAIN, "b": CHAIN}}, r"2 chains \['a', 'b'\] but no grid axis 'chain'"),
    ({"options": {"charge": "constant"}}, r"options \['charge'\] are not compile options"),
    ({"metrics": [{"name": "cfar"}, {"name": "cfar"}]}, r"metric labels .* repeat"),
    ({"frames": {"source": "tape"}}, r"field 'frames'"),
    ({"frames": {"source": "scene", "n_frames": 0}}, r"field 'frames.scene.n_frames'.*given 0"),
    ({"mode": "fast"}, r"field 'mode'"),
    ({"figures": ["fig8"]}, r"field 'figures.0.kind'"),
    ({"surprise": 1}, r"field 'surprise': Extra inputs are not permitted"),
])
def test_invalid_specs_name_the_field(over, match):
    with pytest.raises(CompileError, match=match):
        parse_spec(_spec(**over))


def test_missing_field_and_file_errors(tmp_path):
    with pytest.raises(CompileError, match=r"field 'chains': Field required"):
        parse_spec({"name": "x", "frames": {"source": "scene"}})
    with pytest.raises(CompileError, match=r"cannot be read"):
        load_spec(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(CompileError, match=r"not valid YAML"):
        load_spec(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(CompileError, match=r"expected a mapping of sweep fields, got list"):
        load_spec(bad)
    code = tmp_path / "code.yaml"  # safe_load: a python tag is an error, never a call
    code.write_text("name: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(CompileError, match=r"not valid YAML"):
        load_spec(code)


def test_points_are_the_product_in_written_order():
    spec = SweepSpec.model_validate(_spec(
        chains={"a": CHAIN, "b": CHAIN}, options={"cfar_ties": "exact"}, target="loihi2",
        grid={"chain": ["b", "a"], "weight_bits": [None, 4], "charging": ["constant"]}))
    pts = spec.points()
    assert [(p.chain, p.params["weight_bits"]) for p in pts] == [
        ("b", None), ("b", 4), ("a", None), ("a", 4)]
    assert pts[1].compile_args == {
        "target": "loihi2", "motifs": None, "calibration": "static", "time_steps": None,
        "weight_bits": 4, "options": {"cfar_ties": "exact", "charging": "constant"}}
    assert pts[0].mode == "step"


def test_grid_overrides_fixed_fields():
    spec = SweepSpec.model_validate(_spec(grid={"mode": ["closed"], "target": [None]},
                                          target="loihi"))
    (p,) = spec.points()
    assert p.mode == "closed" and p.compile_args["target"] is None


def test_chain_files_are_read_relative_to_the_spec(tmp_path):
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(CHAIN))
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(_spec(chains={"a": "c.yaml"})))
    spec = load_spec(tmp_path / "s.yaml")
    assert spec.chain_dict("a")["name"] == "c"


def test_cell_key_is_canonical_and_sensitive():
    a = cell_key({"x": 1, "y": [1, 2]}, (0, 5))
    assert a == cell_key({"y": [1, 2], "x": 1}, [0, 5])
    assert a != cell_key({"x": 1, "y": [1, 2]}, (0, 6))
    assert a != cell_key({"x": 1.5, "y": [1, 2]}, (0, 5))
    assert len(a) == 16 and int(a, 16) >= 0


@given(n=st.integers(1, 500), step=st.integers(1, 64))
def test_slices_partition_the_frames(n, step):
    spec = SweepSpec.model_validate(_spec(frames={"source": "scene", "n_frames": n,
                                                  "frames_per_cell": step}))
    sl = spec.slices()
    assert sl[0][0] == 0 and sl[-1][1] == n
    assert all(b - a == step for a, b in sl[:-1]) and 0 < sl[-1][1] - sl[-1][0] <= step
    assert all(sl[i][1] == sl[i + 1][0] for i in range(len(sl) - 1))


def test_hostile_sweep_files_are_compile_errors(tmp_path):
    path = tmp_path / "laughs.yaml"
    path.write_text("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)))
    with pytest.raises(CompileError, match=r"laughs\.yaml'?: line 6: the document has more "
                                           "than 524288 YAML nodes"):
        load_spec(path)
    with pytest.raises(CompileError, match=r"cannot be read: not a regular file"):
        load_spec("/dev/zero")


def _axes(n):
    from compiler.compile import EXTRA_OPTIONS
    from radarsnn.sweep.spec import NAMED_AXES

    return sorted(set(EXTRA_OPTIONS) | set(NAMED_AXES) - {"chain"})[:n]


def test_a_grid_is_counted_before_it_is_expanded():
    # counted: the refusal names 2^33 points without building them (its time, a few
    # milliseconds, is measured by benchmarks/hostile_inputs.py)
    axes = _axes(33)
    assert len(axes) == 33
    with pytest.raises(CompileError, match=r"the grid has 8589934592 points \(the product of "
                                           r"its 33 axes' lengths \[2, 2, .*over the limit of "
                                           r"10000 \(MAX_SWEEP_POINTS\)"):
        parse_spec(_spec(grid={a: [0, 1] for a in axes}))
    with pytest.raises(CompileError, match=r"100 points x 5000 slices of frames = 500000 cells, "
                                           r"over the limit of 100000 \(MAX_SWEEP_CELLS\)"):
        parse_spec(_spec(grid={"time_steps": list(range(1, 101))},
                         frames={"source": "scene", "n_frames": 5000, "frames_per_cell": 1}))
    with pytest.raises(CompileError, match=r"serialise to \d+ bytes of compile arguments, over "
                                           r"the limit of 268435456"):
        parse_spec(_spec(grid={"time_steps": list(range(1, 1001)),
                               "input_bounds": [{"x": i, "pad": "p" * 300_000} for i in range(2)]}))
    assert len(parse_spec(_spec(grid={a: [0, 1] for a in axes[:13]})).points()) == 8192


def test_alias_bombs_in_a_sweep_file_are_refused_unexpanded(tmp_path):
    from capped import run_capped

    big, refs = "x" * 400_000, ", ".join(["*b"] * 120_000)  # 880 KB, 48 GB expanded
    head = f"name: &b {big}\nchains: {{a: c.yaml}}\nframes: {{source: scene}}\n"
    cases = {"mode.yaml": head + f"mode: [{refs}]\n",  # a refused field renders its value
             "options.yaml": head + f"options: {{input_bounds: {{x: [{refs}]}}}}\n"}  # hashed
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        assert (tmp_path / name).stat().st_size < 1 << 20
    body = """
        import json
        out = []
        for path in PATHS:
            try:
                load_spec(path)
                out.append("read")
            except CompileError as err:
                out.append(str(err)[:300])
        print(json.dumps(out))
        """.replace("PATHS", repr([str(tmp_path / n) for n in cases]))
    done = run_capped("from radarsnn.sweep.spec import load_spec\n"
                      "from ir.errors import CompileError", body, timeout_s=60)
    assert done.returncode == 0, done.stderr[-2000:]
    for text in json.loads(done.stdout):
        # refused unexpanded (expanding took minutes); the time of the 880 KB YAML parse is
        # measured by benchmarks/hostile_inputs.py
        assert "more than 16777216 bytes once its aliases are expanded" in text, text


def test_expanded_bytes_stops_on_cycles_and_counts_keys():
    from radarsnn.sweep.spec import expanded_bytes

    loop: list = []
    loop.append(loop)
    assert expanded_bytes(loop, 1000) > 1000
    assert expanded_bytes({"ab": "cde"}, 100) == 8 + 2 + 3
    with pytest.raises(CompileError, match=r"more than 16777216 bytes once its aliases"):
        parse_spec(_spec(options={"input_bounds": {"x": ["y" * (1 << 20)] * 17}}))


@given(parts=st.lists(st.recursive(
    st.none() | st.booleans() | st.integers() | st.text(max_size=5) | st.floats(allow_nan=False),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner,
                                                                 max_size=3),
    max_leaves=6), min_size=1, max_size=4), split=st.integers(0, 4))
def test_cell_keys_built_part_by_part_equal_the_whole(parts, split):
    from radarsnn.sweep.cells import Canonical, CellKey

    head, tail = parts[:split], parts[split:]
    assert CellKey(*head).then(*tail).hex() == cell_key(*parts)
    assert CellKey(*[Canonical.of(p) for p in parts]).hex() == cell_key(*parts)
