#!/usr/bin/env python3
"""Generates the shipped terrain data files in terrains/.

    python3 scripts/gen_terrains.py [output_dir]

Writes bumpy.asc, bumpy_small.pgm, test_track.csv, rough.asc and
rough_unmapped.asc (default output_dir:
terrains/ next to this script's folder). Standard library only; no random
numbers, so every run writes byte-identical files. terrains/README.md
documents the shapes; keep it in step with the constants below.
"""

import math
import os
import struct
import sys

# ---------------------------------------------------------------------------
# Bumpy field: a sum of fixed sinusoids, wavelengths 2.9 m .. 7.3 m.

BUMPY_SIZE = 20.0  # m, square, centred on the origin
BUMPY_CELL = 0.25  # m

# (amplitude [m], wavelength [m], direction [deg], phase [rad]) plane waves...
BUMPY_WAVES = [
    (0.022, 7.3, 20.0, 0.4),
    (0.018, 5.1, 115.0, 1.7),
    (0.014, 3.7, 62.0, 2.9),
    (0.010, 2.9, 160.0, 0.8),
]
# ...times one egg-crate term: amplitude * sin(2 pi x / lx + px) * sin(2 pi y / ly + py).
BUMPY_CRATE = (0.016, 4.3, 3.9, 0.6, 1.3)


def bumpy_height(x, y):
    h = 0.0
    for amplitude, wavelength, direction, phase in BUMPY_WAVES:
        a = math.radians(direction)
        s = x * math.cos(a) + y * math.sin(a)
        h += amplitude * math.sin(2 * math.pi * s / wavelength + phase)
    amplitude, lx, ly, px, py = BUMPY_CRATE
    h += amplitude * math.sin(2 * math.pi * x / lx + px) * math.sin(2 * math.pi * y / ly + py)
    return h


def fmt(value, decimals):
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.0000"


def write_bumpy_asc(path):
    n = int(round(BUMPY_SIZE / BUMPY_CELL)) + 1  # samples are grid points
    half = BUMPY_SIZE / 2
    lines = [
        f"ncols {n}",
        f"nrows {n}",
        f"xllcenter {fmt(-half, 2)}",
        f"yllcenter {fmt(-half, 2)}",
        f"cellsize {BUMPY_CELL}",
        "NODATA_value -9999",
    ]
    # First row is north (max y).
    for r in range(n):
        y = half - r * BUMPY_CELL
        lines.append(" ".join(fmt(bumpy_height(-half + c * BUMPY_CELL, y), 4) for c in range(n)))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


# The centre 8 m x 8 m of the bumpy field as a 16-bit binary PGM: grey 0 is
# -0.08 m, grey 65535 is +0.08 m.
SMALL_SAMPLES = 33
SMALL_SIZE = 8.0
SMALL_MIN, SMALL_MAX = -0.08, 0.08


def write_bumpy_small_pgm(path):
    n = SMALL_SAMPLES
    step = SMALL_SIZE / (n - 1)
    half = SMALL_SIZE / 2
    data = bytearray()
    for r in range(n):  # first row is north
        y = half - r * step
        for c in range(n):
            h = bumpy_height(-half + c * step, y)
            grey = round((h - SMALL_MIN) / (SMALL_MAX - SMALL_MIN) * 65535)
            data += struct.pack(">H", min(65535, max(0, grey)))  # big-endian
    header = f"P5\n# bumpy_small: centre 8 m x 8 m of bumpy.asc, grey 0 = {SMALL_MIN} m, 65535 = {SMALL_MAX} m\n"
    header += f"{n} {n}\n65535\n"
    with open(path, "wb") as f:
        f.write(header.encode("ascii") + bytes(data))


# ---------------------------------------------------------------------------
# Test track profile: run-in, snowy undulation with four bumps, run-out.

TRACK_LENGTH = 22.0  # m
TRACK_STEP = 0.05  # m
TRACK_FLAT = 1.0  # m of flat track at each end
TRACK_BEHIND = 2.0  # m of level snow behind the start (distances from -2 m)
# (start [m], length [m], height [m]) cosine bumps on top of the undulation.
# Each is pi * height / 0.2 long, so its steepest slope is 0.2 (11 deg): a
# four-wheel-drive robot climbs that on packed snow (mu 0.3 > 0.2 plus the
# undulation's 0.03).
TRACK_BUMPS = [
    (2.5, 1.6, 0.10),
    (6.0, 2.4, 0.15),
    (10.0, 3.2, 0.20),
    (14.5, 4.8, 0.30),
]
# (amplitude [m], period [m]): u(d) = sum amplitude * (1 - cos(2 pi (d - 1) / period)).
# Both periods divide the 20 m between the flat ends, so the undulation
# starts and ends at zero height with zero slope.
TRACK_UNDULATION = [(0.015, 5.0), (0.010, 20.0 / 3.0)]


def track_height(d):
    if d <= TRACK_FLAT or d >= TRACK_LENGTH - TRACK_FLAT:
        return 0.0
    s = d - TRACK_FLAT
    h = sum(a * (1 - math.cos(2 * math.pi * s / period)) for a, period in TRACK_UNDULATION)
    for start, length, height in TRACK_BUMPS:
        if start <= d <= start + length:
            h += height / 2 * (1 - math.cos(2 * math.pi * (d - start) / length))
    return h


def write_test_track_csv(path):
    n = int(round((TRACK_LENGTH + TRACK_BEHIND) / TRACK_STEP)) + 1
    lines = ["distance_m,height_m"]
    for k in range(n):
        d = k * TRACK_STEP - TRACK_BEHIND
        lines.append(f"{d:.2f},{fmt(track_height(d), 4)}")
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


# ---------------------------------------------------------------------------
# Rough field: the bumpy field's waves plus shorter ones (0.8 m .. 1.7 m),
# 20 m x 20 m at 0.125 m. rough_unmapped.asc is the same ground with what a
# map lacks (issue 61): a ridge and a hollow across the whole field, for a
# stand-in whose ground is not the console's.

ROUGH_SIZE = 20.0  # m
ROUGH_CELL = 0.125  # m
ROUGH_WAVES = [
    (0.008, 1.7, 35.0, 0.3),
    (0.006, 1.1, 100.0, 2.2),
    (0.005, 0.8, 145.0, 1.1),
]
# (centre x [m], height [m] (negative: a hollow), width [m]) cosine ridges
# across the field (all y), in the unmapped ground only.
ROUGH_UNMAPPED = [
    (-2.0, 0.09, 0.6),
    (2.0, -0.07, 0.8),
]


def rough_height(x, y, unmapped=False):
    h = bumpy_height(x, y)
    for amplitude, wavelength, direction, phase in ROUGH_WAVES:
        a = math.radians(direction)
        s = x * math.cos(a) + y * math.sin(a)
        h += amplitude * math.sin(2 * math.pi * s / wavelength + phase)
    if unmapped:
        for centre, height, width in ROUGH_UNMAPPED:
            if abs(x - centre) < width / 2:
                h += height / 2 * (1 + math.cos(2 * math.pi * (x - centre) / width))
    return h


def write_rough_asc(path, unmapped):
    n = int(round(ROUGH_SIZE / ROUGH_CELL)) + 1
    half = ROUGH_SIZE / 2
    lines = [
        f"ncols {n}",
        f"nrows {n}",
        f"xllcenter {fmt(-half, 2)}",
        f"yllcenter {fmt(-half, 2)}",
        f"cellsize {ROUGH_CELL}",
        "NODATA_value -9999",
    ]
    for r in range(n):
        y = half - r * ROUGH_CELL
        lines.append(" ".join(fmt(rough_height(-half + c * ROUGH_CELL, y, unmapped), 4) for c in range(n)))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "terrains")
    os.makedirs(out, exist_ok=True)
    write_bumpy_asc(os.path.join(out, "bumpy.asc"))
    write_bumpy_small_pgm(os.path.join(out, "bumpy_small.pgm"))
    write_test_track_csv(os.path.join(out, "test_track.csv"))
    write_rough_asc(os.path.join(out, "rough.asc"), unmapped=False)
    write_rough_asc(os.path.join(out, "rough_unmapped.asc"), unmapped=True)


if __name__ == "__main__":
    main()
