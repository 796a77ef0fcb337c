"""Shared helpers of the Python binding tests: run the CLI built beside the module on the same data.

Numbers go to CSV in Python's shortest round-trip form (repr), which the CLI parses back to the
same doubles, and the CLI writes shortest round-trip numbers too: comparing the parsed columns with
== is comparing the bits.
"""
import csv
import math
import os
import subprocess

import numpy as np
import pytest


def cli_path():
    path = os.environ.get("ERRFIELD_CLI")
    if not path or not os.path.exists(path):
        pytest.fail("ERRFIELD_CLI must name the built `errfield` executable (ctest sets it)")
    return path


def run_cli(*args):
    """Runs `errfield args...`; returns stdout, fails the test with stderr on a non-zero status."""
    r = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.fail(f"errfield {' '.join(map(str, args))} exited {r.returncode}: {r.stderr}")
    return r.stdout


def run_cli_status(*args):
    r = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def write_csv(path, columns):
    """columns: dict name -> 1-D array; numbers written with repr (shortest round trip), NaN as an
    empty cell (the CLI's "no value")."""
    names = list(columns)
    n = len(columns[names[0]])
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for i in range(n):
            w.writerow(["" if math.isnan(float(columns[c][i])) else repr(float(columns[c][i])) for c in names])
    return path


def read_csv(path):
    """dict name -> list of cells (strings)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {h: [r[k] for r in body] for k, h in enumerate(header)}


def numbers(cells):
    """CSV cells as float64; an empty cell is NaN (the CLI's empty bin / no prediction)."""
    return np.array([float(c) if c != "" else math.nan for c in cells], dtype=np.float64)


def same(a, b):
    """Bitwise-equal float arrays, NaN equal to NaN."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
