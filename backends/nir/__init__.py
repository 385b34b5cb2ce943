"""NIR interoperability: export spiking networks to NIR graphs, read NIR graphs back.

:func:`export_network` / :func:`export_program` map populations, projections and
ports onto NIR nodes (see :mod:`backends.nir.export` and
:mod:`backends.nir.neurons`) and return an :class:`ExportReport` of what is
exact, lowered to an equivalent construction, or outside NIR;
:func:`write_nir` writes both.  :func:`import_nir` reads a graph back as spiking
networks — radarsnn's own exports exactly (:mod:`backends.nir.roundtrip`), other
graphs of the supported subset (:mod:`backends.nir.generic`) — and
:func:`read_nir` reads a file within bounds (:mod:`backends.nir.reading`).
Requires the ``nir`` package (1.0.x).
"""

from backends.nir.export import (
    CONVENTION,
    MAX_WEIGHTS,
    export_network,
    export_program,
    nir_name,
    write_nir,
)
from backends.nir.reading import ReadBounds, read_nir
from backends.nir.report import ExportReport, ReportEntry
from backends.nir.roundtrip import import_nir

__all__ = [
    "CONVENTION",
    "MAX_WEIGHTS",
    "ExportReport",
    "ReadBounds",
    "ReportEntry",
    "export_network",
    "export_program",
    "import_nir",
    "nir_name",
    "read_nir",
    "write_nir",
]
