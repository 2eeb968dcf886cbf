"""Measures the cohesive column collapse (cases/collapse_cohesive.json) from its VTK files:
at each snapshot, the accumulated plastic deviatoric strain (maximum, mean, share of the
soil above 0.1 and 1), the runout and the height at the wall (free surface of the points'
squares, as the runout monitor), and the failure surface — the inner edge of the zone whose strain exceeds
BAND (0.3), located in the *reference* configuration (X = x − u), where it is a
line: its angle to the horizontal (Coulomb's active wedge: 45° + φ/2 = 57.5°) and where it
meets the base and the top surface, and the width of the sheared zone at mid-height.

    cargo build --release
    target/release/loam run cases/collapse_cohesive.json --out out/collapse_cohesive
    .venv/bin/python scripts/cohesive_collapse.py out/collapse_cohesive [--png DIR]

With --png, each snapshot is also drawn (numpy only): the points' squares in their current
position coloured by κ (blue 0 → red ≥ 1, the jet map), 100 pixels per metre.
"""
import math
import pathlib
import struct
import sys
import xml.etree.ElementTree as ET
import zlib

import meshio
import numpy as np

BAND = 0.3  # accumulated plastic deviatoric strain of a shear band point
H, W = 3.0, 4.0  # column height and width (m)


def surface(x, y, s):
    """Free surface (top envelope of the points' squares): runout from the wall at x = 0
    (surface at least 5 cm above the base, gaps up to half a point joined) and height at
    the wall."""
    high = y + 0.5 * s >= 0.05
    spans = sorted(zip(x[high] - 0.5 * s[high], x[high] + 0.5 * s[high], s[high]))
    reach = 0.0
    for left, right, size in spans:
        if left > reach + 0.5 * size:
            break
        reach = max(reach, right)
    wall = np.abs(x) <= 0.6 * s
    return reach, float(np.max(y[wall] + 0.5 * s[wall])) if wall.any() else 0.0


def failure_surface(X, Y, kappa):
    """Inner (wall-side) edge of the sheared zone kappa >= BAND in the reference
    configuration: the smallest X of the band points in each row of points (0.1 m bins of
    Y), fitted by a line X = a + b Y. Returns (angle to the horizontal in degrees, X at the
    base, X at the top, width of the sheared zone at mid-height) or None."""
    band = kappa >= BAND
    rows = []
    for lo in np.arange(0.0, H, 0.1):
        sel = band & (Y >= lo) & (Y < lo + 0.1)
        if sel.any():
            rows.append((lo + 0.05, X[sel].min(), X[sel].max()))
    if len(rows) < 5:
        return None
    y, xmin, xmax = map(np.array, zip(*rows))
    b, a = np.polyfit(y, xmin, 1)
    angle = math.degrees(math.atan2(1.0, -b))
    mid = np.argmin(np.abs(y - H / 2))
    return angle, a, a + b * H, xmax[mid] - xmin[mid]


def write_png(path, rgb):
    """An 8-bit RGB PNG from an (height, width, 3) uint8 array."""
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[i].tobytes() for i in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    pathlib.Path(path).write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    )


def draw(path, x, y, s, kappa, size=(7.0, 3.2), ppm=100):
    """The points' squares coloured by kappa (jet, clipped at 1) on white."""
    w, h = int(size[0] * ppm), int(size[1] * ppm)
    img = np.full((h, w, 3), 255, np.uint8)
    v = np.clip(kappa, 0.0, 1.0)
    rgb = np.stack([np.clip(1.5 - np.abs(4 * v - k), 0, 1) for k in (3, 2, 1)], -1)
    rgb = (255 * rgb).astype(np.uint8)
    for k in range(len(x)):
        r = max(1, int(0.5 * s[k] * ppm))
        i, j = int(x[k] * ppm), h - 1 - int(y[k] * ppm)
        img[max(0, j - r) : max(0, j + r), max(0, i - r) : max(0, i + r)] = rgb[k]
    write_png(path, img)


def main(out, png=None):
    out = pathlib.Path(out)
    series = ET.parse(out / "soil.pvd").getroot().findall(".//DataSet")
    print("| t (s) | max κ | mean κ | soil with κ > 0.1 / > 1 | runout (m) | height at wall (m) | failure surface (reference configuration): angle, X at the base → X at the top | width of the zone κ ≥ 0.3 at mid-height |")
    print("|---|---|---|---|---|---|---|---|")
    for ds in series:
        t = float(ds.get("timestep"))
        if t == 0.0:
            continue
        m = meshio.read(out / ds.get("file"))
        p, u = m.points, m.point_data["displacement"]
        kappa = m.point_data["accumulated_plastic_deviatoric_strain"].ravel()
        vol = m.point_data["volume"].ravel()
        s = np.sqrt(vol)
        reach, wall = surface(p[:, 0], p[:, 1], s)
        X, Y = p[:, 0] - u[:, 0], p[:, 1] - u[:, 1]
        if png:
            pathlib.Path(png).mkdir(parents=True, exist_ok=True)
            draw(pathlib.Path(png) / f"cohesive_collapse_{t:.2f}s.png", p[:, 0], p[:, 1], s, kappa)
        fs = failure_surface(X, Y, kappa)
        desc = f"{fs[0]:.1f}°, {fs[1]:.2f} → {fs[2]:.2f} m | {fs[3]:.2f} m" if fs else "none | –"
        print(
            f"| {t:.2f} | {kappa.max():.2f} | {kappa.mean():.3f} | {100 * np.mean(kappa > 0.1):.0f} % / "
            f"{100 * np.mean(kappa > 1.0):.0f} % | {reach:.2f} | {wall:.2f} | {desc} |"
        )


if __name__ == "__main__":
    args = sys.argv[1:]
    png = None
    if "--png" in args:
        k = args.index("--png")
        png = args[k + 1]
        del args[k : k + 2]
    main(args[0] if args else "out/collapse_cohesive", png)
