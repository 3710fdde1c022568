#!/usr/bin/env python3
"""Reruns every comparison of docs/accuracy.md and rewrites its tables in place.

Each table in docs/accuracy.md sits between two markers:

    <!-- table: ID -->
    | group | rows | ... |
    <!-- end table -->

and this script knows, for every ID, the `atmo compare` command(s) that produce it (the same
commands the page shows). It runs them with `--markdown` / `--json` into a work folder and
replaces what is between the markers; everything else on the page is left alone.

    scripts/accuracy_tables.py                       # every table (tens of minutes on 2 cores)
    scripts/accuracy_tables.py --only hillaire-sky-view hillaire-ms-directions
    scripts/accuracy_tables.py --list                # the IDs and their commands
    scripts/accuracy_tables.py --dry-run             # print the commands, run nothing

Options: --atmo PATH (default build/apps/atmo/atmo), --doc PATH (default docs/accuracy.md),
--work DIR (default a temporary folder; the CSV/JSON/Markdown of every run are kept there),
--reuse-samples (read the references sampled into --work by an earlier run: several tables compare
against one `atmo sample --model reference` CSV each, SAMPLED_REFERENCES).
Only the Python standard library is used. The page is written atomically (temporary file, then
rename), and only after every requested comparison succeeded.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

REFERENCE = ["--against", "reference", "--against-option", "samples=16384", "--seed", "1"]

# ID -> the compare arguments (a table straight from --markdown).
MARKDOWN_TABLES = {
    "hillaire-ms-directions": ["--model", "hillaire", "--option", "multiple_scattering_directions=2",
                               "--against", "hillaire"],
    "hillaire-sky-view": ["--model", "hillaire", "--against", "hillaire", "--against-option", "sky_view=off"],
    "hillaire-reference-earth": ["--model", "hillaire"] + REFERENCE,
    "hillaire-reference-earth-no-ozone": ["--model", "hillaire", "--config", "{no_ozone}"] + REFERENCE,
    "hillaire-reference-twilight": ["--model", "hillaire", "--grid", "twilight"] + REFERENCE,
    "hillaire-reference-space": ["--model", "hillaire", "--grid", "space"] + REFERENCE,
    "simple-reference": ["--model", "simple", "--preset", "simple"] + REFERENCE,
    "elek-ground-off": ["--model", "elek", "--config", "{albedo}", "--option", "ground=off",
                        "--grid", "docs/data/elek_ground_grid.csv"] + REFERENCE,
    "elek-ground-on": ["--model", "elek", "--config", "{albedo}", "--option", "ground=on",
                       "--grid", "docs/data/elek_ground_grid.csv"] + REFERENCE,
    "elek-reference-earth": ["--model", "elek"] + REFERENCE,
    "source4d-reference-grid": ["--model", "source4d", "--against-samples", "{samples:source4d_grid}"],
    "hillaire-reference-source4d-grid": ["--model", "hillaire", "--against-samples", "{samples:source4d_grid}"],
    # Against a reference sampled once ({samples:ID}, SAMPLED_REFERENCES below) for several models.
    "source4d-reference-twilight": ["--model", "source4d", "--against-samples", "{samples:twilight}"],
    "hillaire-reference-twilight-1pc": ["--model", "hillaire", "--against-samples", "{samples:twilight}"],
    "hillaire-converged-reference-twilight-1pc": [
        "--model", "hillaire", "--option", "multiple_scattering_lut=256x128", "--option",
        "multiple_scattering_directions=1024", "--option", "multiple_scattering_samples=100",
        "--against-samples", "{samples:twilight}"],
    "source4d-reference-deep-twilight": ["--model", "source4d", "--against-samples", "{samples:deep_twilight}"],
    "hillaire-reference-deep-twilight": ["--model", "hillaire", "--against-samples", "{samples:deep_twilight}"],
    "source4d-reference-night": ["--model", "source4d", "--against-samples", "{samples:night}"],
    "hillaire-reference-night": ["--model", "hillaire", "--against-samples", "{samples:night}"],
    "source4d-reference-altitudes": ["--model", "source4d", "--against-samples", "{samples:altitudes}"],
    "hillaire-reference-altitudes": ["--model", "hillaire", "--against-samples", "{samples:altitudes}"],
    "source4d-reference-hazy": ["--model", "source4d", "--config", "{hazy}", "--against-samples", "{samples:hazy}"],
    "hillaire-reference-hazy": ["--model", "hillaire", "--config", "{hazy}", "--against-samples", "{samples:hazy}"],
    # The sunset horizon (docs/data/sunset_grid.csv): the default gathered orders, Hillaire 2020's
    # series alone, and source4d as a second truth, against one reference.
    "hillaire-reference-sunset": ["--model", "hillaire", "--against-samples", "{samples:sunset}"],
    "hillaire-series-reference-sunset": ["--model", "hillaire", "--option", "multiple_scattering_orders=1",
                                         "--against-samples", "{samples:sunset}"],
    "source4d-reference-sunset": ["--model", "source4d", "--against-samples", "{samples:sunset}"],
    "source4d-reference-albedo-0": ["--model", "source4d", "--config", "{albedo_0}",
                                    "--against-samples", "{samples:albedo_0}"],
    "source4d-reference-albedo-1": ["--model", "source4d", "--config", "{albedo_1}",
                                    "--against-samples", "{samples:albedo_1}"],
}

# ID -> the `atmo sample --model reference` arguments of a reference that several tables read
# (`--against-samples`); each is sampled once per run of this script, when a selected table needs it.
SAMPLED_REFERENCES = {
    # 2^18 paths, the vertex estimator: about 0.3 % relative standard error with the sun up, for models near 0.5 %.
    "source4d_grid": ["--grid", "docs/data/source4d_grid.csv", "--option", "samples=262144", "--option",
                      "nee=vertex", "--seed", "7"],
    # Sun 92 and 95 degrees to 1 % relative standard error per direction (the twilight estimator),
    # capped at 2^22 paths (the doubling also waits for max_vov, which a heavy tail can hold off).
    "twilight": ["--grid", "docs/data/source4d_twilight_grid.csv", "--target-rel-error", "0.01",
                 "--option", "max_samples=4194304", "--seed", "7"],
    # Sun 98 and 100 degrees: 1 % per direction, capped at 2^22 paths.
    "deep_twilight": ["--grid", "docs/data/source4d_deep_twilight_grid.csv", "--target-rel-error", "0.01",
                      "--option", "max_samples=4194304", "--seed", "7"],
    # Sun 104 and 108 degrees: 1 % per direction (capped at 2^22 paths, which no direction needs).
    "night": ["--grid", "docs/data/source4d_night_grid.csv", "--target-rel-error", "0.01",
              "--option", "max_samples=4194304", "--seed", "7"],
    # 2^16 paths: about 0.5 % with the sun up.
    "altitudes": ["--grid", "docs/data/source4d_altitude_grid.csv", "--samples", "65536", "--seed", "7"],
    "hazy": ["--config", "{hazy}", "--grid", "docs/data/source4d_media_grid.csv", "--samples", "65536",
             "--seed", "7"],
    # The sun on the horizon, views 30-89.5 degrees from the zenith, 0-180 degrees from the sun:
    # 2^16 paths, about 0.5-1 % there.
    "sunset": ["--grid", "docs/data/sunset_grid.csv", "--samples", "65536", "--seed", "7"],
    "albedo_0": ["--config", "{albedo_0}", "--grid", "docs/data/source4d_media_grid.csv", "--samples", "65536",
                 "--seed", "7"],
    "albedo_1": ["--config", "{albedo_1}", "--grid", "docs/data/source4d_media_grid.csv", "--samples", "65536",
                 "--seed", "7"],
}

# The elek table: one row per order count K, selected columns of each run's JSON summary.
ELEK_ORDERS = [1, 2, 4]
ELEK_ARGS = ["--model", "elek", "--preset", "atmosphere-plus", "--option", "orders={k}"] + REFERENCE


def percent(x):
    """The compare tool's percentage format: 3 significant digits."""
    if x is None:
        return "-"
    v = 100.0 * x
    if v == 0.0:
        return "0%"
    if abs(v) >= 0.01:
        return "%.3g%%" % v
    return "%.2g%%" % v


def band(summary, key):
    for entry in summary["sun_zenith_bands"]:
        if entry["band"] == key:
            return entry
    return None


def elek_table(summaries):
    lines = ["| K | sun up: median abs(e) | p95 abs(e) | max abs(e) | mean e | twilight: median abs(e) | "
             "median abs(z), sun up |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for k, summary in zip(ELEK_ORDERS, summaries):
        up = band(summary, "sun_up") or {}
        twilight = band(summary, "twilight") or {}
        z = up.get("error_in_stderr", {}).get("median_abs")
        lines.append("| %d | %s | %s | %s | %s | %s | %s |" % (
            k, percent(up.get("median_abs")), percent(up.get("p95_abs")), percent(up.get("max_abs")),
            percent(up.get("mean")), percent(twilight.get("median_abs")), "-" if z is None else "%.3g" % z))
    return "\n".join(lines) + "\n"


def no_ozone_config(atmo, work):
    """The earth preset with ozone.absorption_per_m set to 0, as the page describes it."""
    dump = subprocess.run([atmo, "presets", "--dump", "earth"], check=True, capture_output=True, text=True).stdout
    preset = json.loads(dump)
    preset["ozone"]["absorption_per_m"] = [0.0 for _ in preset["ozone"]["absorption_per_m"]] \
        if isinstance(preset["ozone"]["absorption_per_m"], list) else 0.0
    path = os.path.join(work, "earth_no_ozone.json")
    with open(path, "w") as f:
        json.dump(preset, f, indent=2)
    return path


def albedo_config(atmo, work):
    """The atmosphere-plus preset with a ground albedo of 0.3, as the page describes it."""
    dump = subprocess.run([atmo, "presets", "--dump", "atmosphere-plus"], check=True, capture_output=True,
                          text=True).stdout
    preset = json.loads(dump)
    preset["ground_albedo"] = [0.3 for _ in preset["ground_albedo"]]
    path = os.path.join(work, "atmosphere_plus_albedo_0.3.json")
    with open(path, "w") as f:
        json.dump(preset, f, indent=2)
    return path


def earth_variant(atmo, work, name, change):
    """The earth preset with `change(preset)` applied, written to WORK/NAME.json."""
    dump = subprocess.run([atmo, "presets", "--dump", "earth"], check=True, capture_output=True, text=True).stdout
    preset = json.loads(dump)
    change(preset)
    path = os.path.join(work, name + ".json")
    with open(path, "w") as f:
        json.dump(preset, f, indent=2)
    return path


def hazy(preset):
    """Mie x 10: ten times the aerosol's scattering and absorption (its density)."""
    for key in ("scattering_per_m", "absorption_per_m"):
        preset["mie"][key] = [10.0 * x for x in preset["mie"][key]]


def albedo(value):
    def change(preset):
        preset["ground_albedo"] = [value for _ in preset["ground_albedo"]]
    return change


def sample_reference(atmo, reference_id, work, dry_run, substitutions, reuse):
    """Runs `atmo sample --model reference` for SAMPLED_REFERENCES[reference_id] once; its CSV path.
    With `reuse`, a WORK/reference-ID.csv of an earlier run is read instead."""
    path = os.path.join(work, "reference-%s.csv" % reference_id)
    if reuse and os.path.exists(path):
        print("# reusing %s" % path, flush=True)
        return path
    args = [a.format(**substitutions) for a in SAMPLED_REFERENCES[reference_id]]
    command = [atmo, "sample", "--model", "reference"] + args + ["--out", path]
    print("$ " + " ".join(command), flush=True)
    if not dry_run:
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return path


def run_compare(atmo, args, work, name, dry_run, substitutions, reuse=False):
    for reference_id in sorted({a[len("{samples:"):-1] for a in args if a.startswith("{samples:")}):
        key = "samples:" + reference_id
        if key not in substitutions:
            substitutions[key] = sample_reference(atmo, reference_id, work, dry_run, substitutions, reuse)
    args = [substitutions[a[1:-1]] if a.startswith("{samples:") else a.format(**substitutions) for a in args]
    markdown = os.path.join(work, name + ".md")
    summary = os.path.join(work, name + ".json")
    command = [atmo, "compare"] + args + ["--markdown", markdown, "--json", summary,
                                          "--csv", os.path.join(work, name + ".csv")]
    print("$ " + " ".join(command), flush=True)
    if dry_run:
        return None, None
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    with open(markdown) as f:
        table = f.read()
    with open(summary) as f:
        return table, json.load(f)


def replace_block(page, table_id, body):
    pattern = re.compile(r"(<!-- table: %s -->\n)(.*?)(<!-- end table -->)" % re.escape(table_id), re.S)
    if not pattern.search(page):
        raise SystemExit("accuracy_tables: %s has no block <!-- table: %s --> ... <!-- end table -->"
                         % ("the page", table_id))
    return pattern.sub(lambda m: m.group(1) + body + m.group(3), page, count=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmo", default="build/apps/atmo/atmo")
    parser.add_argument("--doc", default="docs/accuracy.md")
    parser.add_argument("--work", default=None)
    parser.add_argument("--only", nargs="+", default=None)
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--dry-run", action="store_true")
    parser.add_argument("--reuse-samples", action="store_true",
                        help="read the sampled references (reference-ID.csv) already in --work instead of sampling")
    options = parser.parse_args()

    ids = list(MARKDOWN_TABLES) + ["elek-reference-orders"]
    if options.list:
        for table_id in MARKDOWN_TABLES:
            print("%-36s atmo compare %s" % (table_id, " ".join(MARKDOWN_TABLES[table_id])))
        print("%-36s atmo compare %s  (K = %s)" % ("elek-reference-orders", " ".join(ELEK_ARGS),
                                                  ", ".join(map(str, ELEK_ORDERS))))
        for reference_id, args in SAMPLED_REFERENCES.items():
            print("%-36s atmo sample --model reference %s" % ("{samples:%s}" % reference_id, " ".join(args)))
        return 0
    selected = options.only or ids
    unknown = [i for i in selected if i not in ids]
    if unknown:
        raise SystemExit("accuracy_tables: unknown table %s (see --list)" % ", ".join(unknown))
    if not options.dry_run and not os.access(options.atmo, os.X_OK):
        raise SystemExit("accuracy_tables: %s is not an executable atmo (build it, or pass --atmo)" % options.atmo)
    with open(options.doc) as f:
        page = f.read()
    for table_id in selected:  # every block must exist before any work
        replace_block(page, table_id, "")

    work = options.work or tempfile.mkdtemp(prefix="atmo-accuracy-")
    os.makedirs(work, exist_ok=True)
    substitutions = {}
    if "hillaire-reference-earth-no-ozone" in selected and not options.dry_run:
        substitutions["no_ozone"] = no_ozone_config(options.atmo, work)
    else:
        substitutions["no_ozone"] = os.path.join(work, "earth_no_ozone.json")
    if any(i.startswith("elek-ground") for i in selected) and not options.dry_run:
        substitutions["albedo"] = albedo_config(options.atmo, work)
    else:
        substitutions["albedo"] = os.path.join(work, "atmosphere_plus_albedo_0.3.json")

    for name, change in (("hazy", hazy), ("albedo_0", albedo(0.0)), ("albedo_1", albedo(1.0))):
        path = os.path.join(work, "earth_%s.json" % name)
        substitutions[name] = path if options.dry_run else earth_variant(options.atmo, work, "earth_" + name, change)

    for table_id in selected:
        if table_id == "elek-reference-orders":
            summaries = []
            for k in ELEK_ORDERS:
                args = [a.replace("{k}", str(k)) for a in ELEK_ARGS]
                _, summary = run_compare(options.atmo, args, work, "%s-%d" % (table_id, k), options.dry_run,
                                         substitutions)
                summaries.append(summary)
            if not options.dry_run:
                page = replace_block(page, table_id, elek_table(summaries))
        else:
            table, _ = run_compare(options.atmo, MARKDOWN_TABLES[table_id], work, table_id, options.dry_run,
                                   substitutions, options.reuse_samples)
            if not options.dry_run:
                page = replace_block(page, table_id, table)
    if options.dry_run:
        return 0
    temporary = options.doc + ".tmp"
    with open(temporary, "w") as f:
        f.write(page)
    os.replace(temporary, options.doc)
    print("accuracy_tables: rewrote %d table(s) of %s; runs kept in %s" % (len(selected), options.doc, work))
    return 0


if __name__ == "__main__":
    sys.exit(main())
