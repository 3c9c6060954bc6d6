#!/usr/bin/env python3
"""Where a multi-threaded run leaves the pool's other threads idle (issue 19).

Reads `perf script -F tid,time,ip,sym` output of a run recorded with call graphs (see
serial_share.sh). A sample is busy unless its innermost frames are rayon's or the kernel's
waiting (sleep, steal, yield, schedule). A busy sample is serial when no other thread has
a busy sample within HALF seconds of it (half the sampling period: each sample stands for
one period of its thread). Prints the busy and serial sample counts per thread and the
serial samples grouped by their innermost three ctcal frames: the code that runs while the
other threads wait.

usage: serial_share.py PERF_SCRIPT_TEXT [HALF_SECONDS (default 0.0013, for 400 Hz)]
"""
import bisect
import collections
import re
import sys

IDLE = re.compile(
    r"wait_until|find_work|steal|rayon_core::sleep|Sleep::|futex|sched_yield|no_work|"
    r"syscall|schedule|finish_task_switch|spin_unlock"
)


def samples(path):
    """(tid, time, [frames, innermost first]) per sample."""
    out, current = [], None
    for line in open(path):
        line = line.rstrip("\n")
        if not line.strip():
            if current:
                out.append(current)
            current = None
            continue
        head = re.match(r"\s*(\d+)\s+([\d.]+):", line)
        if head and not line.startswith("\t"):
            current = (int(head.group(1)), float(head.group(2)), [])
        elif current is not None:
            parts = line.strip().split(None, 1)
            current[2].append(parts[1] if len(parts) > 1 else "?")
    if current:
        out.append(current)
    return out


def chain(stack, depth=3):
    frames = [re.sub(r"::h[0-9a-f]{16}", "", f) for f in stack if "ctcal" in f]
    frames = [re.sub(r"<[^<>]*>", "", f)[:70] for f in frames]
    return " <- ".join(frames[:depth]) or "(outside ctcal: libc, kernel)"


def main():
    half = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0013
    busy = [s for s in samples(sys.argv[1]) if not any(IDLE.search(f) for f in s[2][:8])]
    times = collections.defaultdict(list)
    for tid, t, _ in busy:
        times[tid].append(t)
    for ts in times.values():
        ts.sort()

    def others_busy(tid, t):
        for other, ts in times.items():
            if other != tid:
                i = bisect.bisect_left(ts, t - half)
                if i < len(ts) and ts[i] <= t + half:
                    return True
        return False

    serial = [s for s in busy if not others_busy(s[0], s[1])]
    print(f"busy samples {len(busy)}, serial {len(serial)} "
          f"({100 * len(serial) / max(len(busy), 1):.1f} %)")
    print("per thread:", {tid: len(ts) for tid, ts in times.items()})
    for key, count in collections.Counter(chain(s[2]) for s in serial).most_common(30):
        print(f"{count:6d} {key}")


if __name__ == "__main__":
    main()
