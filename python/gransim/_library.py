"""Loading libgransim.so and calling it through ctypes.

The library is looked for, in this order: the file named by the environment
variable GRANSIM_LIBRARY; the installed library, at the path relative to this
package written by `cmake --install` (_paths.py); a build folder `build/` of
the source tree this package lies in; the system's library path.
"""
import ctypes
import ctypes.util
import os

_HERE = os.path.dirname(os.path.abspath(__file__))


class GransimError(Exception):
    """An error reported by gransim: the message is gransim's own (file, line,
    key and value of a bad case; time and compartment of a failed run)."""


class _Error(ctypes.Structure):
    # include/gransim/error.h: struct gs_error
    _fields_ = [("code", ctypes.c_int), ("msg", ctypes.c_char * 2048)]


def _candidates():
    env = os.environ.get("GRANSIM_LIBRARY")
    if env:
        yield env
        return
    try:
        from . import _paths  # written by cmake --install
        yield os.path.normpath(os.path.join(_HERE, _paths.LIBRARY))
    except ImportError:
        pass
    yield os.path.normpath(os.path.join(_HERE, "..", "..", "build", "libgransim.so"))
    found = ctypes.util.find_library("gransim")
    if found:
        yield found


def _load():
    tried = []
    for path in _candidates():
        if os.path.sep in path and not os.path.exists(path):
            tried.append(path)
            continue
        return ctypes.CDLL(path)
    raise ImportError("gransim: cannot find libgransim.so (tried %s); set GRANSIM_LIBRARY to its path"
                      % (", ".join(tried) or "the system's library path"))


lib = _load()

_P = ctypes.c_void_p
_S = ctypes.c_char_p
_E = ctypes.POINTER(_Error)
for name, res, args in [
    ("gs_version", _S, []),
    ("gs_version_number", _S, []),
    ("gs_api_case_load", _P, [_S, _E]),
    ("gs_api_case_from_text", _P, [_S, _S, _E]),
    ("gs_api_case_free", None, [_P]),
    ("gs_api_case_set", ctypes.c_int, [_P, _S, _S, _E]),
    ("gs_api_case_kind", ctypes.c_int, [_P]),
    ("gs_api_kind_name", _S, [ctypes.c_int]),
    ("gs_api_case_check", ctypes.c_int, [_P, ctypes.c_char_p, ctypes.c_size_t, _E]),
    ("gs_api_case_run", ctypes.c_int, [_P, _S, ctypes.c_int, _E]),
    ("gs_study_key_unit", _S, [_S]),
]:
    f = getattr(lib, name)
    f.restype = res
    f.argtypes = args


def call(fn, *args):
    """Call a gransim function that reports through a gs_error (its last
    argument); raise GransimError with gransim's message on failure."""
    err = _Error()
    result = fn(*args, ctypes.byref(err))
    failed = (result is None) if fn.restype is _P else (result != 0)
    if failed:
        raise GransimError(err.msg.decode("utf-8", "replace") or "gransim failed without a message")
    return result


def text(s):
    return s.encode("utf-8")
