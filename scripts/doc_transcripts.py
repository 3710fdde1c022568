#!/usr/bin/env python3
"""Reruns the example transcripts of the docs and rewrites their outputs in place.

A transcript is a ```sh block whose lines start with `$ ` (the format tests/docs_test.cc checks):
`$ cat FILE` followed by lines writes them to FILE; `$ atmo ...` runs the build's atmo and the
lines after it, up to the next `$ `, are what it printed (standard output, then standard error).
The commands of a file run in order in one fresh folder, as the test runs them.

    scripts/doc_transcripts.py                 # rewrite the outputs in README.md and docs/**/*.md
    scripts/doc_transcripts.py --check         # print the lines that drifted; exit 1 if any did
    scripts/doc_transcripts.py --doc docs/cli.md --atmo build/apps/atmo/atmo
    scripts/doc_transcripts.py --doc docs/performance.md --measured-only 'aerosol-phase|us-standard'
    scripts/doc_transcripts.py --timings       # list the timings that nothing regenerates; exit 1 if any

Timings (a number followed by ` s` or ` ms`) are rewritten with what this run measured; the test
accepts any number there. The machine, its cores and its load are printed first.

A measured block holds the whole output of a command whose numbers are measurements (timings):

    <!-- measured: atmo bench --repeat 10 -->
    ```text
    (the output)
    ```
    Measured 2026-12-04 18:40 UTC on ... (the machine, its cores, its load before the run).
    <!-- end measured -->

A record block keeps a dated measurement of an earlier build (a comparison before and after a
change, a run that took an hour): it is history, not rerun, and says so where a reader sees it:

    <!-- record: 2026-12-04 -->
    *Record of 2026-12-04, not rerun since.* (the text, with its figures)
    <!-- end record -->

Every other timing of the manual (a number followed by ms, µs, s, min or fps) must be in a measured
block, a generated table (`<!-- table: NAME -->`), a transcript, or be a bound (after ≤, ≥, <, >) or
a setting (a line that ends with `<!-- not measured: WHY -->`): `--timings` lists those that are
not, and tests/docs_test.cc (`EveryTimingIsRegeneratedOrARecord`) fails on them.

This script reruns the command, replaces the output and writes the stamp line (`--no-measured`
leaves measured blocks alone: run them on an idle machine). tests/docs_test.cc reruns each
command and checks the output's layout, every number masked.
Only the Python standard library is used; a file is written atomically (temporary file, then
rename), and only when every command of it succeeded.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

TIMING = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?= m?s\b)")
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
MEASURED = re.compile(r"^<!-- measured: (.+) -->$")
# A timing anywhere in the manual's prose, and the bounds that are not measurements (≤ 5 ms).
ANY_TIMING = re.compile(r"\d\s?(?:ms|µs|s|min|fps)\b")
BOUND = re.compile(r"[≤≥<>]\s?~?\d+(?:[.,]\d+)?\s?(?:ms|µs|s|min|fps)\b")
RECORD = re.compile(r"^<!-- record: (\d{4}-\d{2}-\d{2})\b.* -->$")
BLOCK_END = {"measured": "<!-- end measured -->", "table": "<!-- end table -->", "record": "<!-- end record -->"}


def machine():
    """The machine a measurement ran on: system, CPU model, cores, and the load before the run."""
    uname = subprocess.run(["uname", "-srm"], capture_output=True, text=True).stdout.strip()
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{uname}, {cpu}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}"


def layout(line):
    """A line with every number masked and runs of spaces (columns padded to numbers) as one."""
    return re.sub(" +", " ", NUMBER.sub("N", line))


def measured(lines, atmo, check, path, only=None):
    """Reruns the measured blocks of `lines` (those whose command `only`, a regular expression, finds
    when it is given); the new lines and the number of blocks whose layout drifted."""
    out = []
    drift = 0
    i = 0
    while i < len(lines):
        match = MEASURED.match(lines[i].strip())
        if not match:
            out.append(lines[i])
            i += 1
            continue
        end = i + 1
        while end < len(lines) and lines[end].strip() != "<!-- end measured -->":
            end += 1
        if end == len(lines):
            sys.exit(f"{path}: `{lines[i].strip()}` has no `<!-- end measured -->`")
        body = lines[i + 1:end]
        if only is not None and not re.search(only, match.group(1)):
            out.extend(lines[i:end + 1])
            i = end + 1
            continue
        old = body[body.index("```text") + 1:body.index("```")] if "```text" in body and "```" in body else []
        stamp = machine()
        with tempfile.TemporaryDirectory(prefix="atmo-measured-") as folder:
            code, new = run(atmo, folder, match.group(1))
        if code != 0:
            sys.exit(f"{path}: `{match.group(1)}` exited with {code}:\n" + "\n".join(new))
        if [layout(x) for x in old] != [layout(x) for x in new]:
            drift += 1
            print(f"{path}: the layout of `{match.group(1)}` drifted:\n  docs: " + "\n        ".join(old) +
                  "\n  now:  " + "\n        ".join(new))
        out.append(lines[i])
        if check:
            out.extend(body)
        else:
            when = subprocess.run(["date", "-u", "+%Y-%m-%d %H:%M UTC"], capture_output=True, text=True).stdout.strip()
            out.extend(["```text"] + new + ["```", f"Measured {when} on {stamp}."])
        out.append(lines[end])
        i = end + 1
    return out, drift


def transcripts(lines):
    """Yields (start, end) line ranges of the ```sh blocks that are transcripts."""
    start = None
    for i, raw in enumerate(lines):
        line = raw.strip()
        if start is None and line == "```sh":
            start = i + 1
        elif start is not None and line == "```":
            if start < i and lines[start].startswith("$ "):
                yield start, i
            start = None


def untracked_timings(path):
    """The (line number, line) of each timing of `path` that nothing regenerates (see above)."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    found = []
    closing = None
    date = None  # a record's date, until its visible text shows it
    sh = False
    for n, raw in enumerate(lines, 1):
        line = raw.strip()
        if closing is not None:
            if date and date in line:
                date = None
            if line == closing:
                if date:
                    found.append((n, raw + f"   <- the record's text does not show its date {date}"))
                closing = date = None
            continue
        for kind, end in BLOCK_END.items():
            if line.startswith(f"<!-- {kind}: "):
                closing = end
        if line.startswith("<!-- record: "):
            match = RECORD.match(line)
            if match:
                date = match.group(1)
            else:
                found.append((n, raw + "   <- a record needs its date: <!-- record: YYYY-MM-DD -->"))
        if closing is not None:
            continue
        if line.startswith("```sh"):
            sh = True
            continue
        if sh:
            sh = line != "```"
            if line.startswith("$ ") or sh:
                continue
        if "<!-- not measured: " in line:
            continue
        if ANY_TIMING.search(BOUND.sub("", raw)):
            found.append((n, raw))
    return found


def run(atmo, folder, command):
    if command == "atmo" or command.startswith("atmo "):
        command = "'" + atmo + "'" + command[4:]
    result = subprocess.run(["bash", "-c", "timeout 120 " + command], cwd=folder, capture_output=True, text=True)
    return result.returncode, (result.stdout + result.stderr).splitlines()


def same_but_timings(old, new):
    return TIMING.sub("T", old) == TIMING.sub("T", new)


def rewrite(path, atmo, check, with_measured, only=None):
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    out = []
    drift = 0
    if with_measured:
        lines, drift = measured(lines, atmo, check, path, only)
    cursor = 0
    with tempfile.TemporaryDirectory(prefix="atmo-transcripts-") as folder:
        for start, end in transcripts(lines):
            out.extend(lines[cursor:start])
            i = start
            while i < end:
                command = lines[i][2:]
                j = i + 1
                while j < end and not lines[j].startswith("$ "):
                    j += 1
                old = lines[i + 1:j]
                out.append(lines[i])
                if command.startswith("cat "):
                    with open(os.path.join(folder, command[4:]), "w", encoding="utf-8") as f:
                        f.write("".join(line + "\n" for line in old))
                    out.extend(old)
                elif command == "atmo" or command.startswith("atmo "):
                    code, new = run(atmo, folder, command)
                    expected_failure = any("error" in line for line in old)
                    if code != 0 and not expected_failure:
                        sys.exit(f"{path}: `{command}` exited with {code}:\n" + "\n".join(new))
                    for k in range(max(len(old), len(new))):
                        a = old[k] if k < len(old) else "<none>"
                        b = new[k] if k < len(new) else "<none>"
                        if not same_but_timings(a, b):
                            drift += 1
                            print(f"{path}: $ {command}\n  docs: {a}\n  now:  {b}")
                    out.extend(new)
                else:
                    out.extend(old)  # not run here (the test leaves such lines alone too)
                i = j
            cursor = end
    out.extend(lines[cursor:])
    with open(path, encoding="utf-8") as f:
        original = f.read().split("\n")
    if not check and out != original:
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".transcripts-")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write("\n".join(out))
        os.replace(tmp, path)
    return drift


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--atmo", default="build/apps/atmo/atmo")
    parser.add_argument("--doc", action="append",
                        help="a Markdown file (repeatable; default README.md and every page under docs/)")
    parser.add_argument("--check", action="store_true", help="only report drift; exit 1 if any")
    parser.add_argument("--no-measured", action="store_true", help="leave the measured blocks alone")
    parser.add_argument("--measured-only", metavar="REGEX",
                        help="rerun only the measured blocks whose command matches REGEX")
    parser.add_argument("--timings", action="store_true",
                        help="list the timings outside measured blocks, tables, transcripts and records")
    args = parser.parse_args()
    docs = args.doc or ["README.md"] + sorted(
        os.path.join(root, name) for root, _, names in os.walk("docs") for name in names if name.endswith(".md"))
    if args.timings:
        found = [(doc, n, line) for doc in docs for n, line in untracked_timings(doc)]
        for doc, n, line in found:
            print(f"{doc}:{n}: {line}")
        print(f"doc_transcripts: {len(found)} timing line(s) that nothing regenerates")
        sys.exit(1 if found else 0)
    atmo = os.path.abspath(args.atmo)
    if not os.access(atmo, os.X_OK):
        sys.exit(f"doc_transcripts: no atmo binary at {args.atmo} (build first, or pass --atmo)")
    print(f"doc_transcripts: {machine()}")
    drift = sum(rewrite(doc, atmo, args.check, not args.no_measured, args.measured_only) for doc in docs)
    print(f"doc_transcripts: {drift} drifted line(s)" + ("" if args.check else ", rewritten"))
    sys.exit(1 if args.check and drift else 0)


if __name__ == "__main__":
    main()
