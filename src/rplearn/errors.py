"""Exception hierarchy of rplearn.

Every error a user can cause derives from :class:`RplearnError`; its message is one line
naming the file, row or field at fault and what was expected.
"""

from __future__ import annotations

from collections.abc import Sequence


class RplearnError(Exception):
    """Base class of every error rplearn raises on purpose.

    Parameters
    ----------
    message : str
        One line naming the file, row, field or parameter at fault and what was expected.
        Library messages name parameters and fields, never command-line flags.
    param : str, optional
        Name of the library parameter (or option field) whose value is at fault, e.g.
        ``"max_gap_s"``; the command line maps it to the flag that sets it.
    related : sequence of str
        Other parameter names the message mentions (e.g. the one a remedy would set), so
        that the command line can name their flags too.
    """

    def __init__(self, message: str = "", *, param: str | None = None, related: Sequence[str] = ()) -> None:
        super().__init__(message)
        self.param = param
        self.related = tuple(related)


class InputError(RplearnError, ValueError):
    """Bad user input: a wrong shape, a NaN, an out-of-range value, an unknown name."""


class BadValueError(InputError):
    """A parameter's value is none of the words it takes or not of its form (``loss='xyz'``, a
    link ``'A:B:C'``), found from the value alone: the command line reports it, when a flag gave
    it and before any input was read, as a usage error (exit code 2). A value out of its range
    or against another parameter is a plain :class:`InputError`."""


class ArgumentTypeError(InputError, TypeError):
    """An argument of a public function is of the wrong type (see :mod:`rplearn._argtypes`)."""


class FarFieldError(InputError):
    """A sample is closer than the far-field limit d > 2 lambda (paper Sec. III)."""


class IdentifiabilityError(RplearnError):
    """The samples cannot identify the requested model (too few, or poorly spread)."""


class NotPositiveDefinite(IdentifiabilityError):
    """The regularised normal matrix of a joint solve is not positive definite in float64, or
    LAPACK refused to factorise or solve with it (:mod:`rplearn.core.lsq.factor`)."""


class ModelFileError(RplearnError):
    """A model file is missing, malformed, truncated, tampered with or of an unknown version."""


class LogFormatError(RplearnError):
    """A flight or signal log cannot be read: missing column, corrupt bytes, bad timestamps."""


class PlanError(RplearnError):
    """A trajectory plan violates a limit the user gave (speed, acceleration, flight time)."""
