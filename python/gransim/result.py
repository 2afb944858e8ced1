"""Results of a run, read back from its files (result.h5 with h5py; the
tables of a DEM run with pandas), as numpy arrays and pandas DataFrames."""
import math
import os

import h5py
import numpy as np
import pandas as pd
import yaml


class Result:
    """The files of one run in `path`.

    times      output times, shape (ntimes,)
    numbers    particles per compartment and cell, (ntimes, ncomp, n0[, n1[, n2]])
    summary    DataFrame: a row per output time and compartment, the columns
               of summary.csv (M0, M1, M2, d10, d50, d90, mean_<axis>, total_<axis>)
    moments    the summary's time, compartment, M0, M1 and M2
    grid       {axis: (edges, pivots)}
    psd(...)   the volume-weighted size distribution at one output time
    """

    def __init__(self, path, kind="sectional"):
        self.path = os.fspath(path)
        self.kind = kind

    @property
    def h5_path(self):
        return os.path.join(self.path, "result.h5")

    def _read(self, fn):
        with h5py.File(self.h5_path, "r") as f:
            return fn(f)

    @property
    def times(self):
        return self._read(lambda f: f["time"][...])

    @property
    def numbers(self):
        return self._read(lambda f: f["number"][...])

    @property
    def axis_names(self):
        def names(f):
            if "axis_names" in f["grid"].attrs:
                a = f["grid"].attrs["axis_names"]
                return (a.decode() if isinstance(a, bytes) else str(a)).split(",")
            return list(f["grid"].keys())
        return self._read(names)

    @property
    def grid(self):
        axes = self.axis_names
        return self._read(lambda f: {a: (f["grid"][a]["edges"][...], f["grid"][a]["pivots"][...]) for a in axes})

    @property
    def summary(self):
        def table(f):
            s = f["summary"]
            time = f["time"][...]
            ncomp = s["M0"].shape[1]
            cols = {"time": np.repeat(time, ncomp),
                    "compartment": np.tile(np.arange(1, ncomp + 1), len(time))}
            for name in s.keys():
                if name not in cols:
                    cols[name] = s[name][...].reshape(-1)
            return pd.DataFrame(cols)
        return self._read(table)

    @property
    def summary_units(self):
        """{column of summary: its SI unit}, from result.h5's `units` attributes."""
        def units(f):
            u = {"time": "s"}
            for name, ds in f["summary"].items():
                if "units" in ds.attrs:
                    a = ds.attrs["units"]
                    u[name] = a.decode() if isinstance(a, bytes) else str(a)
            return u
        return self._read(units)

    @property
    def moments(self):
        return self.summary[["time", "compartment", "M0", "M1", "M2"]]

    @property
    def case_text(self):
        return self._read(lambda f: _text(f["case"].attrs["text"]))

    def size_axes(self):
        """The axes summed into the granule volume (grid.size_axes, default all)."""
        case = yaml.safe_load(self.case_text) or {}
        return list(case.get("grid", {}).get("size_axes") or self.axis_names)

    def psd(self, time=None, compartment=1):
        """Volume-weighted size distribution at the output time nearest to
        `time` (the last one when None) in a compartment (from 1), over the
        volume-equivalent diameter d = (6 V / pi)^(1/3) [m], V the sum of the
        size axes' coordinates.  Columns: d_lo, d_hi, d (geometric middle),
        volume_fraction, Q3 (cumulative), q3 (dQ3/dd [1/m]), q3_lnd (dQ3/dln d).
        A one-axis grid keeps its cells; a grid of several axes is binned by d
        into as many geometric classes as its longest axis has cells."""
        t = self.times
        it = len(t) - 1 if time is None else int(np.argmin(np.abs(t - time)))
        n = self.numbers[it, compartment - 1]
        grid = self.grid
        axes = self.axis_names
        size = [a in self.size_axes() for a in axes]
        diameter = lambda v: np.cbrt(6.0 * np.asarray(v) / math.pi)
        if len(axes) == 1:
            edges, pivots = grid[axes[0]]
            d_edges = diameter(edges)
            vol = n * pivots
        else:
            mesh = np.meshgrid(*[grid[a][1] for a in axes], indexing="ij")
            v = sum(m for m, s in zip(mesh, size) if s)
            vol = (n * v).reshape(-1)
            d = diameter(v.reshape(-1))
            pos = d[(d > 0) & (vol > 0)]
            if pos.size == 0:
                raise ValueError("gransim: no particles at t = %g in compartment %d" % (t[it], compartment))
            bins = max(len(grid[a][1]) for a in axes)
            lo, hi = pos.min(), pos.max()
            d_edges = np.geomspace(lo / 1.0001, hi * 1.0001, bins + 1)
            vol, _ = np.histogram(d, bins=d_edges, weights=vol)
        total = vol.sum()
        frac = vol / total if total > 0 else np.full(len(vol), np.nan)
        lo, hi = d_edges[:-1], d_edges[1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            mid = np.sqrt(lo * hi)
            q3 = frac / (hi - lo)
            q3_lnd = frac / np.log(hi / lo)
        return pd.DataFrame({"d_lo": lo, "d_hi": hi, "d": mid, "volume_fraction": frac,
                             "Q3": np.cumsum(frac), "q3": q3, "q3_lnd": q3_lnd})

    def table(self, name):
        """A CSV table the run wrote (a DEM run's collisions.csv, ...), '#' lines skipped."""
        return pd.read_csv(os.path.join(self.path, name), comment="#")


def _text(a):
    return a.decode() if isinstance(a, bytes) else str(a)
