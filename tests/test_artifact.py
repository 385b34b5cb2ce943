"""Artifacts: lossless round trips, byte-identical output, and every corruption refused."""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from backends import ARTIFACT_VERSION, load, save
from backends.artifact import read_manifest
from backends.artifact_io import ARRAYS_FILE, MANIFEST_FILE
from compiler.snn import (
    N_PARTS,
    Decoder,
    Encoder,
    LatencyCode,
    MatrixProjection,
    NeuronParams,
    Phase,
    Population,
    RateCode,
    SpikingNetwork,
    StencilProjection,
)
from ir.errors import ArtifactError, NetworkError

# ---------------------------------------------------------------- helpers


def _tiny() -> SpikingNetwork:
    """Two inputs, one neuron, one dense projection (the hand-checked network)."""
    return SpikingNetwork(
        name="tiny", n_steps=8, meta={"policy": "exact", "ks": [1, 2]},
        populations=[Population(id="in", shape={"i": 2}, source=True),
                     Population(id="out", shape={"o": 1}, params=NeuronParams(v_th=2.0))],
        projections=[MatrixProjection(id="w", source="in", target="out", contract=("i",),
                                      produce=("o",), weights=np.array([[0.5], [-1.25]]))],
        encoders=[Encoder(port="x", population="in",
                          code=LatencyCode(t_max=8, x_min=0.0, x_max=1.0))],
        decoders=[Decoder(port="y", population="out", kind="spiked")])


def _rich() -> SpikingNetwork:
    """Dense + sparse + stencil projections, delays, phases, all decoder kinds."""
    ramp = NeuronParams(du=0.0, dv=0.0, v_th=4.0, reset="fire_once",
                        phases=(Phase(start_step=0, spiking_on=False),
                                Phase(start_step=4, bias=1.0, input_on=False)))
    pops = [Population(id="in", shape={"rep": 2, "i": 3, "part": 2}, source=True),
            Population(id="h", shape={"o": 4, "rep": 2}, params=ramp,
                       origin={"node": "rdft", "motif": "sft"}),
            Population(id="m", shape={"o": 4, "rep": 2}, params=NeuronParams(du=0.5, dv=0.25)),
            Population(id="s", shape={"o": 4, "rep": 2}, params=NeuronParams(reset="value"))]
    w = np.arange(24, dtype=float).reshape(6, 4) / 8 - 1
    projs = [MatrixProjection(id="dense", source="in", target="h", contract=("i", "part"),
                              produce=("o",), weights=w, delays=(np.arange(24) % 3).reshape(6, 4)),
             StencilProjection(id="st", source="h", target="m", axes=("o", "rep"),
                               kernel=np.array([[-1.0, 0.0, 2.0]] * 3), edge=("wrap", "clip"),
                               delays=np.ones((3, 3), np.int64)),
             MatrixProjection(id="sp", source="m", target="s", contract=("o",), produce=("o",),
                              rows=[0, 3], cols=[1, 2], values=[0.75, -2.0], n_in_out=(4, 4))]
    decs = [Decoder(port=f"y_{k}", population=p, kind=k, missing=float("nan"), scale=-0.5)
            for k, p in (("spike_time", "h"), ("count", "m"), ("membrane", "s"), ("spiked", "h"))]
    return SpikingNetwork(name="rich", n_steps=8, populations=pops, projections=projs,
                          encoders=[Encoder(port="x", population="in", split="re_im",
                                            code=RateCode(max_rate=0.25, phase=0.5))],
                          decoders=decs)


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _dump(model) -> str:
    return json.dumps(model.model_dump(mode="json"), sort_keys=True)  # NaN-safe comparison


def assert_same_network(a: SpikingNetwork, b: SpikingNetwork) -> None:
    """Field-by-field equality; arrays bit for bit (``-0.0`` and dtypes included)."""
    assert (a.name, a.n_steps, a.meta) == (b.name, b.n_steps, b.meta)
    assert [(p, list(p.shape.items())) for p in a.populations] == \
        [(p, list(p.shape.items())) for p in b.populations]
    assert [_dump(e) for e in a.encoders] == [_dump(e) for e in b.encoders]
    assert [_dump(d) for d in a.decoders] == [_dump(d) for d in b.decoders]
    assert [type(p) for p in a.projections] == [type(p) for p in b.projections]
    for pa, pb in zip(a.projections, b.projections, strict=True):
        for f in dataclasses.fields(pa):
            va, vb = getattr(pa, f.name), getattr(pb, f.name)
            if isinstance(va, np.ndarray):
                assert (va.dtype, va.shape, va.tobytes()) == (vb.dtype, vb.shape, vb.tobytes())
            else:
                assert va == vb, f.name


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _resign(folder: Path, manifest: dict | None = None, npz: bytes | None = None) -> None:
    """Forge a self-consistent artifact, following docs/artifact.md (not the module's code)."""
    if manifest is None:
        manifest = json.loads((folder / MANIFEST_FILE).read_text())
    if npz is not None:
        (folder / ARRAYS_FILE).write_bytes(npz)
        manifest["arrays"].update(sha256=_sha(npz), n_bytes=len(npz))
    body = {k: v for k, v in manifest.items() if k != "manifest_sha256"}
    canonical = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    manifest["manifest_sha256"] = _sha(canonical.encode())
    (folder / MANIFEST_FILE).write_text(json.dumps(manifest, sort_keys=True, indent=2) + "\n")


def _npz(arrays: dict[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _stored_arrays(folder: Path) -> dict[str, np.ndarray]:
    with np.load(folder / ARRAYS_FILE) as npz:
        return {k: npz[k] for k in npz.files}


@pytest.fixture
def rich_dir(tmp_path: Path) -> Path:
    return save(_rich(), tmp_path / "art")


# ---------------------------------------------------------------- random networks

_floats = st.floats(allow_nan=False, allow_infinity=False, width=64)


def _weights(shape: tuple[int, ...]):
    return hnp.arrays(np.float64, shape, elements=_floats)


def _delays(shape: tuple[int, ...], low: int = 0):
    return st.none() | hnp.arrays(np.int64, shape, elements=st.integers(low, 5))


@st.composite
def _params(draw, n_steps: int) -> NeuronParams:
    starts = sorted(draw(st.sets(st.integers(1, n_steps - 1), max_size=2)))
    phases = tuple(Phase(start_step=s, bias=draw(_floats), input_on=draw(st.booleans()),
                         spiking_on=draw(st.booleans())) for s in [0, *starts])
    return NeuronParams(du=draw(st.floats(0, 1)), dv=draw(st.floats(0, 1)),
                        v_th=draw(st.floats(1e-3, 1e6)), v_reset=draw(_floats),
                        reset=draw(st.sampled_from(["value", "subtract", "fire_once"])),
                        phases=phases)


@st.composite
def networks(draw) -> SpikingNetwork:
    n_steps = draw(st.integers(2, 12))
    n_rep, n_in, n_out = (draw(st.integers(1, 4)) for _ in range(3))
    split = draw(st.sampled_from(sorted(N_PARTS)))
    parts = {"part": N_PARTS[split]} if N_PARTS[split] else {}
    src_axes = draw(st.permutations([("rep", n_rep), ("i", n_in)]))
    hid_axes = dict(draw(st.permutations([("rep", n_rep), ("o", n_out)])))
    code = draw(st.sampled_from([
        LatencyCode(t_min=1, t_max=n_steps, x_min=-1.5, x_max=2.0, rounding="floor"),
        LatencyCode(kind="log", t_max=n_steps, x_min=1e-3, x_max=1.0),
        RateCode(x_min=0.0, x_max=3.0, max_rate=1.0, phase=0.125)]))
    pops = [Population(id="in", shape={**dict(src_axes), **parts}, source=True),
            Population(id="h", shape=hid_axes, params=draw(_params(n_steps))),
            Population(id="m", shape=hid_axes, params=draw(_params(n_steps)),
                       origin={"node": "cfar", "motif": draw(st.text(max_size=4))})]
    contract = ("i", *parts)
    rows_in = n_in * (N_PARTS[split] or 1)
    if draw(st.booleans()):
        dense = MatrixProjection(id="w", source="in", target="h", contract=contract,
                                 produce=("o",), weights=draw(_weights((rows_in, n_out))),
                                 delays=draw(_delays((rows_in, n_out))))
    else:
        nnz = draw(st.integers(0, rows_in * n_out))
        dense = MatrixProjection(
            id="w", source="in", target="h", contract=contract, produce=("o",),
            rows=draw(hnp.arrays(np.int64, nnz, elements=st.integers(0, rows_in - 1))),
            cols=draw(hnp.arrays(np.int64, nnz, elements=st.integers(0, n_out - 1))),
            values=draw(_weights((nnz,))), n_in_out=(rows_in, n_out),
            delays=draw(_delays((nnz,))))
    axes = draw(st.sampled_from([("o",), ("o", "rep"), ("rep",)]))
    ksize = tuple(draw(st.sampled_from([1, 3, 5])) for _ in axes)
    edge = tuple("wrap" if k <= hid_axes[a] and draw(st.booleans()) else "clip"
                 for a, k in zip(axes, ksize, strict=True))
    stencil = StencilProjection(id="k", source="h", target="m", axes=axes,
                                kernel=draw(_weights(ksize)), edge=edge,
                                delays=draw(_delays(ksize)))
    projs = [dense, stencil]
    if draw(st.booleans()):  # a recurrent loop m -> h needs delays >= 1 (and a live synapse)
        projs.append(MatrixProjection(
            id="back", source="m", target="h", contract=("o",), produce=("o",),
            weights=draw(hnp.arrays(np.float64, (n_out, n_out), elements=st.floats(0.5, 2.0))),
            delays=draw(hnp.arrays(np.int64, (n_out, n_out), elements=st.integers(1, 3)))))
    decoders = [Decoder(port=f"y{i}", population=draw(st.sampled_from(["h", "m"])), kind=kind,
                        scale=draw(_floats), offset=draw(_floats), t_ref=float(n_steps),
                        missing=draw(st.floats(allow_infinity=True, allow_nan=True)))
                for i, kind in enumerate(draw(st.lists(
                    st.sampled_from(["spike_time", "count", "membrane", "spiked"]), max_size=4)))]
    meta = draw(st.dictionaries(st.text(max_size=3), st.integers() | st.text(max_size=3) | _floats,
                                max_size=3))
    return SpikingNetwork(name=draw(st.text(max_size=8)), n_steps=n_steps, populations=pops,
                          projections=projs, decoders=decoders, meta=meta,
                          encoders=[Encoder(port="x", population="in", code=code, split=split,
                                            node="adc")]).validate()


# ---------------------------------------------------------------- round trips


@given(networks())
def test_round_trip_is_lossless_and_byte_stable(net: SpikingNetwork) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        first = save(net, Path(tmp) / "a")
        back = load(first)
        assert_same_network(net, back)
        assert _files(save(back, Path(tmp) / "b")) == _files(first)


def test_manifest_by_hand(tmp_path: Path) -> None:
    folder = save(_tiny(), tmp_path, extra={"run": 7})
    manifest = json.loads((folder / MANIFEST_FILE).read_text())
    assert (manifest["format"], manifest["format_version"]) == ("radarsnn.spiking-network", "1.0")
    assert manifest["projections"][0]["arrays"]["weights"] == {
        "file": "arrays.npz", "key": "projections.0.weights", "dtype": "<f8", "shape": [2, 1]}
    assert manifest["projections"][0]["contract"] == ["i"]
    assert manifest["populations"][0]["shape"] == [["i", 2]]
    assert manifest["network"] == {"name": "tiny", "n_steps": 8,
                                   "meta": {"policy": "exact", "ks": [1, 2]}}
    assert manifest["extra"] == {"run": 7} == read_manifest(folder)["extra"]
    npz = (folder / ARRAYS_FILE).read_bytes()
    assert manifest["arrays"] == {"file": "arrays.npz", "sha256": _sha(npz), "n_bytes": len(npz)}
    assert _stored_arrays(folder)["projections.0.weights"].tolist() == [[0.5], [-1.25]]
    before = (folder / MANIFEST_FILE).read_bytes()
    _resign(folder)  # the documented recipe reproduces the digest and the exact bytes
    assert (folder / MANIFEST_FILE).read_bytes() == before


def test_axis_order_and_non_finite_decoder_fields_survive(rich_dir: Path) -> None:
    back = load(rich_dir)
    assert back.population["h"].axes == ("o", "rep")
    assert np.isnan(back.decoders[0].missing)
    assert back.projections[0].delays.tolist() == _rich().projections[0].delays.tolist()
    assert_same_network(_rich(), back)


def test_zip_members_have_fixed_dates_and_no_compression(rich_dir: Path) -> None:
    with zipfile.ZipFile(rich_dir / ARRAYS_FILE) as zf:
        infos = zf.infolist()
    assert [i.filename for i in infos] == [
        "projections.0.weights.npy", "projections.0.delays.npy", "projections.1.kernel.npy",
        "projections.1.delays.npy", "projections.2.rows.npy", "projections.2.cols.npy",
        "projections.2.values.npy"]
    assert {(i.date_time, i.compress_type) for i in infos} == {((1980, 1, 1, 0, 0, 0), 0)}


def test_bytes_do_not_depend_on_the_clock(tmp_path: Path, monkeypatch) -> None:
    first = _files(save(_rich(), tmp_path / "a"))
    fake = time.struct_time((2031, 7, 9, 13, 37, 42, 0, 190, 0))
    monkeypatch.setattr(time, "localtime", lambda *_: fake)
    monkeypatch.setattr(time, "time", lambda: 1.9e9)
    assert _files(save(_rich(), tmp_path / "b")) == first
    # the patch is effective: a zip member named by a plain string is stamped with the clock
    # (np.savez itself goes through ZipFile.open, which stamps 1980-01-01)
    assert _stamped() != (1980, 1, 1, 0, 0, 0)
    assert _stamped() == (2031, 7, 9, 13, 37, 42)


def _stamped() -> tuple[int, ...]:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        zf.writestr("a.npy", b"")
    return zipfile.ZipFile(buffer).infolist()[0].date_time


def test_save_refuses_invalid_networks_and_non_json_meta(tmp_path: Path) -> None:
    bad = _tiny()
    bad.decoders = [Decoder(port="y", population="nowhere", kind="spiked")]
    with pytest.raises(NetworkError, match="nowhere"):
        save(bad, tmp_path)
    for meta, hint in (({"t": (1, 2)}, "round trip"), ({"x": np.int64(3)}, "int64"),
                       ({"x": float("nan")}, "not JSON compliant"), ({1: "a"}, "round trip")):
        net = _tiny()
        net.meta = meta
        with pytest.raises(ArtifactError, match=f"network meta cannot be stored.*{hint}"):
            save(net, tmp_path)
    net = _tiny()
    net.n_steps = np.int64(8)  # numpy integers are accepted where an int is meant
    assert load(save(net, tmp_path)).n_steps == 8
    net.name = ("not", "a", "string")
    with pytest.raises(ArtifactError, match="network name cannot be stored"):
        save(net, tmp_path)
    with pytest.raises(ArtifactError, match="extra cannot be stored"):
        save(_tiny(), tmp_path, extra={"a": {1, 2}})
    with pytest.raises(ArtifactError, match="kind 'matrix'.*not in the registry"):
        save(_tiny(), tmp_path, kinds={"stencil": StencilProjection})


def _ramp() -> SpikingNetwork:
    """The fire-once feed-forward part of :func:`_rich` (eligible for the closed form)."""
    rich = _rich()
    return SpikingNetwork(name="ramp", n_steps=8, populations=rich.populations[:2],
                          projections=rich.projections[:1], encoders=rich.encoders,
                          decoders=[d for d in rich.decoders if d.population == "h"])


@pytest.mark.parametrize(("build", "modes"), [(_rich, ("step",)), (_ramp, ("step", "closed"))])
def test_loaded_network_simulates_identically(build, modes, tmp_path: Path) -> None:
    from backends.reference import simulate

    net = build()
    back = load(save(net, tmp_path))
    x = np.random.default_rng(3).normal(size=(5, 2, 3)) + 1j  # 5 frames of (rep, i) values
    for mode in modes:  # random values beyond the rate code's [0, 1]: clipped alike on both
        ours, theirs = (simulate(n, {"x": x}, mode=mode, out_of_range="clip") for n in (net, back))
        assert theirs.mode == mode
        assert ours.outputs.keys() == theirs.outputs.keys() and ours.total_spikes > 0
        for port in ours.outputs:
            np.testing.assert_array_equal(ours.outputs[port], theirs.outputs[port])
        for pid, steps in ours.first_spike_steps.items():
            np.testing.assert_array_equal(steps, theirs.first_spike_steps[pid])
        assert (ours.spike_counts, ours.synaptic_events) == \
            (theirs.spike_counts, theirs.synaptic_events)


# ---------------------------------------------------------------- corruption


def _load_error(folder: Path, match: str | None = None) -> ArtifactError:
    with pytest.raises(ArtifactError, match=match) as info:
        load(folder)
    return info.value


def _saved_files(net: SpikingNetwork) -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as tmp:
        return _files(save(net, tmp))


_GOOD = _saved_files(_rich())


@given(name=st.sampled_from(sorted(_GOOD)), data=st.data())
def test_every_byte_flip_or_truncation_is_refused(name: str, data) -> None:
    original = _GOOD[name]
    if data.draw(st.booleans(), label="truncate"):
        changed = original[:data.draw(st.integers(0, len(original) - 1), label="length")]
    else:
        at = data.draw(st.integers(0, len(original) - 1), label="at")
        flip = data.draw(st.integers(1, 255), label="xor")
        changed = original[:at] + bytes([original[at] ^ flip]) + original[at + 1:]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for other, content in _GOOD.items():
            (folder / other).write_bytes(changed if other == name else content)
        _load_error(folder)


def test_missing_files_and_garbage_json(rich_dir: Path, tmp_path: Path) -> None:
    _load_error(tmp_path / "nowhere", "manifest.json: cannot read")
    (rich_dir / ARRAYS_FILE).unlink()
    _load_error(rich_dir, "arrays.npz: cannot read")
    for junk, why in ((b"{not json", "not valid UTF-8 JSON"), (b"\xff\xfe", "not valid UTF-8"),
                      (b"[1, 2]", "top level is a list"), (b"", "not valid")):
        (rich_dir / MANIFEST_FILE).write_bytes(junk)
        _load_error(rich_dir, why)


def test_edits_to_the_manifest_are_refused(rich_dir: Path) -> None:
    manifest = json.loads((rich_dir / MANIFEST_FILE).read_text())
    (rich_dir / MANIFEST_FILE).write_text(json.dumps(manifest, sort_keys=True, indent=4))
    _load_error(rich_dir, "canonical form")
    manifest["network"]["n_steps"] = 9  # a canonically rendered edit without re-signing
    (rich_dir / MANIFEST_FILE).write_text(json.dumps(manifest, sort_keys=True, indent=2) + "\n")
    _load_error(rich_dir, "digest mismatch")
    manifest["decoders"][0]["missing"] = float("nan")  # a NaN token is not strict JSON
    (rich_dir / MANIFEST_FILE).write_text(json.dumps(manifest, sort_keys=True, indent=2) + "\n")
    _load_error(rich_dir, "canonical form")


def test_versions_and_format_names(rich_dir: Path) -> None:
    manifest = json.loads((rich_dir / MANIFEST_FILE).read_text())
    assert manifest["format_version"] == ARTIFACT_VERSION == "1.0"
    for version, why in (("2.0", r"format 2\.0; this radarsnn .* reads 1\.x: upgrade"),
                         ("0.9", "older than 1.x"), ("one", "not MAJOR.MINOR"),
                         (1.0, "not MAJOR.MINOR")):
        _resign(rich_dir, {**manifest, "format_version": version})
        _load_error(rich_dir, why)
    _resign(rich_dir, {**manifest, "format_version": "1.7", "added_in_1_7": True})
    assert_same_network(load(rich_dir), _rich())  # a newer minor of our major is read
    _resign(rich_dir, {**manifest, "format": "nir"})
    _load_error(rich_dir, "format is 'nir'")


def test_truncated_and_flipped_npz(rich_dir: Path) -> None:
    raw = (rich_dir / ARRAYS_FILE).read_bytes()
    (rich_dir / ARRAYS_FILE).write_bytes(raw[:-10])
    _load_error(rich_dir, "truncated or was modified")
    (rich_dir / ARRAYS_FILE).write_bytes(raw[:200] + bytes([raw[200] ^ 1]) + raw[201:])
    _load_error(rich_dir, "truncated or was modified")


def test_forged_arrays_are_checked_behind_the_digest(rich_dir: Path) -> None:
    good = _stored_arrays(rich_dir)
    key = "projections.0.weights"
    for arrays, why in (
            ({k: v for k, v in good.items() if k != key}, f"{key}' is missing"),
            ({**good, key: good[key].astype(np.float32)}, "dtype <f4 .* declares <f8"),
            ({**good, key: good[key][:2]}, r"shape \[2, 4\], the manifest declares <f8 and \[6, "),
            ({**good, "stowaway": np.zeros(1)}, "does not refer to: \\['stowaway'\\]")):
        _resign(rich_dir, npz=_npz(arrays))
        _load_error(rich_dir, why)
    _resign(rich_dir, npz=b"PK\x05\x06" + bytes(18))  # an empty zip: every array missing
    _load_error(rich_dir, "is missing")
    _resign(rich_dir, npz=b"not a zip at all")
    _load_error(rich_dir, "not a readable .npz")


_UNPICKLED: list[str] = []


def _mark() -> str:
    _UNPICKLED.append("ran")
    return "boom"


class _Payload:
    def __reduce__(self):
        return (_mark, ())


def test_pickled_arrays_never_run(rich_dir: Path) -> None:
    good = _stored_arrays(rich_dir)
    evil = np.array([_Payload()], dtype=object)
    _resign(rich_dir, npz=_npz({**good, "projections.0.weights": evil}))
    _load_error(rich_dir, "allow_pickle")
    assert _UNPICKLED == []


def test_forged_manifest_entries_are_checked(rich_dir: Path) -> None:
    manifest = json.loads((rich_dir / MANIFEST_FILE).read_text())

    def forged(path: list, value) -> dict:
        edited = json.loads(json.dumps(manifest))
        node = edited
        for step in path[:-1]:
            node = node[step]
        node[path[-1]] = value
        return edited

    cases = [
        (["decoders", 0, "population"], "ghost", "stored network is invalid.*ghost"),
        (["populations", 1, "params", "v_th"], -1.0, "does not parse.*v_th"),
        (["populations", 1, "shape"], [["o", 4], ["o", 2]], "repeats an axis"),
        (["projections", 2, "kind"], "conv", "unknown projection kind 'conv'"),
        (["projections", 2, "bogus"], 1, r"fields \['bogus'\] are not fields"),
        (["projections", 0, "arrays", "weights", "file"], "other.npz", "must name file"),
        (["arrays", "file"], "other.npz", "must name 'arrays.npz'"),
        (["network"], {"name": "x"}, "malformed entry.*KeyError"),
        (["projections", 1, "edge"], ["wrap"], "invalid.*edge"),
    ]
    for path, value, why in cases:
        _resign(rich_dir, forged(path, value))
        err = _load_error(rich_dir, why)
        assert str(rich_dir) in str(err)


# ---------------------------------------------------------------- hostile sizes and nesting


def _npy_with_header(shape: tuple, data: bytes = b"\0" * 64, descr: str = "<f8") -> bytes:
    """A ``.npy`` whose header declares ``shape`` whatever the data (a forger's member)."""
    header = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + data


def _zip(members: dict[str, bytes], method: int = zipfile.ZIP_STORED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=method) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buffer.getvalue()


def test_artifact_files_over_their_size_caps_are_refused_unread(rich_dir: Path) -> None:
    from backends.artifact_io import MAX_ARRAYS_BYTES, MAX_MANIFEST_BYTES

    arrays = rich_dir / ARRAYS_FILE
    with arrays.open("r+b") as f:  # sparse: 4 GiB + 1 on disk costs nothing
        f.truncate(MAX_ARRAYS_BYTES + 1)
    _load_error(rich_dir, rf"arrays\.npz: {MAX_ARRAYS_BYTES + 1} bytes, over the limit of "
                          f"{MAX_ARRAYS_BYTES} bytes")
    manifest = rich_dir / MANIFEST_FILE
    with manifest.open("r+b") as f:
        f.truncate(MAX_MANIFEST_BYTES + 1)
    _load_error(rich_dir, rf"manifest\.json: {MAX_MANIFEST_BYTES + 1} bytes, over the limit")


@pytest.mark.parametrize(("member", "why"), [
    (_npy_with_header((10**12,)), r"declares shape \(1000000000000,\) of <f8 \(8000000000000 "
                                  r"bytes\) but the member holds 64 bytes"),
    (_npy_with_header((2**62, 4)), r"declares shape \(4611686018427387904, 4\)"),
    (_npy_with_header((-8,)), r"declares shape \(-8,\)"),
    (_npy_with_header((1,) * 100, b"\0" * 8), r"not a readable \.npz.*64"),
    (_npy_with_header((3,), b"\0" * 24, "|O"), "object arrays are refused"),
])
def test_npz_members_are_checked_before_numpy_allocates(rich_dir: Path, member: bytes,
                                                        why: str) -> None:
    good = _stored_arrays(rich_dir)
    members = {f"{k}.npy": _npy(v) for k, v in good.items()}
    members["projections.0.weights.npy"] = member
    _resign(rich_dir, npz=_zip(members))  # digests re-signed: the parser must catch it
    err = _load_error(rich_dir, why)
    assert "projections.0.weights.npy" in str(err) or "not a readable" in str(err)


def _npy(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=False)
    return buffer.getvalue()


def test_deflated_members_and_odd_zips_are_artifact_errors(rich_dir: Path) -> None:
    good = {f"{k}.npy": _npy(v) for k, v in _stored_arrays(rich_dir).items()}
    deflated = bytearray(_zip(good, zipfile.ZIP_DEFLATED))
    with zipfile.ZipFile(io.BytesIO(bytes(deflated))) as zf:
        info = zf.getinfo("projections.0.weights.npy")
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    deflated[start] = 0xFF  # deflate block type 3: invalid (zlib.error, not a CRC mismatch)
    _resign(rich_dir, npz=bytes(deflated))
    _load_error(rich_dir, r"member '.*\.npy' is compressed; radarsnn stores every member "
                          r"uncompressed")
    _resign(rich_dir, npz=_zip({**good, "notes.txt": b"hi"}))
    _load_error(rich_dir, r"member 'notes\.txt' is not a \.npy array")
    from backends.artifact_io import read_npz

    with pytest.raises(ArtifactError, match=r"members declare \d+ bytes uncompressed, over the "
                                            "limit of 100 bytes"):
        read_npz(_zip(good), rich_dir / ARRAYS_FILE, limit=100)


@pytest.mark.parametrize("version", ["\u00b20.0", "1.\u00b2", "1" * 5000 + ".0"])
def test_format_versions_are_ascii_major_minor(rich_dir: Path, version: str) -> None:
    manifest = json.loads((rich_dir / MANIFEST_FILE).read_text())
    manifest["format_version"] = version
    _resign(rich_dir, manifest)
    _load_error(rich_dir, r"format_version .* is not MAJOR\.MINOR \(digits 0-9\)")


def test_deeply_nested_manifests_are_refused_without_recursion(rich_dir: Path) -> None:
    text = (rich_dir / MANIFEST_FILE).read_text()
    deep = text.replace('"extra": {}', '"extra": ' + "[" * 5000 + "]" * 5000, 1)
    assert deep != text
    (rich_dir / MANIFEST_FILE).write_text(deep)
    _load_error(rich_dir, r"manifest\.json: line \d+: nested deeper than 64 levels")
