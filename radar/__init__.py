"""The radar domain: configurations and presets, a seeded FMCW scene simulator,
loaders for real captures, readers of files on disk (TI raw ``.bin``, ``.mat``, ``.npz``),
and the conventional DSP/CFAR reference.

Submodules: :mod:`radar.config` (presets; the record in :mod:`radar.sensor`),
:mod:`radar.scene`, :mod:`radar.scene_cases` (hard scenes drawn per seed), :mod:`radar.loaders`,
:mod:`radar.ti_capture`, :mod:`radar.readers`, :mod:`radar.mat_reader`, :mod:`radar.files`,
:mod:`radar.windows`, :mod:`radar.dsp`, :mod:`radar.spectra`, :mod:`radar.cfar_window`,
:mod:`radar.cfar`, :mod:`radar.cfar_theory`.  The detector is
``radar.cfar.cfar``; the package does not re-export it, so ``radar.cfar`` stays
the module.
"""

from radar.cfar import noise_estimate
from radar.cfar_theory import ca_alpha, ca_pfa, os_alpha, os_pfa
from radar.cfar_window import n_training, training_mask
from radar.config import PRESETS, RadarConfig, preset
from radar.dsp import dft, dft_matrix, magnitude, to_db
from radar.loaders import load_openradar, load_ti_chirps
from radar.readers import read_mat_array, read_npy_array, read_npz_array
from radar.scene import SCENE_PRESETS, Frame, Scene, Target, simulate_frame
from radar.scene_cases import SCENE_CASES
from radar.spectra import range_doppler_map
from radar.ti_capture import TiBinLayout, read_ti_bin
from radar.windows import apply_window

__all__ = [
    "PRESETS",
    "SCENE_CASES",
    "SCENE_PRESETS",
    "Frame",
    "RadarConfig",
    "Scene",
    "Target",
    "TiBinLayout",
    "apply_window",
    "ca_alpha",
    "ca_pfa",
    "dft",
    "dft_matrix",
    "load_openradar",
    "load_ti_chirps",
    "magnitude",
    "n_training",
    "noise_estimate",
    "os_alpha",
    "os_pfa",
    "preset",
    "range_doppler_map",
    "read_mat_array",
    "read_npy_array",
    "read_npz_array",
    "read_ti_bin",
    "simulate_frame",
    "to_db",
    "training_mask",
]
