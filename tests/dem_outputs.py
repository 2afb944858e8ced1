#!/usr/bin/python3
"""The files of `gransim dem` as pandas and VTK read them, with no options:
every CSV starts with its header (no `#` lines) and has a JSON sidecar whose
units name its columns; every .pvd series lists frames at the times of
output.vtk_every, each .vtp frame reads with VTK's own XML reader, carries its
time, holds as many particles as timeseries.csv reports at that time (with
radii of the case's classes) and the walls hold their meshes' triangles.
Usage: dem_outputs.py OUT_DIR VTK_EVERY RADII(comma) WALL=TRIANGLES..."""
import glob
import json
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import vtk
from vtk.util.numpy_support import vtk_to_numpy

out, every = sys.argv[1], float(sys.argv[2])
radii = [float(r) for r in sys.argv[3].split(",")]
walls = dict((w.split("=")[0], int(w.split("=")[1])) for w in sys.argv[4:])


def fail(msg):
    sys.exit("FAIL (dem_outputs.py): " + msg)


matrix = ("collision_kernel.csv", "impact_table")  # tables of the PBM readers
csvs = sorted(glob.glob(os.path.join(out, "*.csv")))
if len(csvs) < 10:
    fail(f"only {len(csvs)} CSV files in {out}")
for f in csvs:
    with open(f) as fp:
        first = fp.readline()
    if first.startswith("#"):
        fail(f"{f} starts with a comment line")
    df = pd.read_csv(f)
    base = os.path.basename(f)
    if any(str(c).startswith("#") or str(c).startswith("Unnamed") for c in df.columns):
        fail(f"{f}: pandas finds columns {list(df.columns)}")
    meta = json.load(open(f[:-4] + ".json"))
    if meta["file"] != base or not meta["description"]:
        fail(f"{f}: sidecar {meta}")
    if base.startswith(matrix):
        if df.columns[0] != "edges" or not all(np.isfinite(df.columns[1:].astype(float))):
            fail(f"{f}: matrix table header {list(df.columns)}")
        continue
    unknown = set(meta["units"]) - set(df.columns)
    if unknown:
        fail(f"{f}: units for columns it lacks: {unknown}")
    numeric = [c for c in df.columns if c not in ("name", "name_i", "name_j", "wall")]
    if base != "residence_class.csv" and len(df) and not all(df[c].dtype.kind in "fi" for c in numeric):
        fail(f"{f}: non-numeric columns {df.dtypes.to_dict()}")
ts = pd.read_csv(os.path.join(out, "timeseries.csv"))
if not {"time", "particles", "holdup_mass"} <= set(ts.columns) or len(ts) < 3:
    fail(f"timeseries.csv: {list(ts.columns)}, {len(ts)} rows")
if json.load(open(os.path.join(out, "timeseries.json")))["units"]["holdup_mass"] != "kg":
    fail("timeseries.json: holdup_mass not in kg")

vdir = os.path.join(out, "vtk")
nseries = matched = 0
for name, ntri in [("particles", None)] + list(walls.items()):
    pvd = os.path.join(vdir, name + ".pvd")
    root = ET.parse(pvd).getroot()
    if root.get("type") != "Collection":
        fail(f"{pvd}: not a Collection")
    sets = root.findall("./Collection/DataSet")
    times = np.array([float(s.get("timestep")) for s in sets])
    if len(sets) < 2 or not np.allclose(times, every * np.arange(len(sets)), atol=1e-9):
        fail(f"{pvd}: times {times}, expected every {every} s")
    for s, t in zip(sets, times):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(os.path.join(vdir, s.get("file")))
        r.Update()
        pd_ = r.GetOutput()
        if r.GetErrorCode() or pd_.GetNumberOfPoints() == 0:
            fail(f"{s.get('file')}: VTK read {pd_.GetNumberOfPoints()} points")
        tv = vtk_to_numpy(pd_.GetFieldData().GetArray("TimeValue"))[0]
        if abs(tv - t) > 1e-12:
            fail(f"{s.get('file')}: TimeValue {tv}, the series says {t}")
        if ntri is None:
            n = pd_.GetNumberOfPoints()
            want = ts.loc[(ts.time - t).abs() < 1e-9, "particles"]  # where a row falls on the frame
            if len(want) > 1 or (len(want) and int(want.iloc[0]) != n) or pd_.GetNumberOfVerts() != n:
                fail(f"{s.get('file')}: {n} particles, timeseries.csv: {list(want)} at t = {t}")
            matched += len(want)
            pt = pd_.GetPointData()
            rad = vtk_to_numpy(pt.GetArray("radius"))
            cls = vtk_to_numpy(pt.GetArray("class"))
            vel = vtk_to_numpy(pt.GetArray("velocity"))
            ids = vtk_to_numpy(pt.GetArray("id"))
            if vel.shape != (n, 3) or len(set(ids)) != n:
                fail(f"{s.get('file')}: velocity {vel.shape}, {len(set(ids))} distinct ids of {n}")
            if not np.allclose(rad, np.array(radii)[cls - 1], rtol=1e-12):
                fail(f"{s.get('file')}: radii do not match the classes")
        elif pd_.GetNumberOfPolys() != ntri or pd_.GetNumberOfPoints() != 3 * ntri:
            fail(f"{s.get('file')}: {pd_.GetNumberOfPolys()} triangles, the mesh has {ntri}")
    nseries += 1
if matched < 2:
    fail(f"only {matched} particle frames fall on a timeseries.csv row")
print(f"dem_outputs.py: {len(csvs)} tables and {nseries} VTK series read as they are")
