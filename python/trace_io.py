"""Reading rigidtouch trace CSV files (one row per haptic tick, SI units in column names).

Shared by the plot scripts; depends only on the standard library so that a missing matplotlib
can be reported before anything else fails.
"""

import csv
import sys

VECTORS = ("tool", "tool_v", "penalty_f", "impulsive_f", "device_f", "hand_f", "wall_n")


def read_trace(path):
    """Returns the trace as a dict of column name -> list of floats."""
    try:
        with open(path, newline="") as handle:
            reader = csv.reader(handle)
            header = next(reader, None)
            if header is None:
                raise SystemExit(f"error: trace file '{path}' is empty (no header row)")
            columns = {name.strip(): [] for name in header}
            names = [name.strip() for name in header]
            for line_number, row in enumerate(reader, start=2):
                if not row:
                    continue
                for name, value in zip(names, row):
                    try:
                        columns[name].append(float(value))
                    except ValueError:
                        raise SystemExit(
                            f"error: trace file '{path}' line {line_number}: column '{name}' "
                            f"value '{value}' is not a number")
    except OSError as error:
        raise SystemExit(f"error: cannot read trace file '{path}': {error.strerror}")
    required = ["time_s", "penalty_fx_N", "impulsive_fx_N", "device_fx_N", "wall_nx", "impulses",
                "tap", "tool_contacts"]
    missing = [name for name in required if name not in columns]
    if missing:
        raise SystemExit(f"error: trace file '{path}' misses columns: {', '.join(missing)}")
    return columns


def normal_component(columns, prefix, unit):
    """Per-row component of the vector column `prefix` along the row's wall normal."""
    x, y, z = (columns[f"{prefix}{axis}_{unit}"] for axis in "xyz")
    nx, ny, nz = columns["wall_nx"], columns["wall_ny"], columns["wall_nz"]
    return [a * d + b * e + c * f for a, b, c, d, e, f in zip(x, y, z, nx, ny, nz)]


def tap_rows(columns, tap):
    """Row indices of scripted tap `tap`; exits with a message if the trace has no such tap."""
    rows = [i for i, value in enumerate(columns["tap"]) if int(value) == tap]
    if not rows:
        taps = sorted({int(v) for v in columns["tap"] if v >= 0})
        raise SystemExit(f"error: the trace has no tap {tap}; taps present: {taps}")
    return rows


def import_pyplot():
    """Imports matplotlib with a non-interactive backend; exits with code 3 if it is missing."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as error:
        print(f"error: matplotlib is not installed ({error}); install python3-matplotlib",
              file=sys.stderr)
        sys.exit(3)
    return plt
