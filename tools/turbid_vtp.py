"""Reading turbid's particle output with numpy only: the VTK XML PolyData frames
(particles_NNNN.vtp: appended raw data, zlib, UInt64 headers) and the particles.pvd collection
that gives each frame its time. Shared by tools/plot_snapshot, tools/plot_landslide and
tools/validation_metrics.py."""
import pathlib
import re
import struct
import sys
import zlib

import numpy as np

TYPES = {"Float32": np.float32, "Float64": np.float64, "UInt8": np.uint8, "Int32": np.int32,
         "UInt32": np.uint32, "Int64": np.int64, "UInt64": np.uint64}


def read_vtp(path):
    """{array name: numpy array} of one frame; positions are under 'Points' (n x 3), and
    'units' maps field names to their units ({} when the frame has none)."""
    raw = pathlib.Path(path).read_bytes()
    marker = raw.index(b"<AppendedData")
    start = raw.index(b"_", marker) + 1
    header = raw[:marker].decode("utf-8", "replace")
    if 'header_type="UInt64"' not in header or "vtkZLibDataCompressor" not in header:
        sys.exit(f"{path}: expected zlib-compressed appended data with UInt64 headers (turbid's format)")
    arrays = {}

    def block(attrs):
        pos = start + int(attrs["offset"])
        nblocks = struct.unpack_from("<Q", raw, pos)[0]
        sizes = struct.unpack_from(f"<{3 + nblocks}Q", raw, pos)
        data, p = b"", pos + 8 * (3 + nblocks)
        for c in sizes[3:]:
            data += zlib.decompress(raw[p:p + c])
            p += c
        return data

    # The field data's string array "units" ("pressure [Pa]", ...): arrays["units"] = {name: unit}.
    for m in re.finditer(r'<Array ([^>]*?)/?>', header):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        if attrs.get("type") == "String" and attrs.get("Name") == "units" and attrs.get("format") == "appended":
            units = {}
            for entry in block(attrs).split(b"\0"):
                um = re.match(r"(.*) \[(.*)\]$", entry.decode("utf-8", "replace"))
                if um:
                    units[um.group(1)] = um.group(2)
            arrays["units"] = units
    for m in re.finditer(r'<DataArray ([^>]*?)/?>', header):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        if attrs.get("format") != "appended" or attrs.get("type") not in TYPES:
            continue
        data = block(attrs)
        values = np.frombuffer(data, dtype=TYPES[attrs["type"]])
        ncomp = int(attrs.get("NumberOfComponents", "1"))
        name = attrs.get("Name", "points")
        arrays.setdefault(name, values.reshape(-1, ncomp) if ncomp > 1 else values)
    return arrays


def frames(run_dir):
    """[(time [s], path)] of a run's frames in time order, from particles.pvd."""
    run = pathlib.Path(run_dir)
    pvd = run / "particles.pvd"
    if not pvd.exists():
        sys.exit(f"{run}: no particles.pvd (was the scene run with output.vtk: true?)")
    out = []
    for m in re.finditer(r'<DataSet [^>]*timestep="([^"]+)"[^>]*file="([^"]+)"', pvd.read_text()):
        out.append((float(m.group(1)), run / m.group(2)))
    return sorted(out)


def frame_at(run_dir, t):
    """(time, path) of the frame whose time is nearest to t [s]."""
    return min(frames(run_dir), key=lambda f: abs(f[0] - t))
