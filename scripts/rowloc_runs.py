"""Simulator runs for the sweep scripts (seed-sweep, tune-noise): one seed simulated, replayed and
evaluated with the `rowloc` command, and the seed-range argument they share.

A failing command ends the script with exit status 1 and the command's own output (rowloc's error
names the file and the field); a bad seed range is an argparse error (exit status 2).
"""
import argparse
import json
import os
import re
import subprocess
import sys


def parse_seeds(text):
    """'N' or 'N-M' (inclusive) as a list of seeds."""
    match = re.fullmatch(r"(\d+)(?:-(\d+))?", text)
    if not match:
        raise argparse.ArgumentTypeError(f"seeds must be N or N-M (e.g. 1-12), got '{text}'")
    first = int(match.group(1))
    last = int(match.group(2) or first)
    if last < first:
        raise argparse.ArgumentTypeError(f"seeds {text}: the range is empty")
    return list(range(first, last + 1))


def run(command, tool):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.stderr.write(f"{tool}: {' '.join(command)} failed ({result.returncode}):\n"
                         f"{result.stdout}{result.stderr}")
        sys.exit(1)


def effective_filter(rowloc, filter_path, tool):
    """Every value a filter file loads to (`rowloc config show --filter FILE`; the built-in defaults
    with filter_path None), as a dict: filter files are overlays on the defaults and may extend
    another file, so their own JSON lists only part of the values."""
    command = [rowloc, "config", "show"] + (["--filter", filter_path] if filter_path else [])
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.stderr.write(f"{tool}: {' '.join(command)} failed ({result.returncode}):\n{result.stderr}")
        sys.exit(1)
    return json.loads(result.stdout)


def overlay_on(defaults, config):
    """The keys of config whose values differ from defaults (nested objects compared key by key):
    what a filter file states as an overlay on the defaults."""
    changed = {}
    for key, value in config.items():
        if isinstance(value, dict) and isinstance(defaults.get(key), dict):
            inner = overlay_on(defaults[key], value)
            if inner:
                changed[key] = inner
        elif key not in defaults or defaults[key] != value or type(defaults[key]) is not type(value):
            changed[key] = value
    return changed


def simulate(rowloc, scenario, seed, run_dir, tool):
    """`rowloc simulate SCENARIO --seed N` into run_dir (sensors.ndjson, truth.ndjson)."""
    run([rowloc, "simulate", scenario, "-o", run_dir, "--seed", str(seed)], tool)


def row_map_of(run_dir, scenario, tool):
    """The row map a simulated run wrote (row-map.geojson, for --with-map); ends the script when the
    scenario has no world and so no map."""
    row_map = os.path.join(run_dir, "row-map.geojson")
    if not os.path.isfile(row_map):
        sys.stderr.write(f"{tool}: --with-map: {scenario} writes no row map (a scenario without a world)\n")
        sys.exit(1)
    return row_map


def replay_and_evaluate(rowloc, run_dir, vehicle, filter_path, skip, out_dir, tool, row_map=None):
    """`rowloc replay` of run_dir's log with the vehicle, filter and skipped sensors (and the row
    map, for the map-aided update), then `rowloc evaluate --clip-to-truth` (with the map: along and
    across the rows) into out_dir; returns its report.json (docs/validation.md)."""
    os.makedirs(out_dir, exist_ok=True)
    estimates = os.path.join(out_dir, "estimates.ndjson")
    skips = [a for sensor in skip for a in ("--skip", sensor)]
    map_args = ["--map", row_map] if row_map else []
    run([rowloc, "replay", os.path.join(run_dir, "sensors.ndjson"), "--vehicle", vehicle, "--filter", filter_path,
         *skips, *map_args, "-o", estimates], tool)
    report_dir = os.path.join(out_dir, "report")
    run([rowloc, "evaluate", "--clip-to-truth", os.path.join(run_dir, "truth.ndjson"), estimates, *map_args,
         "--no-plots", "-o", report_dir], tool)
    with open(os.path.join(report_dir, "report.json")) as f:
        return json.load(f)


def sensor_innovations(report, sensor):
    """One sensor's entry of a report's `innovations`, or None when it has no updates."""
    return next((s for s in report.get("innovations", []) if s["sensor"] == sensor), None)


def sensor_nis(report, sensor):
    """The NIS summary of one sensor's updates in a report, or None when it has no updates."""
    entry = sensor_innovations(report, sensor)
    return entry["nis"] if entry else None


def sensor_whiteness(report, sensor):
    """The fraction of one sensor's whiteness lags inside their band, or None when it was not computed
    (no updates, or too few for one lag)."""
    whiteness = (sensor_innovations(report, sensor) or {}).get("whiteness") or {}
    return None if whiteness.get("not_computed") else whiteness.get("fraction_inside")


def check_inputs(parser, paths, rowloc):
    for path in paths:
        if not os.path.isfile(path):
            parser.error(f"no such file: {path}")
    if not os.access(rowloc, os.X_OK):
        parser.error(f"{rowloc} is not an executable: build first, or name it with --rowloc")
