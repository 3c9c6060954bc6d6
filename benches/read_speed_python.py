"""Read speed of ctcal's Python reader against faery and evlib (both on PyPI).

Run from the project root, in a venv that has ctcal, faery and evlib:

    /tmp/wsvenv/bin/python benches/read_speed_python.py [--reps 5] [--data DIR]

For every shared recording that at least two of the three libraries can read, each library
reads the whole file into memory once as a warm-up, then REPS more times, timed in-process
(the libraries take turns inside each repetition, so drifting machine load hits all alike).
Import times are measured separately in fresh subprocesses. Every timed run is at nice 10
(the script renices itself, and its subprocesses inherit that). Prints Markdown.

What "read" means per library (each library's documented way to get all events in memory):
- ctcal: ``ctcal.read(path)`` -> NumPy structured array (t int64 us, x, y uint16, p uint8);
- faery: ``faery.events_stream_from_file(path, ...).to_array()`` -> NumPy structured array
  (t uint64 us, x, y uint16, on bool); Gen3 EVT2 headers carry no geometry, so those files
  get ``dimensions_fallback=(640, 480)``;
- evlib: ``evlib.load_events(path).collect()`` -> Polars DataFrame (x, y int16, t Duration[us],
  polarity int8 -1/1); its default ``sort=True`` sorts by t after decoding, so the run with
  ``sort=False`` is timed as well.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

NICE = 10
FILES = [
    "evk4_faery_evt3.raw",
    "evk4_faery_gen4.dat",
    "gen3_faery_evt2.raw",
    "gen3_expelliarmus_evt2.raw",
    "davis346_faery.aedat4",
    "dvxplorer_tonic.aedat4",
]
LIBS = ["ctcal", "faery", "evlib", "evlib sort=False"]


def renice() -> None:
    cur = os.nice(0)
    if cur < NICE:
        os.nice(NICE - cur)


def uptime() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "load average: " + ", ".join(f"{v:.2f}" for v in os.getloadavg())


# ---------------------------------------------------------------- readers (in-process)


def make_readers():
    import numpy as np

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        import ctcal
        import evlib
        import faery

    def r_ctcal(path: str):
        return ctcal.read(path)

    def r_faery(path: str):
        kw = {}
        if "gen3" in Path(path).name:
            kw["dimensions_fallback"] = (640, 480)
        return faery.events_stream_from_file(path, **kw).to_array()

    def r_evlib(path: str):
        return evlib.load_events(path).collect()

    def r_evlib_nosort(path: str):
        return evlib.load_events(path, sort=False).collect()

    def to_columns(lib: str, res):
        """(t int64, x int64, y int64, p 0/1 int64) NumPy columns, in the library's order."""
        if lib.startswith("evlib"):
            t = res["t"].dt.total_microseconds().to_numpy().astype(np.int64)
            x = res["x"].to_numpy().astype(np.int64)
            y = res["y"].to_numpy().astype(np.int64)
            p = (res["polarity"].to_numpy() > 0).astype(np.int64)
        else:
            t = res["t"].astype(np.int64)
            x = res["x"].astype(np.int64)
            y = res["y"].astype(np.int64)
            p = (res["p"] if lib == "ctcal" else res["on"]).astype(np.int64)
            p = (p > 0).astype(np.int64)
        return t, x, y, p

    readers = {
        "ctcal": r_ctcal,
        "faery": r_faery,
        "evlib": r_evlib,
        "evlib sort=False": r_evlib_nosort,
    }
    return readers, to_columns


def digest(cols, order: str) -> str:
    import numpy as np

    t, x, y, p = cols
    if order == "sorted":  # as a multiset: sort by (t, x, y, p)
        idx = np.lexsort((p, y, x, t))
        t, x, y, p = t[idx], x[idx], y[idx], p[idx]
    h = hashlib.sha256()
    for c in (t, x, y, p):
        h.update(np.ascontiguousarray(c).tobytes())
    return h.hexdigest()[:16]


# ---------------------------------------------------------------- import times (subprocess)


def import_times(reps: int) -> list[dict]:
    py = sys.executable
    rows = []
    for mod in ["(none: python -c pass)", "numpy", "ctcal", "faery", "evlib"]:
        code = "pass" if mod.startswith("(") else f"import {mod}"
        walls, selfs = [], []
        for _ in range(reps):
            t0 = time.perf_counter()
            subprocess.run([py, "-c", code], check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
            if not mod.startswith("("):
                out = subprocess.run(
                    [py, "-X", "importtime", "-c", code], check=True, capture_output=True, text=True
                ).stderr
                cum = None
                for line in out.splitlines():
                    m = re.match(r"import time:\s+(\d+)\s+\|\s+(\d+)\s+\|\s?(\s*)(\S+)$", line)
                    if m and m.group(4) == mod and m.group(3) == "":
                        cum = int(m.group(2))
                selfs.append(cum / 1e6 if cum is not None else float("nan"))
        rows.append(
            {
                "module": mod,
                "wall_median": statistics.median(walls),
                "wall_min": min(walls),
                "importtime_median": statistics.median(selfs) if selfs else None,
                "importtime_min": min(selfs) if selfs else None,
            }
        )
    return rows


# ---------------------------------------------------------------- main


def versions() -> dict:
    from importlib import metadata

    v = {"python": platform.python_version()}
    for pkg in ["ctcal", "faery", "evlib", "numpy", "polars"]:
        try:
            v[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            v[pkg] = "not installed"
    return v


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--data", default=None, help="folder of the shared real recordings")
    args = ap.parse_args()
    renice()
    root = Path(__file__).resolve().parent.parent
    data = Path(args.data) if args.data else (root.parent / "shared" / "data" / "real")
    if not data.is_dir():
        data = Path("/work/shared/data/real")
    truth = json.loads((data / "truth.json").read_text())

    load_start = uptime()
    started = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    readers, to_columns = make_readers()

    # Which library reads which file (warm-up read doubles as the correctness check).
    results: dict[str, dict[str, dict]] = {}
    for f in FILES:
        path = str(data / f)
        results[f] = {}
        for lib in LIBS:
            entry: dict = {}
            try:
                res = readers[lib](path)
                cols = to_columns(lib, res)
                t = cols[0]
                entry.update(
                    ok=True,
                    n=int(len(t)),
                    t_first=int(t[0]) if len(t) else None,
                    t_last=int(t[-1]) if len(t) else None,
                    t_min=int(t.min()) if len(t) else None,
                    t_max=int(t.max()) if len(t) else None,
                    sorted=bool((t[1:] >= t[:-1]).all()),
                    on=int(cols[3].sum()),
                    hash_order=digest(cols, "order"),
                    hash_set=digest(cols, "sorted"),
                    times=[],
                    cpu=[],
                )
                del res, cols, t
            except Exception as e:  # noqa: BLE001 - a library that cannot read a file is a result
                entry.update(ok=False, error=f"{type(e).__name__}: {e}")
            results[f][lib] = entry
        n_ok = sum(results[f][lib]["ok"] for lib in ["ctcal", "faery", "evlib"])
        if n_ok < 2:
            results[f]["_skip"] = {"ok": False}

    # Timed reads: libraries take turns inside each repetition.
    for rep in range(args.reps):
        for f in FILES:
            if "_skip" in results[f]:
                continue
            path = str(data / f)
            for lib in LIBS:
                e = results[f][lib]
                if not e["ok"]:
                    continue
                c0 = time.process_time()
                t0 = time.perf_counter()
                res = readers[lib](path)
                dt = time.perf_counter() - t0
                dc = time.process_time() - c0
                assert len(res) == e["n"]
                del res
                e["times"].append(dt)
                e["cpu"].append(dc)

    imports = import_times(args.reps)
    load_end = uptime()

    # ------------------------------------------------------------ report
    v = versions()
    out = []
    out.append(f"Measured {started} on {os.cpu_count()} cores, nice {os.nice(0)}, "
               f"{args.reps} timed reads per cell after one warm-up read.\n")
    out.append(f"- load at start: `{load_start}`")
    out.append(f"- load at end:   `{load_end}`")
    out.append("- versions: " + ", ".join(f"{k} {val}" for k, val in v.items()) + "\n")

    out.append("### Read all events into memory (in-process, warm)\n")
    out.append("| file | events (truth) | library | median s | min s | M events/s (median) "
               "| M events/s (best) | CPU s (median) | vs ctcal (median) |")
    out.append("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    for f in FILES:
        tr = truth[f]["events"]
        ref = results[f]["ctcal"]
        ref_med = statistics.median(ref["times"]) if ref["ok"] and ref["times"] else None
        for lib in LIBS:
            e = results[f][lib]
            if not e["ok"]:
                out.append(f"| {f} | {tr:,} | {lib} | cannot read | | | | | |")
                continue
            if not e["times"]:
                out.append(f"| {f} | {tr:,} | {lib} | not timed (fewer than 2 libraries) | | | | | |")
                continue
            med, mn = statistics.median(e["times"]), min(e["times"])
            cpu = statistics.median(e["cpu"])
            rel = f"{med / ref_med:.2f}x" if ref_med else ""
            out.append(
                f"| {f} | {tr:,} | {lib} | {med:.4f} | {mn:.4f} | {e['n'] / med / 1e6:.1f} "
                f"| {e['n'] / mn / 1e6:.1f} | {cpu:.4f} | {rel} |"
            )

    out.append("\n### Agreement (counts and times from the warm-up read)\n")
    out.append("| file | library | events | = truth | first t (us) | last t (us) | t sorted "
               "| ON events | same (t,x,y,p) list as ctcal |")
    out.append("|---|---|---:|---|---:|---:|---|---:|---|")
    problems = []
    for f in FILES:
        tr = truth[f]
        ref = results[f]["ctcal"]
        for lib in LIBS:
            e = results[f][lib]
            if not e["ok"]:
                out.append(f"| {f} | {lib} | error: `{e['error']}` | | | | | | |")
                continue
            eq_truth = e["n"] == tr["events"]
            if not eq_truth:
                problems.append(f"{f}: {lib} reads {e['n']} events, truth.json says {tr['events']}")
            same = ""
            if lib != "ctcal" and ref["ok"]:
                if e["hash_order"] == ref["hash_order"]:
                    same = "yes, same order"
                elif e["hash_set"] == ref["hash_set"]:
                    same = "same events, different order within equal t"
                else:
                    same = "NO"
                    problems.append(f"{f}: {lib} event list differs from ctcal's")
                for k in ("n", "t_first", "t_last"):
                    if e[k] != ref[k]:
                        problems.append(f"{f}: {lib} {k} = {e[k]}, ctcal {k} = {ref[k]}")
            elif lib == "ctcal":
                same = "(reference)"
            out.append(
                f"| {f} | {lib} | {e['n']:,} | {'yes' if eq_truth else 'NO'} | {e['t_first']} "
                f"| {e['t_last']} | {'yes' if e['sorted'] else 'no'} | {e['on']:,} | {same} |"
            )
        if ref["ok"]:
            tf = round(tr["t_first_s"] * 1e6)
            tl = round(tr["t_last_s"] * 1e6)
            if (ref["t_min"], ref["t_max"]) != (tf, tl):
                problems.append(f"{f}: ctcal t range {ref['t_min']}..{ref['t_max']} us, "
                                f"truth.json {tf}..{tl} us")
            on_truth = round(tr["on_fraction"] * tr["events"])
            if abs(ref["on"] - on_truth) > 1:
                problems.append(f"{f}: ctcal ON events {ref['on']}, truth.json ~{on_truth}")

    out.append("\nDisagreements: " + ("; ".join(problems) if problems else "none."))

    out.append("\n### Import time (fresh `python -c 'import X'` subprocess)\n")
    out.append("| module | wall median s | wall min s | `-X importtime` cumulative median s | min s |")
    out.append("|---|---:|---:|---:|---:|")
    for r in imports:
        it_med = "" if r["importtime_median"] is None else f"{r['importtime_median']:.3f}"
        it_min = "" if r["importtime_min"] is None else f"{r['importtime_min']:.3f}"
        out.append(f"| {r['module']} | {r['wall_median']:.3f} | {r['wall_min']:.3f} | {it_med} | {it_min} |")
    print("\n".join(out))


if __name__ == "__main__":
    main()
