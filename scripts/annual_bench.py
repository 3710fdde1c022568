#!/usr/bin/env python3
"""The annual figures of docs/daylighting.md and docs/performance.md, on this machine:

  scripts/annual_bench.py year   OUT_DIR   a year of Greensboro's TMY3 with atmo annual (source4d,
                                           us-standard, Tregenza + ground, a 30-degree south plane):
                                           wall time, models built, and how well the calibrated hours
                                           reproduce the file's direct and diffuse illuminance
  scripts/annual_bench.py dask   DAYS      DAYS summer days of it in 2 shards on a Dask LocalCluster
                                           of 1 worker, then of 2 (one thread each, atmo's threads 1):
                                           the speed-up, and whether both wrote the same bytes
  scripts/annual_bench.py stats  OUT_DIR   the statistics of an existing run's hours.csv
  scripts/annual_bench.py blend  OUT_DIR   for 24 clear hours of that run: (a) its sky light on the
                                           horizontal and the 30-degree plane against the model built
                                           for the hour's aod_550 and omega_550 (atmo.with_aerosol):
                                           how far the blend of table nodes is from the model at those
                                           values; (b) for 8 of them, its global irradiance against an
                                           exact calibration of the same hour (atmo.calibrate, then
                                           atmo.irradiance): what a user of the run gets against
                                           calibrating each hour with its own models

Run from the repository root after a build (PYTHONPATH=build/python, /usr/bin/python3 for Debian's
numpy and distributed). Prints the machine (CPU, cores) and its load with the figures.
"""
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EPW = os.path.join(ROOT, "tests", "data", "greensboro_tmy3.epw")
ATMO = os.path.join(ROOT, "build", "apps", "atmo", "atmo")


def machine():
    cpu = "unknown CPU"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return f"{cpu}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}"


def stats(out_dir):
    rows = list(csv.DictReader(open(os.path.join(out_dir, "hours.csv"))))
    by_status = {}
    for r in rows:
        by_status[r["status"]] = by_status.get(r["status"], 0) + 1
    print("hours by status:", ", ".join(f"{k} {v}" for k, v in sorted(by_status.items())))
    for status in ("clear", "cloudy", "overcast"):
        dn, dh = [], []
        for r in rows:
            if r["status"] != status:
                continue
            m_dn, m_dh = float(r["measured_direct_normal_lux"]), float(r["measured_diffuse_horizontal_lux"])
            if m_dn > 1000:
                dn.append(abs(float(r["direct_normal_lux"]) / m_dn - 1))
            if m_dh > 1000:
                dh.append(abs(float(r["diffuse_horizontal_lux"]) / m_dh - 1))
        for name, v in (("direct normal", dn), ("diffuse horizontal", dh)):
            if v:
                v.sort()
                print(f"{status:9s} {name:19s}: {len(v)} hours above 1000 lux, |model/measured - 1| median "
                      f"{100 * v[len(v) // 2]:.3f} %, p95 {100 * v[int(0.95 * (len(v) - 1))]:.3f} %, max {100 * v[-1]:.3f} %")
    aods = sorted(float(r["aod_550"]) for r in rows if r["status"] == "clear")
    omegas = sorted(float(r["omega_550"]) for r in rows if r["status"] == "clear")
    if aods:
        q = lambda v, p: v[int(p * (len(v) - 1))]
        print(f"clear hours: aod_550 median {q(aods, .5):.3f} (p5 {q(aods, .05):.3f}, p95 {q(aods, .95):.3f}); "
              f"omega_550 median {q(omegas, .5):.3f} (p5 {q(omegas, .05):.3f}, p95 {q(omegas, .95):.3f})")


def year(out_dir):
    shutil.rmtree(out_dir, ignore_errors=True)
    print(machine())
    start = time.time()
    r = subprocess.run([ATMO, "annual", "--epw", EPW, "--out-dir", out_dir, "--plane", "30:180"], capture_output=True,
                       text=True, check=True)
    print(f"atmo annual, a year: {time.time() - start:.0f} s wall; {r.stdout.strip()}")
    stats(out_dir)


def dask(days):
    sys.path.insert(0, os.path.join(ROOT, "build", "python"))
    import atmo
    import distributed
    from atmo import annual_on_dask

    print(machine())
    with tempfile.TemporaryDirectory() as tmp:
        # Summer days: the most daylight hours per day.
        with open(EPW) as f:
            lines = f.read().splitlines(keepends=True)
        epw = os.path.join(tmp, "days.epw")
        with open(epw, "w") as f:
            f.writelines(lines[:8] + lines[8 + 24 * 172:8 + 24 * (172 + days)])
        times = {}
        for workers in (1, 2):
            out = os.path.join(tmp, f"out{workers}")
            with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                          dashboard_address=None, silence_logs=50) as cluster, \
                    distributed.Client(cluster) as client:
                start = time.time()
                result = annual_on_dask(client, epw, out, shards=2, threads_per_worker=1, planes=[(30.0, 180.0)])
                times[workers] = time.time() - start
                assert result["merged"]
            models = [r["models_built"] for r in result["shards"]]
            hours = [r["computed"] for r in result["shards"]]
            print(f"{days} days on {workers} worker(s): {times[workers]:.1f} s (per shard: models {models}, hours {hours})")
        same = open(os.path.join(tmp, "out1", "sky.mtx"), "rb").read() == open(os.path.join(tmp, "out2", "sky.mtx"), "rb").read()
        print(f"speed-up 2 workers / 1: {times[1] / times[2]:.2f}x; sky.mtx identical: {same}")


def blend(out_dir):
    sys.path.insert(0, os.path.join(ROOT, "build", "python"))
    import datetime
    import json

    import atmo

    print(machine())
    hours = [r for r in csv.DictReader(open(os.path.join(out_dir, "hours.csv"))) if r["status"] == "clear"]
    hours = hours[:: max(1, len(hours) // 24)][:24]
    planes = {}
    for r in csv.DictReader(open(os.path.join(out_dir, "irradiance.csv"))):
        planes[(r["hour"], r["plane"])] = r
    errors = {"horizontal": [], "30:180": []}
    for r in hours:
        when = datetime.datetime(1970, 1, 1) + datetime.timedelta(days=float(r["julian_day_utc"]) - 2440587.5)
        sun = atmo.sun_position(when.isoformat() + "Z", 36.10, -79.95)
        config = atmo.with_aerosol(float(r["aod_550"]), float(r["omega_550"]), preset="us-standard")
        exact = atmo.irradiance(float(r["sun_elevation_deg"]), float(r["sun_azimuth_deg"]), planes=[(0, 180), (30, 180)],
                                config=config, altitude_m=273.0, sun_scale=1.0 / sun["distance_au"] ** 2)
        for name, e in zip(("horizontal", "30:180"), exact["planes"]):
            annual = planes[(r["hour"], name)]
            ours = float(annual["circumsolar_lux"]) + float(annual["sky_diffuse_lux"])
            theirs = e["circumsolar_lux"] + e["sky_diffuse_lux"]
            errors[name].append(ours / theirs - 1)
            if os.environ.get("ATMO_BLEND_DETAIL"):
                print(r["hour"], r["sun_elevation_deg"][:5], r["aod_550"][:5], r["omega_550"][:5], name, f"{100 * (ours / theirs - 1):+.2f} %")
    for name, v in errors.items():
        a = sorted(abs(x) for x in v)
        print(f"(a) {name:10s} sky light (circumsolar + diffuse), annual / model at its aod and omega - 1 over {len(v)} "
              f"clear hours: median |e| {100 * a[len(a) // 2]:.2f} %, max {100 * a[-1]:.2f} %, mean e {100 * sum(v) / len(v):+.2f} %")
    calibrated = {"horizontal": [], "30:180": []}
    omega_shift = []
    for r in hours[::3][:8]:
        when = datetime.datetime(1970, 1, 1) + datetime.timedelta(days=float(r["julian_day_utc"]) - 2440587.5)
        scale = 1.0 / atmo.sun_position(when.isoformat() + "Z", 36.10, -79.95)["distance_au"] ** 2
        el, az = float(r["sun_elevation_deg"]), float(r["sun_azimuth_deg"])
        c = atmo.calibrate(float(r["measured_direct_normal_lux"]), float(r["measured_diffuse_horizontal_lux"]), el, az,
                           altitude_m=273.0, sun_scale=scale)
        omega_shift.append(float(r["omega_550"]) - c["omega_550"])
        exact = atmo.irradiance(el, az, planes=[(0, 180), (30, 180)], config=json.loads(c["parameters_json"]),
                                altitude_m=273.0, sun_scale=scale)
        for name, e in zip(("horizontal", "30:180"), exact["planes"]):
            calibrated[name].append(float(planes[(r["hour"], name)]["global_lux"]) / e["global_lux"] - 1)
    for name, v in calibrated.items():
        a = sorted(abs(x) for x in v)
        print(f"(b) {name:10s} global, annual / exact calibration - 1 over {len(v)} clear hours: "
              f"median |e| {100 * a[len(a) // 2]:.2f} %, max {100 * a[-1]:.2f} %")
    print(f"(b) omega_550 of the run minus the exact calibration's: {min(omega_shift):+.3f} to {max(omega_shift):+.3f}")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("year", "dask", "stats", "blend"):
        sys.exit(__doc__)
    {"year": year, "dask": lambda a: dask(int(a)), "stats": stats, "blend": blend}[sys.argv[1]](sys.argv[2])
