"""gransim from Python: cases loaded from files or built from dicts, keys
changed by dotted paths, runs in this process over libgransim, results as
numpy arrays and pandas DataFrames.

    import gransim
    case = gransim.Case.load("examples/high-shear-batch.yaml")
    case["output.end"] = 60
    result = case.run("out")
    result.summary          # DataFrame
    result.psd()            # size distribution at the last output time

Errors of gransim (a bad key, a failed run) raise gransim.GransimError with
gransim's own message.  docs/python.md describes the package.
"""
from ._library import GransimError, lib as _lib
from .case import Case
from .result import Result
from .study import sweep, with_units

__version__ = _lib.gs_version_number().decode()


def version():
    """The library's version with `git describe` where it was built from a checkout."""
    return _lib.gs_version().decode()


__all__ = ["Case", "Result", "GransimError", "sweep", "with_units", "version", "__version__"]
