#!/usr/bin/python3
"""Units and attribute types of the result files, as pandas and h5py see them:
summary.csv reads with pd.read_csv(f) and no options, every column numeric and
named with its SI unit ("d50 [m]"); every dataset of result.h5 carries `units`
and `dimensions` (as many names as it has axes), the summary datasets the units
of summary.csv's header; and an attribute that both solvers write has the same
HDF5 type in both (64-bit integers, fixed-length UTF-8 strings).
Usage: result_units.py SECTIONAL_DIR STOCHASTIC_DIR"""
import re
import sys

import h5py
import pandas as pd


def fail(msg):
    sys.exit("FAIL (result_units.py): " + msg)


def attr_types(f):
    """name -> (type class, size or cset) of every attribute, by object path."""
    out = {}

    def visit(path, obj):
        for k in obj.attrs:
            t = obj.attrs.get_id(k).get_type()
            cset = t.get_cset() if t.get_class() == h5py.h5t.STRING else None
            out[(path if path else "/", k)] = (t.get_class(), None if cset is not None else t.get_size(),
                                              cset, t.is_variable_str() if cset is not None else None)
    visit("", f)
    f.visititems(visit)
    return out


types = {}
for d in sys.argv[1:3]:
    df = pd.read_csv(d + "/summary.csv")
    units = {}
    for c in df.columns:
        m = re.fullmatch(r"(\S+) \[(\S+)\]", c)
        if not m and c != "compartment":
            fail(f"{d}/summary.csv: column '{c}' has no unit")
        if m:
            units[m.group(1)] = m.group(2)
        if df[c].dtype.kind not in "fi":
            fail(f"{d}/summary.csv: column '{c}' is not numeric ({df[c].dtype})")
    if units.get("d50") != "m" or units.get("time") != "s" or units.get("M0") != "1":
        fail(f"{d}/summary.csv: units {units}")
    with h5py.File(d + "/result.h5", "r") as f:
        n = 0

        def check(path, obj):
            global n
            if not isinstance(obj, h5py.Dataset):
                return
            n += 1
            u, dims = obj.attrs.get("units"), obj.attrs.get("dimensions")
            if u is None or dims is None:
                fail(f"{d}/result.h5: {path} lacks units or dimensions")
            u = u.decode() if isinstance(u, bytes) else u
            dims = dims.decode() if isinstance(dims, bytes) else dims
            if len(dims.split(",")) != obj.ndim:
                fail(f"{d}/result.h5: {path} has {obj.ndim} axes, dimensions '{dims}'")
            col = path.split("/")[-1]
            if path.startswith(("summary/", "summary_ci/")) and col != "compartment" and units.get(col) != u:
                fail(f"{d}/result.h5: {path} in {u}, summary.csv says {units.get(col)}")
        f.visititems(check)
        if n < 10:
            fail(f"{d}/result.h5: only {n} datasets")
        types[d] = attr_types(f)
        if f.attrs["ntimes"].dtype != "int64" or f["grid"].attrs["ncomp"].dtype != "int64":
            fail(f"{d}/result.h5: counts are not 64-bit integers")
        if not f["grid"].attrs["axis_names"]:
            fail(f"{d}/result.h5: no axis_names")
a, b = (types[d] for d in sys.argv[1:3])
shared = {k for k in a if k in b and k[0] in ("/", "grid", "case")}
diff = {k: (a[k], b[k]) for k in shared if a[k][:2] != b[k][:2] or a[k][2:] != b[k][2:]}
if len(shared) < 8 or diff:
    fail(f"{len(shared)} attributes in both files; types that differ: {diff}")
print(f"result_units.py: {len(shared)} attributes of the same type in both solvers' files; units on every dataset")
