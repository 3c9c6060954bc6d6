#!/usr/bin/env python3
"""A straightforward NumPy equivalent of `ctcal stats` (the same definitions), to time ctcal
against and to cross-check its numbers. Reads IJRR text (numpy.loadtxt), event_utils HDF5
(h5py) and Prophesee EVT3 (vectorised NumPy decoding).

usage: stats_numpy.py INPUT [--width W --height H]   (prints JSON)
"""
import argparse
import json
import os
import sys

import numpy as np


def read_text(path):
    if os.path.isdir(path):
        path = os.path.join(path, "events.txt")
    with open(path) as f:
        first = f.readline().split()
    skip = 1 if len(first) == 2 else 0
    data = np.loadtxt(path, skiprows=skip, comments="#")
    t = np.rint(data[:, 0] * 1e6).astype(np.int64)
    size = (int(first[0]), int(first[1])) if skip else None
    return t, data[:, 1].astype(np.int64), data[:, 2].astype(np.int64), data[:, 3] > 0, size


def read_h5(path):
    import h5py

    with h5py.File(path, "r") as f:
        t = np.rint(f["events/ts"][:] * 1e6).astype(np.int64)
        x = f["events/xs"][:].astype(np.int64)
        y = f["events/ys"][:].astype(np.int64)
        p = f["events/ps"][:].astype(bool)
        h, w = f.attrs["sensor_resolution"]
    return t, x, y, p, (int(w), int(h))


def forward_fill_index(mask):
    idx = np.where(mask, np.arange(mask.size), -1)
    np.maximum.accumulate(idx, out=idx)
    return idx


def read_evt3(path):
    with open(path, "rb") as f:
        head = f.read(65536)
    offset, size = 0, None
    while head[offset:offset + 1] == b"%":
        end = head.index(b"\n", offset)
        line = head[offset + 1:end].decode(errors="replace").strip()
        offset = end + 1
        if line.startswith("geometry"):
            w, h = line.split()[1].split("x")
            size = (int(w), int(h))
        if line == "end":
            break
    words = np.fromfile(path, dtype="<u2", offset=offset).astype(np.int64)
    kind = words >> 12
    payload = words & 0xFFF
    # time: the high word (unwrapped when it jumps back by more than half its range), the
    # low word since the last high word (0 if none)
    high_idx = forward_fill_index(kind == 8)
    low_idx = forward_fill_index(kind == 6)
    highs = payload[kind == 8]
    loops = np.concatenate([[0], np.cumsum(np.diff(highs) < -2048)])
    high_value = np.zeros(words.size, dtype=np.int64)
    high_value[kind == 8] = highs + (loops << 12)
    high = np.where(high_idx >= 0, high_value[np.maximum(high_idx, 0)], -1)
    low = np.where(low_idx > high_idx, payload[np.maximum(low_idx, 0)], 0)
    t_all = (high << 12) + low
    y_idx = forward_fill_index(kind == 0)
    y_all = np.where(y_idx >= 0, words[np.maximum(y_idx, 0)] & 0x7FF, 0)
    # single events
    single = (kind == 2) & (high_idx >= 0)
    xs = [words[single] & 0x7FF]
    ys = [y_all[single]]
    ts = [t_all[single]]
    ps = [(words[single] >> 11) & 1 == 1]
    order = [np.flatnonzero(single).astype(np.float64)]
    # vectors: base x and polarity from the last VECT_BASE_X, advanced 12 or 8 per vector
    vector = ((kind == 4) | (kind == 5)) & (high_idx >= 0)
    if vector.any():
        base_idx = forward_fill_index(kind == 3)
        step = np.where(kind == 4, 12, np.where(kind == 5, 8, 0))
        advance = np.cumsum(step)
        since_base = advance - step - np.where(base_idx >= 0, advance[np.maximum(base_idx, 0)], 0)
        base_x = words[np.maximum(base_idx, 0)] & 0x7FF
        base_p = (words[np.maximum(base_idx, 0)] >> 11) & 1
        vi = np.flatnonzero(vector)
        bits = (words[vi, None] >> np.arange(12)) & 1
        bits[kind[vi] == 5, 8:] = 0
        r, c = np.nonzero(bits)
        xs.append(base_x[vi][r] + since_base[vi][r] + c)
        ys.append(y_all[vi][r])
        ts.append(t_all[vi][r])
        ps.append(base_p[vi][r] == 1)
        order.append(vi[r] + c / 16.0)
    o = np.argsort(np.concatenate(order), kind="stable")
    cat = lambda parts: np.concatenate(parts)[o]
    return cat(ts), cat(xs), cat(ys), cat(ps), size


def stats(t, x, y, p, width, height, window_s=0.01):
    n = t.size
    duration = (t[-1] - t[0]) / 1e6
    pixels = width * height
    pix = y * width + x
    counts = np.bincount(pix, minlength=pixels)
    order = np.argsort(pix, kind="stable")
    ps, ts = pix[order], t[order]
    same = ps[1:] == ps[:-1]
    dt = (ts[1:] - ts[:-1])[same]
    windows = max(1, int(round((t[-1] - t[0]) / (window_s * 1e6))))
    bins = np.minimum((t - t[0]) // int(round(window_s * 1e6)), windows - 1)
    timeline = np.bincount(bins, minlength=windows)
    grid = counts.reshape(height, width).astype(np.float64)
    padded = np.pad(grid, 1)
    neighbour_max = np.max(
        [padded[1 + dy:1 + dy + height, 1 + dx:1 + dx + width] for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx],
        axis=0,
    )
    residual = grid - neighbour_max
    active = grid > 0
    mad = np.median(np.abs(residual[active])) if active.any() else 0.0
    z = residual / np.maximum(1.4826 * mad, np.sqrt(neighbour_max + 1))
    hot = (z > 10) & (grid >= 10)
    on = int(p.sum())
    return {
        "width": width,
        "height": height,
        "events": int(n),
        "on_events": on,
        "t_first_us": int(t[0]),
        "t_last_us": int(t[-1]),
        "duration_s": duration,
        "events_per_pixel_per_second": n / (pixels * duration),
        "active_pixel_fraction": float(active.mean()),
        "rate_timeline_windows": int(timeline.size),
        "hot_pixels": int(hot.sum()),
        "background_rate_hz": float(np.median(grid[~hot]) / duration),
        "inter_event_interval_s": {
            "p5": float(np.percentile(dt, 5) / 1e6) if dt.size else None,
            "median": float(np.percentile(dt, 50) / 1e6) if dt.size else None,
            "count": int(dt.size),
        },
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("input")
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    args = parser.parse_args()
    path = args.input
    if path.endswith(".h5"):
        t, x, y, p, size = read_h5(path)
    elif path.endswith(".raw"):
        t, x, y, p, size = read_evt3(path)
    else:
        t, x, y, p, size = read_text(path)
    if args.width:
        size = (args.width, args.height)
    if size is None:
        size = (int(x.max()) + 1, int(y.max()) + 1)
    json.dump(stats(t, x, y, p, *size), sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
