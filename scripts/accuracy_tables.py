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
--work DIR (default a temporary folder; the CSV/JSON/Markdown of every run are kept there).
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
# 2^18 paths: a relative standard error of about 0.3 % with the sun up, for models near 0.5 %.
PRECISE_REFERENCE = ["--against", "reference", "--against-option", "samples=262144", "--against-option", "nee=vertex",
                     "--seed", "7"]

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
    "source4d-reference-grid": ["--model", "source4d", "--grid", "docs/data/source4d_grid.csv"] + PRECISE_REFERENCE,
    "hillaire-reference-source4d-grid": ["--model", "hillaire", "--grid", "docs/data/source4d_grid.csv"]
                                        + PRECISE_REFERENCE,
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


def run_compare(atmo, args, work, name, dry_run, substitutions):
    args = [a.format(**substitutions) for a in args]
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
    options = parser.parse_args()

    ids = list(MARKDOWN_TABLES) + ["elek-reference-orders"]
    if options.list:
        for table_id in MARKDOWN_TABLES:
            print("%-36s atmo compare %s" % (table_id, " ".join(MARKDOWN_TABLES[table_id])))
        print("%-36s atmo compare %s  (K = %s)" % ("elek-reference-orders", " ".join(ELEK_ARGS),
                                                  ", ".join(map(str, ELEK_ORDERS))))
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
                                   substitutions)
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
