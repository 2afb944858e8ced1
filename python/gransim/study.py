"""Sweeps in this process: a case run once per variation of dotted keys,
a failed run recorded (status 'error' and its message) without stopping the
others, as `gransim sweep` does."""
import itertools
import os

import pandas as pd

from ._library import GransimError, lib


def sweep(case, values, out_dir, progress=False):
    """Run `case` for every combination of `values` ({dotted key: [v1, v2, ...]},
    the first key varying slowest) into out_dir/run-<i>.  Returns a DataFrame:
    run (from 1), status ('ok' or 'error'), the varied keys, the summary
    columns of every compartment at the final time (NAME_c<j>), error (the
    message of a failed run, whose outputs are nan) and path (its folder).
    attrs["units"] gives the SI unit of each key and output column, as
    `gransim sweep` writes them (with_units puts them in the names)."""
    keys = list(values)
    rows = []
    units = {"run": "1"}
    units.update({k: lib.gs_study_key_unit(k.encode("utf-8")).decode() for k in keys})
    for i, combo in enumerate(itertools.product(*(values[k] for k in keys)), start=1):
        row = {"run": i, "status": "ok"}
        row.update(dict(zip(keys, combo)))
        path = os.path.join(os.fspath(out_dir), "run-%d" % i)
        try:
            c = case.copy()
            for k, v in zip(keys, combo):
                c[k] = v
            result = c.run(path, progress=progress)
            final, unit = result.summary, result.summary_units
            final = final[final["time"] == final["time"].max()]
            for _, r in final.iterrows():
                for col in final.columns:
                    if col not in ("time", "compartment"):
                        name = "%s_c%d" % (col, int(r["compartment"]))
                        row[name] = r[col]
                        if col in unit:
                            units[name] = unit[col]
            row["error"] = ""
        except GransimError as e:
            row["status"] = "error"
            row["error"] = str(e)
        row["path"] = path
        rows.append(row)
    # a failed run has no output columns: nan there
    df = pd.DataFrame(rows)
    df.attrs["units"] = units
    return df


def with_units(df):
    """A copy of df whose column names carry their units from
    df.attrs["units"] ("d50_c1 [m]"), as gransim's CSV files name them."""
    units = df.attrs.get("units", {})
    return df.rename(columns={c: "%s [%s]" % (c, units[c]) for c in df.columns if c in units})
