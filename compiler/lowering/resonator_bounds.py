"""Values the ``resonator`` motif cannot represent, refused with the least that works.

* **Stream bits** ``B``: the calibrated peak must stream as at least one level,
  ``peak · (2^B − 1) / x_max ≥ 1``, so ``B ≥ ⌈log₂(x_max / peak + 1)⌉`` (2 at the encoder
  headroom of 2); below it every sample streams as 0 and the DFT is 0.
* **Decay** ``ρ`` on fixed-point targets: the whole rotation coefficients have
  ``C² + S² ≤ (ρ 2^F)²`` (``F`` fraction bits), so ``ρ ≥ 2^{−F}``; below it the only
  coefficient is ``(0, 0)``, every bin's gain ``g_k`` is 0 and the host decoder's ``1/|g_k|``
  is not finite.  A bin whose chosen coefficients still give no response is refused too.

Examples
--------
>>> check_levels("f", 2, x_max=2.0, peak=1.0)  # 3 levels: the peak is level 1.5 -> 2
>>> check_levels("f", 1, x_max=2.0, peak=1.0)
Traceback (most recent call last):
...
ir.errors.CompileError: node 'f': stream_bits=1 gives 1 level(s) over the encoder range 2, so \
the calibrated peak 1 streams as 0 (an all-zero DFT); give stream_bits >= 2 (or a smaller \
encoder_headroom)
>>> check_decay("f", 1e-300, None)
Traceback (most recent call last):
...
ir.errors.CompileError: node 'f': resonator_decay=1e-300 is below one step of the 12-bit \
rotation coefficients (2^-12 = 0.000244): every coefficient rounds to 0; give resonator_decay \
>= 0.000244 (or more resonator_coef_bits)
"""

from __future__ import annotations

import numpy as np

from compiler.lowering.resonator_fixed import CHIP_COEF_BITS
from ir.errors import CompileError

__all__ = ["check_decay", "check_gains", "check_levels"]


def check_levels(node: str, bits: int, x_max: float, peak: float) -> None:
    """Refuse ``bits`` whose top level leaves the calibrated ``peak`` below one level."""
    if peak <= 0 or peak * ((1 << bits) - 1) >= x_max:
        return
    least = int(np.ceil(np.log2(x_max / peak + 1)))
    raise CompileError(
        f"node {node!r}: stream_bits={bits} gives {(1 << bits) - 1} level(s) over the encoder "
        f"range {x_max:.4g}, so the calibrated peak {peak:.4g} streams as 0 (an all-zero "
        f"DFT); give stream_bits >= {least} (or a smaller encoder_headroom)", node=node)


def check_decay(node: str, rho: float, coef_bits: int | None) -> None:
    """Refuse a decay below one step of the coefficients (``coef_bits``, None: the chip's)."""
    f_bits = CHIP_COEF_BITS if coef_bits is None else int(coef_bits)
    if rho * 2.0 ** f_bits < 1.0:
        raise CompileError(
            f"node {node!r}: resonator_decay={rho:g} is below one step of the {f_bits}-bit "
            f"rotation coefficients (2^-{f_bits} = {2.0 ** -f_bits:.3g}): every coefficient "
            f"rounds to 0; give resonator_decay >= {2.0 ** -f_bits:.3g} (or more "
            "resonator_coef_bits)", node=node)


def check_gains(node: str, rho: float, f_bits: int, gains: np.ndarray | None) -> None:
    """Refuse bins whose fixed-point gain ``|g_k|`` is 0 or not finite (None: float target)."""
    if gains is not None and not np.all((gains > 0) & np.isfinite(gains)):
        raise CompileError(f"node {node!r}: resonator_decay={rho:g} leaves a bin with no "
                           f"response in {f_bits}-bit coefficients (gain 0); give a larger "
                           "resonator_decay or resonator_coef_bits", node=node)
