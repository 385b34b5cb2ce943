"""The package being generated: stage modules, stored arrays and the name mapping.

:class:`PackageBuilder` is the emitters' shared state.  Stage modules are named
after IR nodes (``stage_<slug>``), their functions after populations,
projections and ports (``update_``, ``deliver_``, ``encode_``, ``decode_``
+ slug), each unique in its module; :attr:`PackageBuilder.names` records every
original id → generated name.  Arrays go to ``weights.npz`` under the key
``<module>.<function>.<k>.<part>``.

Examples
--------
>>> import numpy as np
>>> pkg = PackageBuilder()
>>> module = pkg.stage("rng-fft")
>>> fn = pkg.function(module, "update_", "rng-fft/out")
>>> key = pkg.store(module, fn, 0, "w", np.eye(2))
>>> module, fn, key, sorted(pkg.arrays)
('stage_rng_fft', 'update_rng_fft_out', 'stage_rng_fft.update_rng_fft_out', \
['stage_rng_fft.update_rng_fft_out.0.w'])
"""

from __future__ import annotations

import numpy as np

from backends.emit.names import Namespace
from backends.emit.render import Code, join

__all__ = ["PackageBuilder", "RESERVED_MODULES"]

#: Module names of the fixed files of every generated package.
RESERVED_MODULES = ("_kernels", "program", "__init__", "__main__")


class PackageBuilder:
    """Stage modules (functions in order), arrays for ``weights.npz`` and the id mapping."""

    def __init__(self) -> None:
        self.modules = Namespace("stage_", RESERVED_MODULES)
        self.functions: dict[str, dict[str, Namespace]] = {}
        self.bodies: dict[str, list[Code]] = {}
        self.nodes: dict[str, str] = {}
        self.arrays: dict[str, np.ndarray] = {}
        self.names: dict[str, dict[str, str]] = {"stages": self.modules.mapping}

    def stage(self, node: str) -> str:
        """The stage module of IR node ``node`` (created on first use)."""
        module = self.modules.name(node)
        if module not in self.bodies:
            self.bodies[module] = []
            self.functions[module] = {}
            self.nodes[module] = node
        return module

    def function(self, module: str, prefix: str, original: str) -> str:
        """A fresh function name ``<prefix><slug>`` in ``module`` for ``original``."""
        spaces = self.functions[module]
        space = spaces.setdefault(prefix, Namespace(prefix))
        if original in space.mapping:  # the same id in another network: a new name
            original = f"{original}#{len(space.mapping)}"
        name = space.name(original)
        self.names.setdefault(prefix.rstrip("_"), {})[f"{module}.{name}"] = original
        return name

    def add(self, module: str, code: Code) -> None:
        """Append a function's code to ``module``."""
        self.bodies[module].append(code)

    def store(self, module: str, fn: str, k: int, part: str, array: np.ndarray) -> str:
        """Keep ``array`` for ``weights.npz``; return the key prefix ``<module>.<fn>``."""
        key = f"{module}.{fn}"
        self.arrays[f"{key}.{k}.{part}"] = np.ascontiguousarray(array)
        return key

    def module_code(self, module: str) -> Code:
        """The functions of ``module`` concatenated."""
        return join(self.bodies[module], "")
