"""Sweeps in this process: a case run once per variation of dotted keys,
a failed run recorded (status 'error' and its message) without stopping the
others, as `gransim sweep` does."""
import itertools
import os

import pandas as pd

from ._library import GransimError


def sweep(case, values, out_dir, progress=False):
    """Run `case` for every combination of `values` ({dotted key: [v1, v2, ...]},
    the first key varying slowest) into out_dir/run-<i>.  Returns a DataFrame:
    run (from 1), status ('ok' or 'error'), the varied keys, the summary
    columns of every compartment at the final time (NAME_c<j>), error (the
    message of a failed run, whose outputs are nan) and path (its folder)."""
    keys = list(values)
    rows = []
    for i, combo in enumerate(itertools.product(*(values[k] for k in keys)), start=1):
        row = {"run": i, "status": "ok"}
        row.update(dict(zip(keys, combo)))
        path = os.path.join(os.fspath(out_dir), "run-%d" % i)
        try:
            c = case.copy()
            for k, v in zip(keys, combo):
                c[k] = v
            final = c.run(path, progress=progress).summary
            final = final[final["time"] == final["time"].max()]
            for _, r in final.iterrows():
                for col in final.columns:
                    if col not in ("time", "compartment"):
                        row["%s_c%d" % (col, int(r["compartment"]))] = r[col]
            row["error"] = ""
        except GransimError as e:
            row["status"] = "error"
            row["error"] = str(e)
        row["path"] = path
        rows.append(row)
    # a failed run has no output columns: nan there
    return pd.DataFrame(rows)
