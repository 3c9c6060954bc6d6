"""The Python package answers as the ``ctcal`` command does, on the shared recordings.

The command is ``target/release/ctcal`` of this checkout (``CTCAL_BIN`` overrides it); the
recordings are read in place from ``../shared/data`` (``CTCAL_SHARED_DATA`` overrides it).
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import ctcal

ROOT = Path(__file__).resolve().parents[2]
CLI = Path(os.environ.get("CTCAL_BIN", ROOT / "target" / "release" / "ctcal"))
DATA = Path(os.environ.get("CTCAL_SHARED_DATA", ROOT.parent / "shared" / "data"))
REAL = DATA / "real"

if not DATA.is_dir():
    pytest.skip(f"the shared data are not at {DATA}", allow_module_level=True)
if not CLI.is_file():
    pytest.skip(f"build the command first: cargo build --release ({CLI})", allow_module_level=True)

#: Recordings of every reader the shared data cover.
RECORDINGS = [
    REAL / "ijrr_slider_depth_50k",
    REAL / "davis346_faery.aedat4",
    REAL / "evk4_faery_evt3.raw",
    REAL / "evk4_faery_gen4.dat",
    REAL / "gen3_faery_evt2.raw",
    DATA / "h5" / "e_ct060_event_utils.h5",
]


def cli(*args: str) -> dict:
    """The JSON the command writes to stdout."""
    done = subprocess.run(
        [str(CLI), *args, "--json", "-", "--quiet"], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


def cli_error(*args: str) -> str:
    """The command's error message (stderr without its `error: ` prefix)."""
    done = subprocess.run([str(CLI), *args, "--quiet"], capture_output=True, text=True)
    assert done.returncode != 0
    return done.stderr.strip().removeprefix("error: ")


@pytest.mark.parametrize("path", RECORDINGS, ids=lambda p: p.name)
def test_read_gives_every_event_time_ordered_as_info_counts_them(path: Path) -> None:
    events = ctcal.read(path)
    assert events.dtype == ctcal.EVENT_DTYPE
    assert events.dtype.names == ("t", "x", "y", "p")
    info = cli("info", str(path))
    assert len(events) == info["events"]
    assert int(events["p"].sum()) == info["on_events"]
    assert np.all(np.diff(events["t"]) >= 0)
    assert events["t"][0] == info["t_first_us"] and events["t"][-1] == info["t_last_us"]
    assert events["x"].max() < info["width"] and events["y"].max() < info["height"]


def test_read_counts_equal_the_truth_of_the_shared_recordings() -> None:
    truth = json.loads((REAL / "truth.json").read_text())
    checked = 0
    for name, t in truth.items():
        path = REAL / name
        if not path.exists() or "events" not in t:
            continue
        events = ctcal.read(path)
        assert len(events) == t["events"], name
        if "on_fraction" in t:
            assert abs(events["p"].mean() - t["on_fraction"]) < 1e-5, name
        if "t_first_s" in t:
            assert abs(events["t"][0] * 1e-6 - t["t_first_s"]) < 1e-6, name
        checked += 1
    assert checked >= 3


def test_read_takes_a_time_window() -> None:
    path = REAL / "ijrr_slider_depth_50k"
    every = ctcal.read(path)
    part = ctcal.read(path, start=0.05, end=0.1)
    first = every["t"][0]
    inside = every[(every["t"] >= first + 50_000) & (every["t"] <= first + 100_000)]
    assert np.array_equal(part, inside)


def test_read_frames_gives_the_frames_info_counts() -> None:
    path = REAL / "ijrr_slider_depth_50k"
    times, frames = ctcal.read_frames(path)
    info = cli("info", str(path))
    assert frames.shape == (info["frames"], info["height"], info["width"])
    assert frames.dtype == np.uint8 and times.dtype == np.int64
    assert np.all(np.diff(times) > 0)


@pytest.mark.parametrize("path", RECORDINGS, ids=lambda p: p.name)
def test_info_and_stats_equal_the_command(path: Path) -> None:
    assert ctcal.info(path) == cli("info", str(path))
    assert ctcal.stats(path) == cli("stats", str(path))


def test_stats_of_a_window_equal_the_command() -> None:
    path = REAL / "davis346_faery.aedat4"
    got = ctcal.stats(path, start=0.5, end=1.5, window_s=0.05)
    assert got == cli("stats", str(path), "--start", "0.5", "--end", "1.5", "--window", "0.05")


def test_stats_of_one_instant_leave_rates_undetermined_with_reasons() -> None:
    path = REAL / "ijrr_slider_depth_50k"
    got = ctcal.stats(path, start=0.0, end=0.0)
    assert got["events"] == 1 and got["duration_s"] == 0.0
    for key in ("events_per_pixel_per_second", "background_rate_hz", "median_pixel_rate_hz"):
        assert got[key] is None, key
        assert "no time" in got["why"][key], key
    # slider_depth's five frames lie outside this instant
    assert got["frames"] == {"count": 0, "median_interval_s": None}


def test_stats_of_events_in_memory_count_what_was_read() -> None:
    path = REAL / "evk4_faery_evt3.raw"
    events = ctcal.read(path)
    info = ctcal.info(path)
    got = ctcal.stats(events, sensor=f"{info['width']}x{info['height']}")
    want = ctcal.stats(path)
    for key in ("events", "on_events", "duration_s", "active_pixel_fraction", "hot_pixels"):
        assert got[key] == want[key], key


@pytest.mark.parametrize("method", ["aps", "eppps"])
def test_estimate_equals_the_command(method: str) -> None:
    path = REAL / "ijrr_slider_depth_50k"
    assert ctcal.estimate(path, method) == cli("estimate", method, str(path))


def test_estimate_aps_on_a_region_equals_the_command() -> None:
    # an event budget under the 44,920 events between its frames: a region of about 30,000
    # (at 20,000 the region's flow follows too few frame intervals and aps refuses it, as
    # the command does)
    path = REAL / "ijrr_slider_depth_50k"
    sparse = ctcal.estimate(path, "aps", max_events=30000)
    assert sparse == cli("estimate", "aps", str(path), "--max-events", "30000")
    notes = [a for a in sparse["assumptions"] if a.startswith("measured by `estimate aps` on the region")]
    assert len(notes) == 1 and "44920 events are more than the 30000" in notes[0]


def test_fit_equals_the_command() -> None:
    path = REAL / "ijrr_slider_depth_50k"
    assert ctcal.fit(path) == cli("fit", str(path))
    # a pixel limit under the DAVIS240C's 43,200 pixels: fitted on a region, as the command
    small = ctcal.fit(path, max_pixels=20000)
    assert small == cli("fit", str(path), "--max-pixels", "20000")
    assert any(a.startswith("fitted on the region") for a in small["assumptions"])
    # an event budget under the 44,920 events between its frames: a region of about 20,000
    sparse = ctcal.fit(path, max_events=20000)
    assert sparse == cli("fit", str(path), "--max-events", "20000")
    assert any("44920 events are more than the 20000" in a for a in sparse["assumptions"])


def test_errors_carry_the_commands_message() -> None:
    missing = REAL / "no_such_recording.aedat4"
    with pytest.raises(ctcal.CtcalError) as raised:
        ctcal.info(missing)
    assert isinstance(raised.value, ValueError)
    assert str(raised.value) == cli_error("info", str(missing))
    frameless = REAL / "evk4_faery_evt3.raw"
    with pytest.raises(ctcal.CtcalError, match="needs grey frames"):
        ctcal.estimate(frameless, "aps")
    # a region without events is named as the cause, as the command names it
    slider = REAL / "ijrr_slider_depth_50k"
    with pytest.raises(ctcal.CtcalError, match="no event lies in the selected pixels") as empty:
        ctcal.estimate(slider, "eppps", roi="0,0,1,1")
    assert str(empty.value) == cli_error("estimate", "eppps", str(slider), "--roi", "0,0,1,1")


def test_simulate_is_deterministic_and_follows_the_frames() -> None:
    h, w = 16, 24
    ramp = np.linspace(20, 230, 40)
    frames = np.stack([np.full((h, w), v, dtype=np.uint8) for v in ramp])
    frames[:, :, : w // 2] = 60  # half the sensor static
    times = np.arange(len(frames), dtype=np.int64) * 10_000
    params = {"ct_on": 0.2, "ct_off": 0.2, "seed": 7}
    first = ctcal.simulate(frames, times, params)
    again = ctcal.simulate(frames, times, params)
    assert first.dtype == ctcal.EVENT_DTYPE
    assert np.array_equal(first, again)
    assert len(first) > 0
    # brightening only: ON events, on the moving half, inside the frames' span
    assert np.all(first["p"] == 1)
    assert np.all(first["x"] >= w // 2)
    assert first["t"].min() >= times[0] and first["t"].max() <= times[-1]
    # about ln(230/20) / 0.2 events per changing pixel
    per_pixel = len(first) / (h * w / 2)
    assert abs(per_pixel - np.log(230 / 20) / 0.2) < 2
    # the same model as TOML text
    toml = "ct_on = 0.2\nct_off = 0.2\nseed = 7\n"
    assert np.array_equal(ctcal.simulate(frames, times, toml), first)


@pytest.fixture(scope="module")
def two_recordings() -> list:
    return [REAL / "ijrr_slider_depth_50k", REAL / "ijrr_shapes_rotation_chunk"]


def comparable(results: dict) -> dict:
    """The results without what differs between two runs of one report: how it was asked
    for, how long each stage took, and the paths as given."""
    results = json.loads(json.dumps(results))
    results.pop("command_line")
    for s in results["sequences"]:
        s.pop("seconds")
        for f in s["inputs"]:
            f.pop("path")
    for f in results["failed"]:
        f.pop("path")
    return results


def files_of(folder: Path) -> dict:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name not in ("results.json", "index.html", "report.md", ".ctcal-output.json")
    }


@pytest.fixture(scope="module")
def cli_report(tmp_path_factory: pytest.TempPathFactory, two_recordings: list) -> Path:
    out = tmp_path_factory.mktemp("cli") / "report"
    subprocess.run(
        [str(CLI), "report", *map(str, two_recordings), "--out", str(out), "--quiet"], check=True
    )
    return out


def test_a_local_cluster_report_equals_the_command(
    tmp_path: Path, two_recordings: list, cli_report: Path
) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        out = tmp_path / "report"
        got = ctcal.report(two_recordings, out, client=client)
    want = json.loads((cli_report / "results.json").read_text())
    assert comparable(got) == comparable(want)
    assert comparable(json.loads((out / "results.json").read_text())) == comparable(want)
    assert files_of(out) == files_of(cli_report)


def test_worker_processes_report_as_the_command(
    tmp_path: Path, two_recordings: list, cli_report: Path
) -> None:
    """Tasks in other processes: the sequences travel as their JSON and files (pickled),
    as they would from other machines."""
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        got = ctcal.report(two_recordings, tmp_path / "report", client=client)
    assert comparable(got) == comparable(json.loads((cli_report / "results.json").read_text()))
    assert files_of(tmp_path / "report") == files_of(cli_report)


def test_a_report_on_this_machine_equals_the_command(
    tmp_path: Path, two_recordings: list, cli_report: Path
) -> None:
    out = tmp_path / "report"
    got = ctcal.report(two_recordings, out)
    assert comparable(got) == comparable(json.loads((cli_report / "results.json").read_text()))
    assert files_of(out) == files_of(cli_report)


def test_config_of_a_report_equals_the_command(cli_report: Path) -> None:
    for fmt in ("v2e", "esim", "ctcal"):
        done = subprocess.run(
            [str(CLI), "config", str(cli_report), "--format", fmt],
            capture_output=True,
            text=True,
            check=True,
        )
        assert ctcal.config(cli_report, fmt) == done.stdout
    fitted = next(s for s in json.loads((cli_report / "results.json").read_text())["sequences"] if "fit" in s)
    assert "--pos_thres" in ctcal.config(fitted["fit"], "v2e")


def test_report_refuses_unknown_options(tmp_path: Path, two_recordings: list) -> None:
    with pytest.raises(ctcal.CtcalError, match="unknown report option"):
        ctcal.report(two_recordings, tmp_path / "r", max_frame=3)
