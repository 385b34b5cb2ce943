"""NIR interoperability: export spiking networks to NIR graphs, import NIR graphs as classifiers.

:func:`export_network` / :func:`export_program` map populations, projections and
ports onto NIR nodes (see :mod:`backends.nir.export` and
:mod:`backends.nir.neurons`) and return an :class:`ExportReport` of what is
exact, lowered to an equivalent construction, or outside NIR;
:func:`write_nir` writes both.  Requires the ``nir`` package (1.0.x).
"""

from backends.nir.export import (
    CONVENTION,
    MAX_WEIGHTS,
    export_network,
    export_program,
    nir_name,
    write_nir,
)
from backends.nir.report import ExportReport, ReportEntry

__all__ = [
    "CONVENTION",
    "MAX_WEIGHTS",
    "ExportReport",
    "ReportEntry",
    "export_network",
    "export_program",
    "nir_name",
    "write_nir",
]
