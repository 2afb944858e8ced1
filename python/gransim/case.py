"""Cases: loaded from a file or built from a dict, keys changed by dotted
paths as in `gransim sweep`, checked and run in this process."""
import copy
import os
import tempfile

import yaml

from . import _library as L
from .result import Result


def _yaml_scalar(value):
    """The text a case file would hold for a Python value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (int, str)):
        return str(value)
    if hasattr(value, "item"):  # numpy scalars
        return _yaml_scalar(value.item())
    raise TypeError("gransim: a key takes a number, a string or a bool, not %r" % (value,))


class Case:
    """A gransim case of any kind (sectional, swa, DEM, coupled).

    case = Case.load("examples/high-shear-batch.yaml")
    case["mechanisms.0.kernel.beta0"] = 2e-3     # the key must exist
    result = case.run("out")                      # a Result
    """

    def __init__(self, handle, text, name, path):
        self._handle = handle
        self._text = text
        self._name = name
        self._path = path
        self._set = []  # (dotted, text) in order

    @classmethod
    def load(cls, path):
        """A case file; relative paths in it resolve against its folder."""
        handle = L.call(L.lib.gs_api_case_load, L.text(path))
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except OSError:
            L.lib.gs_api_case_free(handle)
            raise
        return cls(handle, text, path, path)

    @classmethod
    def from_dict(cls, d, name="<dict>"):
        """A case given as a dict of the case file's sections; relative paths
        in it resolve against the current folder.  Messages name `name` and
        the line of the key in the YAML text written from the dict
        (Case.text shows it)."""
        text = yaml.safe_dump(d, sort_keys=False, default_flow_style=None)
        return cls.from_text(text, name)

    @classmethod
    def from_text(cls, text, name="<text>"):
        handle = L.call(L.lib.gs_api_case_from_text, L.text(text), L.text(name))
        return cls(handle, text, name, None)

    def __del__(self):
        handle, self._handle = getattr(self, "_handle", None), None
        if handle and L is not None and L.lib is not None:  # not at interpreter exit
            L.lib.gs_api_case_free(handle)

    def copy(self):
        """An independent copy with the same keys set."""
        new = Case.load(self._path) if self._path else Case.from_text(self._text, self._name)
        for key, value in self._set:
            new[key] = value
        return new

    @property
    def text(self):
        """The case file's text as loaded (keys set since are not in it)."""
        return self._text

    @property
    def name(self):
        return self._name

    @property
    def kind(self):
        """'sectional', 'swa', 'dem' or 'coupled'."""
        return L.lib.gs_api_kind_name(L.lib.gs_api_case_kind(self._handle)).decode()

    def __setitem__(self, dotted, value):
        """Set the scalar at a dotted path ('output.end', 'mechanisms.0.kernel.beta0');
        the path must exist in the case.  The value is validated by check() and run()."""
        value_text = _yaml_scalar(value)
        L.call(L.lib.gs_api_case_set, self._handle, L.text(dotted), L.text(value_text))
        self._set.append((dotted, value_text))

    def set(self, values):
        """Set several dotted keys from a dict."""
        for key, value in values.items():
            self[key] = value
        return self

    def __getitem__(self, dotted):
        node = self.to_dict()
        for part in dotted.split("."):
            node = node[int(part)] if isinstance(node, list) else node[part]
        return node

    def to_dict(self):
        """The case as a dict, with the keys set since it was loaded."""
        d = yaml.safe_load(self._text) or {}
        for dotted, value_text in self._set:
            parts = dotted.split(".")
            node = d
            for part in parts[:-1]:
                node = node[int(part)] if isinstance(node, list) else node[part]
            last = int(parts[-1]) if isinstance(node, list) else parts[-1]
            node[last] = yaml.safe_load(value_text)
        return copy.deepcopy(d)

    def check(self):
        """Validate the case as a run would; returns gransim's one-line
        description, raises GransimError with its message otherwise."""
        buf = L.ctypes.create_string_buffer(1024)
        L.call(L.lib.gs_api_case_check, self._handle, buf, len(buf))
        return buf.value.decode()

    def run(self, out_dir=None, progress=False):
        """Run the case in this process into out_dir (a new temporary folder
        when None) and return its Result.  A failed run raises GransimError
        and leaves no result files."""
        if out_dir is None:
            out_dir = tempfile.mkdtemp(prefix="gransim-")
        out_dir = os.fspath(out_dir)
        L.call(L.lib.gs_api_case_run, self._handle, L.text(out_dir), 1 if progress else 0)
        return Result(out_dir, self.kind)
