"""Valid, unique Python identifiers for arbitrary node, population and port ids.

:class:`Namespace` maps an original id (any string: dashes, dots, unicode,
keywords, leading digits) to an identifier ``<prefix><slug>`` where the slug
keeps ASCII letters and digits (accents folded by NFKD, every other run of
characters becomes ``_``, lower case, at most 32 characters); collisions get
``_2``, ``_3``, …  The mapping is recorded so users can find their nodes.

Examples
--------
>>> ns = Namespace("stage_")
>>> ns.name("Range-FFT.v2"), ns.name("range_fft_v2"), ns.name("1é"), ns.name("")
('stage_range_fft_v2', 'stage_range_fft_v2_2', 'stage_1e', 'stage_x')
>>> ns.mapping["Range-FFT.v2"]
'stage_range_fft_v2'
"""

from __future__ import annotations

import keyword
import re
import unicodedata

from ir.errors import CompileError

__all__ = ["Namespace", "slug"]

_MAX_SLUG = 32
_VALID = re.compile(r"[a-z_][a-z0-9_]*")


def slug(text: str) -> str:
    """``text`` folded to lower-case ASCII letters, digits and single underscores.

    Examples
    --------
    >>> slug("__import__('os')"), slug("Doppler FFT"), slug("класс")
    ('import_os', 'doppler_fft', 'x')
    """
    ascii_text = unicodedata.normalize("NFKD", str(text)).encode("ascii", "ignore").decode()
    s = re.sub(r"[^0-9a-zA-Z]+", "_", ascii_text).strip("_").lower()
    return s[:_MAX_SLUG].rstrip("_") or "x"


class Namespace:
    """Identifiers with one prefix, unique within the namespace.

    Parameters
    ----------
    prefix : str
        A valid identifier start (e.g. ``"stage_"``, ``"update_"``).
    reserved : iterable of str
        Names that must not be produced.
    """

    def __init__(self, prefix: str, reserved: tuple[str, ...] = ()) -> None:
        if not _VALID.fullmatch(prefix):
            raise CompileError(f"bad identifier prefix {prefix!r}")
        self.prefix = prefix
        self.taken: set[str] = set(reserved)
        self.mapping: dict[str, str] = {}

    def name(self, original: str) -> str:
        """The identifier of ``original`` (the same one when asked again).

        Raises
        ------
        CompileError
            Never for any input string; only if the result failed the final check.
        """
        if original in self.mapping:
            return self.mapping[original]
        base = self.prefix + slug(original)
        if base[0].isdigit():
            base = "n" + base
        candidate, i = base, 2
        while candidate in self.taken or keyword.iskeyword(candidate):
            candidate, i = f"{base}_{i}", i + 1
        if not _VALID.fullmatch(candidate) or not candidate.isidentifier():
            raise CompileError(f"could not make an identifier for {original!r}")
        self.taken.add(candidate)
        self.mapping[original] = candidate
        return candidate
