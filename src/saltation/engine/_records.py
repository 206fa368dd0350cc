"""The named records in which the engine's step-and-event loop takes its settings and arrays.

The engine (``_kernel_source.py``, generated into the kernel cache) imports them from here, so that each
is one class per process: numba's cache names a record's class in the signatures it stores, and finds
it again by this module's name.  Their fields are the loop's local names, in the order the engine
unpacks them.  (:mod:`saltation.engine.codegen` puts a hash of this file into the engine's source, so
that a change here compiles the engine again.)
"""

from collections import namedtuple

# Built once by integrate_kernel (numba passes a record as a struct of its fields).
Settings = namedtuple("Settings", ["exact_affine", "t_end", "p", "var", "pidx", "rtol", "atol", "max_step", "max_events",
                                   "max_steps", "tr_table", "n_surfaces", "record", "n_err", "direction",
                                   "sliding_step_cap"])
Vectors = namedtuple("Vectors", ["y", "ynew", "ytmp", "ysave", "xtmp", "fa", "fb", "fplus", "xplus", "gt", "wvec",
                                 "psi_tmp", "samples", "chatter_ring", "h_mode", "xmin", "xmax"])
Matrices = namedtuple("Matrices", ["K", "Ksave", "F", "gx", "gp", "S", "Phi_tmp"])
Work = namedtuple("Work", ["W", "WJ", "WP", "wv"])  # a field's evaluation (see _field_called)
Affine = namedtuple("Affine", ["AFF_A", "AFF_B", "AFF_W", "AFF_AP", "AFF_BP"])  # exact flows of affine modes
Taylor = namedtuple("Taylor", ["TW", "TP", "TC"])  # their series (see _exact_step)
Gradients = namedtuple("Gradients", ["hx", "hp", "gtmp", "gptmp"])
Surfaces = namedtuple("Surfaces", ["surf_sign", "surf_old", "surf_res", "slope_old", "surf_new", "slope_new"])
Flags = namedtuple("Flags", ["watched", "fixed_sign", "no_dip"])
Arrays = namedtuple("Arrays", ["vectors", "matrices", "work", "affine", "taylor", "gradients", "surfaces", "flags"])
Log = namedtuple("Log", ["ev", "ev_int", "rec", "rec_F"])  # the event log's floats and integers, the recorded steps
# the loop's scalar state (slots SF_* and SI_* of the contract), the sliding state and the surfaces' firing bits
LoopState = namedtuple("LoopState", ["state_f", "state_i", "slide", "fires"])

__all__ = ["Affine", "Arrays", "Flags", "Gradients", "Log", "LoopState", "Matrices", "Settings", "Surfaces", "Taylor",
           "Vectors", "Work"]
