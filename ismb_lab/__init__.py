"""ismb_lab: a teaching workbench for Hopfield-network stereo matching (ISMB).

Bad input raises :class:`ParameterError` (a ``ValueError``) or
:class:`ParameterTypeError` (a ``TypeError``) naming the parameter, the rule and
the value received.
"""

from ._validation import ParameterError, ParameterTypeError

__version__ = "0.1.0"

__all__ = ["ParameterError", "ParameterTypeError", "__version__"]
