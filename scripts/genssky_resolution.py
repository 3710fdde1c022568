#!/usr/bin/env python3
"""What the table resolution of Radiance's `genssky` costs a daylighting sky, against atmo's solvers.

genssky (Radiance 6, 2024) looks the sky up in a precomputed table of Bruneton's 2017 method:
Bruneton's parameterisation of (r, mu, mu_s, nu) at 16 x 64 x 16 x 4 texels (its atmos.c; Bruneton's
own demo uses 32 x 128 x 32 x 8), 20 bands over 380-780 nm and 4 orders. Such a table stores, per
texel, the single Rayleigh and Mie scattering without their phase functions and the multiple
scattering divided by the Rayleigh phase; a lookup interpolates those linearly in the texture
coordinates (hardware filtering in r, mu and mu_s, by hand in nu) and multiplies the phases back
at the query's nu.

This script measures that interpolation, nothing else: it fills the texels of such a table with
atmo's own values at the texel centres (model source4d, whose radiance is within 0.2 % of atmo's
path tracer at the median with the sun up, docs/accuracy.md) and reads the table back at the 145
Tregenza patch centres for suns from 2 to 80 degrees up, against source4d at the same directions.
The physics being the same on both sides, the difference is the table's resolution alone. With
`--reference N`, the same patches at two sun elevations are also traced by the reference path
tracer (N paths each) to show what both are worth against it.

The observer is on the ground, where the r axis reads its first texel exactly (no interpolation
in r); only the sky half of the mu axis (32 texels of 64) is read by views above the horizon.
The single scattering is split into its Rayleigh and Mie parts by a second run in which the aerosol
absorbs what it scattered (the same transmittances, no Mie light).

    scripts/genssky_resolution.py [--atmo build/apps/atmo/atmo] [--write docs/daylighting.md]
                                  [--reference 65536]

Only the Python standard library is used. With --write, the table between
`<!-- table: genssky -->` and `<!-- end table -->` in that file is replaced.
"""

import argparse
import atexit
import csv
import io
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SUN_ELEVATIONS = [2, 5, 10, 20, 30, 45, 60, 80]
# Tregenza's 145 patches: the centres' elevations and the patches per row.
TREGENZA = [(6, 30), (18, 30), (30, 24), (42, 24), (54, 18), (66, 12), (78, 6), (90, 1)]


class Atmo:
    def __init__(self, path, preset):
        self.path = path
        self.preset = preset
        self.folder = tempfile.mkdtemp(prefix="genssky_")
        atexit.register(shutil.rmtree, self.folder, True)  # the grids and the configs go with the run

    def sample(self, points, config=None, options=(), model="source4d", extra=()):
        """points: (sun_zenith, view_zenith, azimuth) at the ground -> per point the channels' radiance."""
        grid = os.path.join(self.folder, "grid.csv")
        with open(grid, "w") as f:
            f.write("altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n")
            for p in points:
                f.write("0,%.12g,%.12g,%.12g\n" % p)
        sky = ["--config", config] if config else ["--preset", self.preset]
        args = [self.path, "sample", "--model", model, "--grid", grid] + sky + list(extra)
        for o in options:
            args += ["--option", o]
        out = subprocess.run(args, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit("genssky_resolution: %s failed: %s" % (" ".join(args), out.stderr.strip()))
        # One row per point and channel, the channels of a point together (docs/cli.md).
        rows = list(csv.DictReader(io.StringIO(out.stdout)))
        nc = len(rows) // len(points)
        return [[float(rows[nc * i + c]["radiance"]) for c in range(nc)] for i in range(len(points))]


# Phase functions as atmo defines them (src/atmo/shared/phase.glsl), normalised over the sphere.
def phase(kind, g, nu):
    kind = kind.replace("_", "-")
    if kind == "rayleigh":
        return 3.0 / (16.0 * math.pi) * (1.0 + nu * nu)
    if kind == "modified-rayleigh":
        return (1.4 + 0.5 * nu * nu) / (47.0 / 30.0 * 4.0 * math.pi)
    if kind == "cornette-shanks":
        k = 3.0 / (8.0 * math.pi) * (1.0 - g * g) / (2.0 + g * g)
        d = 1.0 + g * g - 2.0 * g * nu
        return k * (1.0 + nu * nu) / (d * math.sqrt(d))
    if kind == "henyey-greenstein":
        d = 1.0 + g * g - 2.0 * g * nu
        return (1.0 - g * g) / (4.0 * math.pi * d * math.sqrt(d))
    if kind == "isotropic":
        return 1.0 / (4.0 * math.pi)
    sys.exit("genssky_resolution: phase function %r is not analytic (use a preset with an analytic Mie phase)" % kind)


class Bruneton:
    """Bruneton 2017's scattering-texture parameterisation (his functions.glsl), ground observer."""

    def __init__(self, bottom, top, mu_size, mu_s_size, nu_size, mu_s_min=-0.2, uniform_sun=False):
        self.bottom, self.top = bottom, top
        # uniform_sun: the sun-zenith texels uniform in angle from 0 to acos(mu_s_min) instead of
        # Bruneton's mapping (which is dense near the horizon and sparse near the zenith).
        self.uniform_sun, self.max_sun_zenith = uniform_sun, math.acos(mu_s_min)
        self.H = math.sqrt(top * top - bottom * bottom)
        self.mu_half = mu_size // 2
        self.mu_s_size, self.nu_size = mu_s_size, nu_size
        self.A = (self.distance_to_top(mu_s_min) - (top - bottom)) / (self.H - (top - bottom))

    def distance_to_top(self, mu):
        r = self.bottom
        return max(-r * mu + math.sqrt(max(r * r * (mu * mu - 1.0) + self.top * self.top, 0.0)), 0.0)

    # Unit-range coordinates x in [0, 1] of a view above the horizon and of the sun; nodes at
    # x = i / (n - 1) (the texel centres).
    def x_mu(self, mu):
        d = self.distance_to_top(mu)
        return (d - (self.top - self.bottom)) / (self.H - (self.top - self.bottom))

    def mu_of(self, x):
        d = (self.top - self.bottom) + x * (self.H - (self.top - self.bottom))
        return 1.0 if d == 0 else max(-1.0, min(1.0, (self.H ** 2 - d * d) / (2.0 * self.bottom * d)))

    def x_mu_s(self, mu_s):
        if self.uniform_sun:
            return max(1.0 - math.acos(mu_s) / self.max_sun_zenith, 0.0)
        a = (self.distance_to_top(mu_s) - (self.top - self.bottom)) / (self.H - (self.top - self.bottom))
        return max(1.0 - a / self.A, 0.0) / (1.0 + a)

    def mu_s_of(self, x):
        if self.uniform_sun:
            return math.cos((1.0 - x) * self.max_sun_zenith)
        a = (self.A - x * self.A) / (1.0 + x * self.A)
        d = (self.top - self.bottom) + min(a, self.A) * (self.H - (self.top - self.bottom))
        return 1.0 if d == 0 else max(-1.0, min(1.0, (self.H ** 2 - d * d) / (2.0 * self.bottom * d)))


def nu_node(l, nu_size):
    return -1.0 + 2.0 * l / (nu_size - 1)


def clamp_nu(nu, mu, mu_s):
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return max(mu * mu_s - s, min(mu * mu_s + s, nu))


def direction(mu, mu_s, nu):
    """(sun zenith, view zenith, azimuth from the sun) in degrees of a (mu, mu_s, nu)."""
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    cos_phi = 1.0 if s < 1e-12 else max(-1.0, min(1.0, (nu - mu * mu_s) / s))
    return (math.degrees(math.acos(mu_s)), math.degrees(math.acos(mu)), math.degrees(math.acos(cos_phi)))


def brackets(x, n):
    """The two nodes around unit-range x on n nodes and the weight of the upper."""
    t = min(max(x, 0.0), 1.0) * (n - 1)
    i = min(int(math.floor(t)), n - 2)
    return i, t - i


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmo", default=os.path.join(ROOT, "build", "apps", "atmo", "atmo"))
    parser.add_argument("--preset", default="earth")
    parser.add_argument("--write", help="rewrite the genssky table of this Markdown file")
    parser.add_argument("--uniform-sun-zenith", action="store_true",
                        help="the tables' sun-zenith texels uniform in angle instead of Bruneton's mapping")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 unless the emulation checks out: the fine table converges on source4d "
                             "(p95 under 0.5 %% with the sun up to 60 degrees) and the nu axis's error falls "
                             "with its texels (the ctest genssky_resolution)")
    parser.add_argument("--reference", type=int, default=0,
                        help="also trace the patches at sun 10 and 45 degrees with N paths each")
    args = parser.parse_args()
    atmo = Atmo(args.atmo, args.preset)

    params = json.loads(subprocess.run([args.atmo, "presets", "--dump", args.preset], capture_output=True,
                                       text=True, check=True).stdout)
    rayleigh_phase = params["rayleigh"].get("phase_function", "rayleigh")
    mie_phase, mie_g = params["mie"].get("phase_function", "cornette-shanks"), params["mie"].get("phase_g", 0.0)
    phase(mie_phase, mie_g, 0.0)  # refuses a tabulated phase early
    # The aerosol as a pure absorber of the same extinction: the Rayleigh single scattering alone.
    absorbing = json.loads(json.dumps(params))
    absorbing["mie"]["absorption_per_m"] = [s + a for s, a in zip(params["mie"]["scattering_per_m"],
                                                                  params["mie"]["absorption_per_m"])]
    absorbing["mie"]["scattering_per_m"] = [0.0] * len(params["mie"]["scattering_per_m"])
    absorbing_path = os.path.join(atmo.folder, "absorbing.json")
    with open(absorbing_path, "w") as f:
        json.dump(absorbing, f)

    single = ["orders=1", "tail=off"]

    def texels(points):
        """Per (mu, mu_s, nu) point: what a Bruneton texel holds there, (S_R + M / P_R, S_M) per channel."""
        dirs = [direction(*p) for p in points]
        full = atmo.sample(dirs)
        one = atmo.sample(dirs, options=single)
        ray = atmo.sample(dirs, config=absorbing_path, options=single)
        out = []
        for (mu, mu_s, nu), f, o, r in zip(points, full, one, ray):
            p_r, p_m = phase(rayleigh_phase, 0.0, nu), phase(mie_phase, mie_g, nu)
            out.append(([(rc + (fc - oc)) / p_r for fc, oc, rc in zip(f, o, r)],
                        [(oc - rc) / p_m for oc, rc in zip(o, r)]))
        return out

    def lookup(values, nu):
        """A texel's values (as texels() returns them) times the phases at the query's nu."""
        p_r, p_m = phase(rayleigh_phase, 0.0, nu), phase(mie_phase, mie_g, nu)
        g, m = values
        return [p_r * a + p_m * b for a, b in zip(g, m)]

    def blend(items):
        """Weighted sum of texel values: items are (weight, values)."""
        g = [sum(w * v[0][c] for w, v in items) for c in range(len(items[0][1][0]))]
        m = [sum(w * v[1][c] for w, v in items) for c in range(len(items[0][1][1]))]
        return g, m

    # The queries: Tregenza's patch centres, the sun in the south.
    queries = []
    for e_sun in SUN_ELEVATIONS:
        for e, n in TREGENZA:
            for i in range(n):
                azimuth = (360.0 * i / n) % 360.0
                away = min(azimuth, 360.0 - azimuth)  # from the sun's azimuth
                queries.append((e_sun, 90.0 - e, away))
    exact = atmo.sample([(90.0 - s, v, a) for s, v, a in queries])

    def mu_nu(q):
        s, v, a = q
        mu, mu_s = math.cos(math.radians(v)), math.cos(math.radians(90.0 - s))
        nu = mu * mu_s + math.sqrt(max((1 - mu * mu) * (1 - mu_s * mu_s), 0.0)) * math.cos(math.radians(a))
        return mu, mu_s, nu

    results = {}

    # (1) The nu axis alone: nu_size nodes at the query's own mu and mu_s.
    for nu_size in (4, 8, 16):
        nodes, plan = [], []
        for q in queries:
            mu, mu_s, nu = mu_nu(q)
            l, w = brackets((nu + 1.0) / 2.0, nu_size)
            plan.append((len(nodes), w, nu))
            for k in (l, l + 1):
                nodes.append((mu, mu_s, clamp_nu(nu_node(k, nu_size), mu, mu_s)))
        values = texels(nodes)
        results["nu axis alone, %d texels" % nu_size] = [
            lookup(blend([(1 - w, values[i]), (w, values[i + 1])]), nu) for i, w, nu in plan]

    # (2) genssky's whole table at the ground: mu (sky half, 32 texels) x mu_s (16) x nu (4).
    # The last row checks the emulation itself: a fine table converges on source4d.
    for label, mu_size, mu_s_size, nu_size in (("genssky's table, 64 x 16 x 4 (mu x mu_s x nu)", 64, 16, 4),
                                               ("Bruneton's demo table, 128 x 32 x 8", 128, 32, 8),
                                               ("a fine table, 1024 x 256 x 1024 (the emulation's check)", 1024,
                                                256, 1024)):
        b = Bruneton(params["ground_radius_m"], params["top_radius_m"], mu_size, mu_s_size, nu_size,
                     uniform_sun=args.uniform_sun_zenith)
        index, nodes, plan = {}, [], []
        for q in queries:
            mu, mu_s, nu = mu_nu(q)
            j, wj = brackets(b.x_mu(mu), b.mu_half)
            k, wk = brackets(b.x_mu_s(mu_s), b.mu_s_size)
            l, wl = brackets((nu + 1.0) / 2.0, b.nu_size)
            corners = []
            for dj, fj in ((0, 1 - wj), (1, wj)):
                for dk, fk in ((0, 1 - wk), (1, wk)):
                    for dl, fl in ((0, 1 - wl), (1, wl)):
                        key = (j + dj, k + dk, l + dl)
                        if key not in index:
                            mu_n = b.mu_of((j + dj) / (b.mu_half - 1))
                            mu_s_n = b.mu_s_of((k + dk) / (b.mu_s_size - 1))
                            index[key] = len(nodes)
                            nodes.append((mu_n, mu_s_n, clamp_nu(nu_node(l + dl, b.nu_size), mu_n, mu_s_n)))
                        corners.append((fj * fk * fl, index[key]))
            plan.append((corners, nu))
        values = texels(nodes)
        results[label] = [lookup(blend([(w, values[i]) for w, i in corners]), nu) for corners, nu in plan]

    # Relative differences from source4d per sun elevation, over patches and channels.
    def stats(values):
        e = sorted(abs(v) for v in values)
        return e[len(e) // 2], e[int(0.95 * (len(e) - 1))], e[-1]

    if args.check:
        def p95_up_to(label, highest_sun):
            return stats([a / b - 1.0 for q, t, x in zip(queries, results[label], exact) if q[0] <= highest_sun
                          for a, b in zip(t, x) if b > 0])[1]
        fine = p95_up_to("a fine table, 1024 x 256 x 1024 (the emulation's check)", 60)
        nu = [p95_up_to("nu axis alone, %d texels" % k, 80) for k in (4, 8, 16)]
        print("check: fine table p95 %.3f %% (sun <= 60); nu axis alone p95 %s" %
              (100 * fine, " > ".join("%.2f %%" % (100 * v) for v in nu)))
        if not (fine < 0.005 and nu[0] > nu[1] > nu[2]):
            sys.exit("genssky_resolution: the emulation does not check out")

    header = ["table (read at the ground)"] + ["sun %d°" % s for s in SUN_ELEVATIONS] + ["all: median / p95 / max"]
    rows = []
    for label, table in results.items():
        by_sun = {s: [] for s in SUN_ELEVATIONS}
        for q, t, x in zip(queries, table, exact):
            by_sun[q[0]] += [a / b - 1.0 for a, b in zip(t, x) if b > 0]
        every = [v for s in SUN_ELEVATIONS for v in by_sun[s]]
        m, p, w = stats(every)
        rows.append([label] + ["%.1f %%" % (100 * stats(by_sun[s])[1]) for s in SUN_ELEVATIONS] +
                    ["%.2f / %.1f / %.1f %%" % (100 * m, 100 * p, 100 * w)])
    text = ("%d Tregenza patch centres per sun, 3 channels, preset `%s`%s; each cell the p95 of |table ÷ "
            "source4d − 1| over the patches and channels\n\n" %
            (145, args.preset, ", sun-zenith texels uniform in angle" if args.uniform_sun_zenith else ""))
    text += "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n"
    for r in rows:
        text += "| " + " | ".join(r) + " |\n"

    if args.reference:
        # source4d and genssky's table against the path tracer, at two suns.
        label = "genssky's table, 64 x 16 x 4 (mu x mu_s x nu)"
        lines = []
        for e_sun in (10, 45):
            pick = [i for i, q in enumerate(queries) if q[0] == e_sun]
            ref = atmo.sample([(90.0 - queries[i][0], queries[i][1], queries[i][2]) for i in pick], model="reference",
                              extra=["--samples", str(args.reference), "--seed", "1"])
            for name, values in (("source4d", exact), ("genssky's table", results[label])):
                e = [values[i][c] / ref[n][c] - 1.0 for n, i in enumerate(pick) for c in range(len(ref[n]))
                     if ref[n][c] > 0]
                m, p, w = stats(e)
                lines.append("| %d° | %s | %.2f %% | %.1f %% | %.1f %% |" % (e_sun, name, 100 * m, 100 * p, 100 * w))
        text += ("\nAgainst the reference path tracer (%d paths per patch centre and channel, seed 1), the same "
                 "145 patches:\n\n| sun | | median | p95 | max |\n|---|---|---|---|---|\n" % args.reference)
        text += "\n".join(lines) + "\n"

    print(text, end="")
    if args.write:
        with open(args.write) as f:
            doc = f.read()
        start, end = "<!-- table: genssky -->\n", "<!-- end table -->"
        a = doc.index(start) + len(start)
        b = doc.index(end, a)
        doc = doc[:a] + text + doc[b:]
        tmp = args.write + ".tmp"
        with open(tmp, "w") as f:
            f.write(doc)
        os.replace(tmp, args.write)


if __name__ == "__main__":
    main()
