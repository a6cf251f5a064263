"""ismb_lab: a teaching workbench for Hopfield-network stereo matching (ISMB).

Bad input raises :class:`ParameterError` (a ``ValueError``) or
:class:`ParameterTypeError` (a ``TypeError``) naming the parameter, the rule and
the value received.
"""

__version__ = "0.1.0"

from ._core import numba_cache as _numba  # noqa: E402,F401  (before any kernel: numba needs a folder it can cache in)

__all__ = ["ParameterError", "ParameterTypeError", "__version__"]


def __getattr__(name):
    # Imported on first use, so that ``import ismb_lab`` (and the command line's start-up,
    # before its signal handlers are in place) does not wait for numpy.
    if name in ("ParameterError", "ParameterTypeError"):
        from ._core import validation as _validation
        return getattr(_validation, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
