"""Tests of the Python package over libgransim (run by CTest as python_unit:
GRANSIM_LIBRARY names the built library, PYTHONPATH the package)."""
import math
import os
import re
import shutil
import tempfile
import unittest

import numpy as np

import gransim

SOURCE = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", ".."))


def aggregation_case(beta0=1.0, end=2.0):
    """Constant-kernel aggregation from an exponential distribution of N0 = 1:
    M0(t) = N0 / (1 + beta0 N0 t / 2), M1 constant."""
    return {
        "title": "constant kernel",
        "grid": {"axes": [{"name": "solid", "type": "geometric", "min": 1.0e-5, "ratio": 1.25,
                           "cells": 80, "zero_first": True}]},
        "initial": {"type": "exponential", "number": 1, "mean": 0.01},
        "mechanisms": [{"type": "aggregation", "kernel": {"type": "constant", "beta0": beta0}}],
        "output": {"end": end, "count": 5},
    }


class Cases(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="gransim-python-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_version(self):
        with open(os.path.join(SOURCE, "CMakeLists.txt")) as f:
            want = re.search(r"project\(gransim VERSION ([0-9.]+)", f.read()).group(1)
        self.assertEqual(gransim.__version__, want)
        self.assertTrue(gransim.version().startswith(want))

    def test_run_from_dict_against_closed_form(self):
        case = gransim.Case.from_dict(aggregation_case())
        self.assertEqual(case.kind, "sectional")
        self.assertIn("1 axes, 80 cells", case.check())
        r = case.run(os.path.join(self.dir, "out"))
        s = r.summary
        t = r.times
        np.testing.assert_allclose(t, [0, 0.5, 1, 1.5, 2])
        np.testing.assert_allclose(s["M0"], 1 / (1 + t / 2), rtol=2e-4)
        np.testing.assert_allclose(s["M1"], s["M1"][0], rtol=1e-9)
        self.assertEqual(list(r.moments.columns), ["time", "compartment", "M0", "M1", "M2"])
        # the numbers per cell add up to the summary's M0 and M1
        edges, pivots = r.grid["solid"]
        n = r.numbers
        self.assertEqual(n.shape, (5, 1, 80))
        np.testing.assert_allclose(n.sum(axis=(1, 2)), s["M0"], rtol=1e-12)
        np.testing.assert_allclose((n * pivots).sum(axis=(1, 2)), s["M1"], rtol=1e-12)
        # the size distribution: fractions of the volume, cumulative to 1
        psd = r.psd()
        self.assertAlmostEqual(psd["volume_fraction"].sum(), 1.0, places=12)
        self.assertAlmostEqual(psd["Q3"].iloc[-1], 1.0, places=12)
        np.testing.assert_allclose(psd["d_hi"], np.cbrt(6 * edges[1:] / math.pi))
        # d50 of the summary lies where Q3 crosses 0.5
        d50 = s["d50"].iloc[-1]
        row = psd[(psd["d_lo"] <= d50) & (psd["d_hi"] >= d50)].index[0]
        self.assertLessEqual(psd["Q3"].iloc[row - 1], 0.5 + 1e-9)
        self.assertGreaterEqual(psd["Q3"].iloc[row], 0.5 - 1e-9)

    def test_dotted_keys(self):
        case = gransim.Case.from_dict(aggregation_case())
        case["mechanisms.0.kernel.beta0"] = 2.0
        self.assertEqual(case["mechanisms.0.kernel.beta0"], 2.0)
        self.assertEqual(case.to_dict()["mechanisms"][0]["kernel"]["beta0"], 2.0)
        s = case.run(os.path.join(self.dir, "b")).summary
        self.assertAlmostEqual(s["M0"].iloc[-1], 1 / 3, delta=1e-4)
        # a key the case lacks is refused at once, with a suggestion
        with self.assertRaisesRegex(gransim.GransimError, r"no 'ned' in output.*did you mean 'end'"):
            case["output.ned"] = 3
        with self.assertRaises(TypeError):
            case["output.end"] = [1, 2]

    def test_errors_are_exceptions_and_leave_nothing(self):
        case = gransim.Case.from_dict(aggregation_case(), name="agg.yaml")
        case["output.end"] = -1
        out = os.path.join(self.dir, "bad")
        with self.assertRaisesRegex(gransim.GransimError, r"^agg\.yaml:\d+: output\.end = '-1': expected a number > 0$"):
            case.run(out)
        self.assertFalse(os.path.exists(os.path.join(out, "result.h5")))
        self.assertFalse(os.path.exists(os.path.join(out, ".result.h5.partial")))
        # the same case runs once the key is right again: nothing was left half-done
        case["output.end"] = 1
        self.assertAlmostEqual(case.run(out).summary["M0"].iloc[-1], 2 / 3, delta=1e-4)
        d = aggregation_case()
        d["mechanisms"][0]["kernal"] = d["mechanisms"][0].pop("kernel")
        with self.assertRaisesRegex(gransim.GransimError, r"unknown key 'kernal' .*did you mean 'kernel'"):
            gransim.Case.from_dict(d).check()
        with self.assertRaisesRegex(gransim.GransimError, "cannot open case file"):
            gransim.Case.load(os.path.join(self.dir, "none.yaml"))

    def test_file_cases_of_every_kind(self):
        for name, kind in [("high-shear-batch.yaml", "sectional"), ("twin-screw.yaml", "swa"),
                           ("dem-corimix.yaml", "dem"), ("corimix-coupled.yaml", "coupled")]:
            case = gransim.Case.load(os.path.join(SOURCE, "examples", name))
            self.assertEqual(case.kind, kind, name)
            self.assertTrue(case.check(), name)

    def test_swa(self):
        d = aggregation_case(beta0=1e-3)
        d["initial"]["number"] = 1000
        d["solver"] = {"method": "swa", "particles": 512, "runs": 4, "seed": 3}
        case = gransim.Case.from_dict(d)
        self.assertEqual(case.kind, "swa")
        r = case.run(os.path.join(self.dir, "swa"))
        s = r.summary
        self.assertIn("M0", s.columns)
        self.assertAlmostEqual(s["M0"].iloc[0], 1000, delta=1e-9)
        # M0 within 3 confidence half-widths (90 %) plus 1 % of the closed form 1000 / (1 + 1000 t 1e-3 / 2)
        with_ci = gransim.Result(r.path)._read(lambda f: f["summary_ci"]["M0"][...]).reshape(-1)
        want = 1000 / (1 + r.times / 2)
        self.assertTrue(np.all(np.abs(s["M0"] - want) <= 3 * with_ci + 0.01 * want))

    def test_sweep_keeps_going_after_a_failed_run(self):
        case = gransim.Case.from_dict(aggregation_case())
        df = gransim.sweep(case, {"mechanisms.0.kernel.beta0": [1.0, -1.0, 2.0]}, self.dir)
        self.assertEqual(list(df["status"]), ["ok", "error", "ok"])
        self.assertIn("expected a number >= 0", df["error"][1])
        self.assertTrue(math.isnan(df["M0_c1"][1]))
        np.testing.assert_allclose(df["M0_c1"][[0, 2]], [1 / 2, 1 / 3], atol=1e-4)
        # every column's unit, as gransim sweep writes them
        u = df.attrs["units"]
        self.assertEqual((u["M0_c1"], u["d50_c1"], u["M1_c1"], u["run"]), ("1", "m", "m^3", "1"))
        self.assertEqual(u["mechanisms.0.kernel.beta0"], "case")
        named = gransim.with_units(df)
        self.assertIn("d50_c1 [m]", named.columns)
        self.assertEqual([c for c in named.columns if "[" not in c], ["status", "error", "path"])


if __name__ == "__main__":
    unittest.main()
