#!/usr/bin/env python3
"""atmo's annual skies against the empirical skies daylighting tools use, hour by hour
(docs/daylighting.md, "Against the Perez and CIE skies"):

  scripts/daylight_validation.py OUT_DIR EPW

reads a finished `atmo annual` run (OUT_DIR/hours.csv and sky.mtx, Tregenza patches) of the weather
file EPW and, for its clear hours, compares each sky patch's luminance with

- the Perez all-weather sky (Perez, Seals and Michalsky 1993, "All-weather model for sky luminance
  distribution - preliminary configuration and validation", Solar Energy 50(3) 235-245, with the
  erratum in 51(5) 423), driven by the same hour's direct-normal and diffuse-horizontal irradiance
  as Radiance's gendaylit drives it: sky clearness epsilon and brightness Delta, the coefficients
  of its clearness bin (PEREZ_COEFFICIENTS below, the paper's Table 1 as gendaylit.c carries it),
  the bin-1 forms of c and d, and Delta >= 0.2 for 1.065 < epsilon < 2.8 (gendaylit's adjustment);
- the CIE standard clear sky of low turbidity (CIE S 011/E:2003, type 12).

Both empirical skies are scaled to the hour's diffuse horizontal illuminance (as gendaylit scales
Perez), so the comparison is of the distribution only. The sun's patch is left out (the matrix adds
the sun's direct light to it). Patches are grouped: near the sun (centre within 20 degrees), the
horizon row (altitude 0-12 degrees, away from the sun) and the rest. Prints markdown tables of
atmo / model per group (median and 10-90 % range over the hours' patches), by solar elevation.
"""
import csv
import math
import os
import sys

import numpy as np

# Perez et al. 1993, Table 1: for each of the 8 clearness bins, a, b, c, d, e each as
# x1 + x2 Z + Delta (x3 + x4 Z), Z the solar zenith angle in radians. Bin edges of epsilon:
PEREZ_BINS = [1.0, 1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200]
PEREZ_COEFFICIENTS = np.array([
    [[1.3525, -0.2576, -0.2690, -1.4366], [-0.7670, 0.0007, 1.2734, -0.1233], [2.8000, 0.6004, 1.2375, 1.0000],
     [1.8734, 0.6297, 0.9738, 0.2809], [0.0356, -0.1246, -0.5718, 0.9938]],
    [[-1.2219, -0.7730, 1.4148, 1.1016], [-0.2054, 0.0367, -3.9128, 0.9156], [6.9750, 0.1774, 6.4477, -0.1239],
     [-1.5798, -0.5081, -1.7812, 0.1080], [0.2624, 0.0672, -0.2190, -0.4285]],
    [[-1.1000, -0.2515, 0.8952, 0.0156], [0.2782, -0.1812, -4.5000, 1.1766], [24.7219, -13.0812, -37.7000, 34.8438],
     [-5.0000, 1.5218, 3.9229, -2.6204], [-0.0156, 0.1597, 0.4199, -0.5562]],
    [[-0.5484, -0.6654, -0.2672, 0.7117], [0.7234, -0.6219, -5.6812, 2.6297], [33.3389, -18.3000, -62.2500, 52.0781],
     [-3.5000, 0.0016, 1.1477, 0.1062], [0.4659, -0.3296, -0.0876, -0.0329]],
    [[-0.6000, -0.3566, -2.5000, 2.3250], [0.2937, 0.0496, -5.6812, 1.8415], [21.0000, -4.7656, -21.5906, 7.2492],
     [-3.5000, -0.1554, 1.4062, 0.3988], [0.0032, 0.0766, -0.0656, -0.1294]],
    [[-1.0156, -0.3670, 1.0078, 1.4051], [0.2875, -0.5328, -3.8500, 3.3750], [14.0000, -0.9999, -7.1406, 7.5469],
     [-3.4000, -0.1078, -1.0750, 1.5702], [-0.0672, 0.4016, 0.3017, -0.4844]],
    [[-1.0000, 0.0211, 0.5025, -0.5119], [-0.3000, 0.1922, 0.7023, -1.6317], [19.0000, -5.0000, 1.2438, -1.9094],
     [-4.0000, 0.0250, 0.3844, 0.2656], [1.0468, -0.3788, -2.4517, 1.4656]],
    [[-1.0500, 0.0289, 0.4260, 0.3590], [-0.3250, 0.1156, 0.7781, 0.0025], [31.0625, -14.5000, -46.1148, 55.3750],
     [-7.2312, 0.4050, 13.3500, 0.6234], [1.5000, -0.6426, 1.8564, 0.5636]],
])
SOLAR_CONSTANT_W_M2 = 1367.0  # gendaylit's


def perez_coefficients(dni, dhi, sun_zenith, sun_scale):
    """a..e of the Perez sky for irradiances in W m^-2 and the sun's zenith angle in radians."""
    z3 = 1.041 * sun_zenith ** 3
    epsilon = ((dhi + dni) / dhi + z3) / (1.0 + z3)
    # Kasten's air mass, as gendaylit computes it.
    air_mass = 1.0 / (math.cos(sun_zenith) + 0.15 * (93.885 - math.degrees(sun_zenith)) ** -1.253)
    delta = dhi * air_mass / (SOLAR_CONSTANT_W_M2 * sun_scale)
    b = min(int(np.searchsorted(PEREZ_BINS, epsilon, side="right")) - 1, 7)
    if 1.065 < epsilon < 2.8:
        delta = max(delta, 0.2)
    x = PEREZ_COEFFICIENTS[b]
    coefficients = x[:, 0] + x[:, 1] * sun_zenith + delta * (x[:, 2] + x[:, 3] * sun_zenith)
    if b == 0:
        coefficients[2] = math.exp((delta * (x[2, 0] + x[2, 1] * sun_zenith)) ** x[2, 2]) - x[2, 3]
        coefficients[3] = -math.exp(delta * (x[3, 0] + x[3, 1] * sun_zenith)) + x[3, 2] + delta * x[3, 3]
    return coefficients, epsilon, delta


def perez(coefficients, cos_zenith, gamma):
    a, b, c, d, e = coefficients
    return (1.0 + a * np.exp(b / np.maximum(cos_zenith, 0.01))) * (1.0 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)


def cie12(cos_zenith, gamma, sun_zenith):
    a, b, c, d, e = -1.0, -0.32, 10.0, -3.0, 0.45
    f = 1.0 + c * (np.exp(d * gamma) - math.exp(d * math.pi / 2)) + e * np.cos(gamma) ** 2
    phi = 1.0 + a * np.exp(b / np.maximum(cos_zenith, 0.01))
    return f * phi


def tregenza():
    """Patch centres, solid angles and the integral of cos(zenith) over each (reinhart.cal, MF 1)."""
    counts = [30, 30, 24, 24, 18, 12, 6]
    centres, omegas, cosines, rows = [], [], [], []
    for r, n in enumerate(counts + [1]):
        a0, a1 = 12.0 * r, (90.0 if r == 7 else 12.0 * (r + 1))
        width = 2 * math.pi / n
        for j in range(n):
            alt = math.radians(90.0 if r == 7 else 0.5 * (a0 + a1))
            az = j * width
            centres.append((math.cos(alt) * math.sin(az), math.cos(alt) * math.cos(az), math.sin(alt)))
            s0, s1 = math.sin(math.radians(a0)), math.sin(math.radians(a1))
            omegas.append(width * (s1 - s0))
            cosines.append(width * 0.5 * (s1 * s1 - s0 * s0))
            rows.append(r)
    return np.array(centres), np.array(omegas), np.array(cosines), np.array(rows)


def read_matrix(path):
    with open(path) as f:
        header = {}
        for line in f:
            line = line.strip()
            if not line:
                break
            if "=" in line:
                k, v = line.split("=", 1)
                header[k] = v
        values = np.array(f.read().split(), dtype=float)
    rows, cols = int(header["NROWS"]), int(header["NCOLS"])
    return values.reshape(rows, cols, 3)


def main(out_dir, epw_path):
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "build", "python"))
    import atmo

    epw = atmo.read_epw(epw_path)["hours"]
    hours = list(csv.DictReader(open(os.path.join(out_dir, "hours.csv"))))
    matrix = read_matrix(os.path.join(out_dir, "sky.mtx"))
    centres, omegas, cosines, rows = tregenza()
    lum = 179.0 * (0.265 * matrix[..., 0] + 0.670 * matrix[..., 1] + 0.065 * matrix[..., 2])
    groups = {}  # (elevation band, model, region) -> ratios
    for h in hours:
        if h["status"] != "clear":
            continue
        i = int(h["hour"])
        dni, dhi = epw["direct_normal_w_m2"][i], epw["diffuse_horizontal_w_m2"][i]
        if not (dhi > 0 and dni >= 0):
            continue
        elevation = math.radians(float(h["sun_elevation_deg"]))
        azimuth = math.radians(float(h["sun_azimuth_deg"]))
        sun = np.array([math.cos(elevation) * math.sin(azimuth), math.cos(elevation) * math.cos(azimuth),
                        math.sin(elevation)])
        sun_zenith = math.pi / 2 - elevation
        gamma = np.arccos(np.clip(centres @ sun, -1, 1))
        sky = lum[1:, i].copy()
        sun_patch = int(np.argmin(gamma))
        keep = np.ones(len(sky), bool)
        keep[sun_patch] = False
        # The sky's diffuse illuminance without the sun's patch, from atmo's own patches.
        target = np.sum((sky * cosines)[keep])
        jd = float(h["julian_day_utc"])
        sun_scale = 1.0 / (1.0 - 0.01671 * math.cos(2 * math.pi * (jd - 2451547.0) / 365.2596)) ** 2
        coefficients, _, _ = perez_coefficients(dni, dhi, sun_zenith, sun_scale)
        for name, model in (("Perez", perez(coefficients, centres[:, 2], gamma)),
                            ("CIE 12", cie12(centres[:, 2], gamma, sun_zenith))):
            scaled = model * target / np.sum((model * cosines)[keep])
            ratio = sky / scaled
            band = "10-30" if elevation < math.radians(30) else ("30-50" if elevation < math.radians(50) else "50-80")
            for region, mask in (("near the sun (< 20°)", gamma < math.radians(20)),
                                 ("horizon row, away from the sun", (rows == 0) & (gamma >= math.radians(20))),
                                 ("rest of the sky", (rows > 0) & (gamma >= math.radians(20)))):
                groups.setdefault((band, name, region), []).extend(ratio[mask & keep])
    print(f"{sum(1 for h in hours if h['status'] == 'clear')} clear hours of {out_dir}\n")
    print("| sun elevation (°) | region | atmo ÷ Perez, median (10–90 %) | atmo ÷ CIE 12, median (10–90 %) |")
    print("|---|---|---|---|")
    for band in ("10-30", "30-50", "50-80"):
        for region in ("near the sun (< 20°)", "horizon row, away from the sun", "rest of the sky"):
            cells = []
            for name in ("Perez", "CIE 12"):
                v = np.array(groups.get((band, name, region), []))
                cells.append("—" if v.size == 0 else
                             f"{np.median(v):.2f} ({np.percentile(v, 10):.2f}–{np.percentile(v, 90):.2f})")
            print(f"| {band.replace('-', '–')} | {region} | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
