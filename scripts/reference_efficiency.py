#!/usr/bin/env python3
"""Efficiency of the `reference` model per direction: relative standard error per second.

For each configuration (observer altitude, sun zenith, view zenith, azimuth) it runs
`atmo sample --model reference` once with a fixed number of paths under `taskset -c 0,1
--threads 2`, reads the radiance and standard error of every channel, and reports

  rel_se   = standard error / radiance (per channel),
  t        = the CPU time of the run (user + system) / 2: the wall time of 2 idle cores,
  t_to(E)  = t * (rel_se / E)^2, the time to reach the relative error E (the standard error falls
             as 1/sqrt(paths); the figure is the slowest channel's),

as a Markdown table. The wall time under the measuring load is printed too, but t is the figure
to compare (the machine may be shared). Example (docs/models/reference.md, "Performance"):

  scripts/reference_efficiency.py --samples 65536 --option nee=vertex
  scripts/reference_efficiency.py --samples 16384 --sun 95,100,104,108 --altitude 0
"""
import argparse
import csv
import io
import math
import resource
import subprocess
import sys
import time

VIEWS = [(0, 0), (60, 0), (60, 180), (85, 0), (85, 180), (90, 0), (90, 180)]


def run(atmo, altitude, sun, view, azimuth, samples, seed, options):
    cmd = ["taskset", "-c", "0,1", atmo, "sample", "--model", "reference", "--threads", "2",
           "--altitude", str(altitude), "--sun-zenith", str(sun), "--view-zenith", str(view),
           "--azimuth", str(azimuth), "--samples", str(samples), "--seed", str(seed)]
    for o in options:
        cmd += ["--option", o]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rows = list(csv.DictReader(io.StringIO(out)))
    return rows, wall, cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--atmo", default="build/apps/atmo/atmo")
    ap.add_argument("--samples", type=int, default=65536)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--altitude", default="0,10000")
    ap.add_argument("--sun", default="60,90,95,100,104,108")
    ap.add_argument("--views", default=None, help="zenith:azimuth,... (default: 0:0,60:0,60:180,85:0,85:180,90:0,90:180)")
    ap.add_argument("--option", action="append", default=[], help="reference option KEY=VALUE (repeatable)")
    args = ap.parse_args()
    views = VIEWS if args.views is None else [tuple(float(x) for x in v.split(":")) for v in args.views.split(",")]
    print(f"options: {' '.join(args.option) or '(defaults)'}; {args.samples} paths; seed {args.seed}")
    print("| altitude m | sun ° | view ° | azimuth ° | rel SE 680 / 550 / 440 nm | t (s) | wall (s) | t to 1 % (s) | t to 0.3 % (s) |")
    print("|---:|---:|---:|---:|---|---:|---:|---:|---:|")
    for altitude in [float(a) for a in args.altitude.split(",")]:
        for sun in [float(s) for s in args.sun.split(",")]:
            for view, azimuth in views:
                rows, wall, cpu = run(args.atmo, altitude, sun, view, azimuth, args.samples, args.seed, args.option)
                t = cpu / 2.0
                rel = []
                for r in rows:
                    radiance, se = float(r["radiance"]), float(r["stderr"])
                    rel.append(se / radiance if radiance > 0 else math.inf)
                worst = max(rel)
                rel_text = " / ".join(f"{x:.3g}" for x in rel)
                to1 = t * (worst / 0.01) ** 2
                to03 = t * (worst / 0.003) ** 2
                print(f"| {altitude:g} | {sun:g} | {view:g} | {azimuth:g} | {rel_text} | {t:.2f} | {wall:.2f} | "
                      f"{to1:.3g} | {to03:.3g} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
